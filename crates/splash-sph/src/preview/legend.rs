//! The colour scale drawn into a preview coloured by an attribute: a vertical viridis bar at
//! the right edge with its maximum above and minimum below, in a built-in 3×5 pixel font.

use super::colormap::viridis_srgb;
use super::png_file::Image;

/// 3×5 glyphs, one row of 3 bits a line, most significant bit leftmost.
fn glyph(c: char) -> Option<[u8; 5]> {
    Some(match c {
        '0' => [7, 5, 5, 5, 7],
        '1' => [2, 6, 2, 2, 7],
        '2' => [7, 1, 7, 4, 7],
        '3' => [7, 1, 7, 1, 7],
        '4' => [5, 5, 7, 1, 1],
        '5' => [7, 4, 7, 1, 7],
        '6' => [7, 4, 7, 5, 7],
        '7' => [7, 1, 1, 2, 2],
        '8' => [7, 5, 7, 5, 7],
        '9' => [7, 5, 7, 1, 7],
        '.' => [0, 0, 0, 0, 2],
        '-' => [0, 0, 7, 0, 0],
        '+' => [0, 2, 7, 2, 0],
        'e' => [0, 7, 7, 4, 7],
        _ => return None,
    })
}

/// A value with three significant digits: fixed from 0.01 to 9999, else `1.23e-5`.
pub fn label(v: f32) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if (1e-2..1e4).contains(&a) {
        let decimals = (2 - a.log10().floor() as i32).clamp(0, 4) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.2e}")
    }
}

/// The rectangle (x, y, width, height) of the bar in a `width`×`height` image, or None when the
/// image is too small to hold a legend.
pub fn bar_rect(width: u32, height: u32) -> Option<(u32, u32, u32, u32)> {
    if width < 96 || height < 64 {
        return None;
    }
    let scale = (height / 180).max(1);
    let (bw, bh) = (6 * scale, height / 2);
    let text = 7 * scale;
    Some((
        width - 4 * scale - bw,
        (height - bh) / 2 + text / 2,
        bw,
        bh - text,
    ))
}

fn text(image: &mut Image, s: &str, right: u32, top: u32, scale: u32, colour: [u8; 3]) {
    let glyphs: Vec<[u8; 5]> = s.chars().filter_map(glyph).collect();
    let advance = 4 * scale;
    let width = glyphs.len() as u32 * advance;
    let left = right.saturating_sub(width);
    for (i, g) in glyphs.iter().enumerate() {
        for (row, bits) in g.iter().enumerate() {
            for col in 0..3u32 {
                if bits >> (2 - col) & 1 == 0 {
                    continue;
                }
                for dy in 0..scale {
                    for dx in 0..scale {
                        let x = left + i as u32 * advance + col * scale + dx;
                        let y = top + row as u32 * scale + dy;
                        set(image, x, y, colour);
                    }
                }
            }
        }
    }
}

fn set(image: &mut Image, x: u32, y: u32, c: [u8; 3]) {
    if x < image.width && y < image.height {
        let i = 3 * (y as usize * image.width as usize + x as usize);
        image.rgb[i..i + 3].copy_from_slice(&c);
    }
}

/// Draws the bar (minimum at the bottom) and the labels of `min` and `max` into `image`,
/// right-aligned to the bar; nothing when the image is too small.
pub fn draw(image: &mut Image, min: f32, max: f32) {
    let Some((x0, y0, bw, bh)) = bar_rect(image.width, image.height) else {
        return;
    };
    let scale = (image.height / 180).max(1);
    let ink = [40, 40, 48];
    for y in 0..bh {
        let c = viridis_srgb(1.0 - y as f32 / (bh - 1).max(1) as f32);
        for x in 0..bw {
            set(image, x0 + x, y0 + y, c);
        }
    }
    let right = x0 + bw;
    text(image, &label(max), right, y0 - 7 * scale, scale, ink);
    text(image, &label(min), right, y0 + bh + 2 * scale, scale, ink);
}
