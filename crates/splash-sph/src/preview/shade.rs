//! Phong shading with one directional light and a hard shadow, in linear RGB, stored as sRGB.

use glam::Vec3;

/// Colours of a preview, as sRGB bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Style {
    /// Where rays miss the fluid.
    pub background: [u8; 3],
    /// The fluid's diffuse colour.
    pub colour: [u8; 3],
    /// Whether shadow rays are traced.
    pub shadows: bool,
}

impl Default for Style {
    fn default() -> Self {
        Style {
            background: [236, 238, 242],
            colour: [58, 123, 213],
            shadows: true,
        }
    }
}

/// Parses a colour as `#rrggbb`, `rrggbb` or `R,G,B` (0–255 each).
pub fn parse_colour(text: &str) -> crate::Result<[u8; 3]> {
    let t = text.trim();
    let bad = || {
        crate::Error::config(format!(
            "colour '{text}': expected #rrggbb (e.g. #3a7bd5) or R,G,B from 0 to 255"
        ))
    };
    if t.contains(',') {
        let parts: Vec<u8> = t
            .split(',')
            .map(|p| p.trim().parse::<u8>().map_err(|_| bad()))
            .collect::<crate::Result<_>>()?;
        return <[u8; 3]>::try_from(parts).map_err(|_| bad());
    }
    let hex = t.strip_prefix('#').unwrap_or(t);
    if hex.len() != 6 || !hex.is_ascii() {
        return Err(bad());
    }
    let byte = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).map_err(|_| bad());
    Ok([byte(0)?, byte(2)?, byte(4)?])
}

const AMBIENT: f32 = 0.18;
const DIFFUSE: f32 = 0.8;
const SPECULAR: f32 = 0.35;
const SHININESS: i32 = 48;

/// The light's direction (towards it) for a camera with viewing direction `forward` and image
/// axes `right`, `up`: above, to the left and behind the camera.
pub fn light_direction(forward: Vec3, right: Vec3, up: Vec3) -> Vec3 {
    (-0.45 * right + 0.85 * up - 0.6 * forward).normalize()
}

/// Linear RGB of a surface point with unit `normal` seen along unit `view` (from the eye),
/// lit from `light` unless `shadowed`.
pub fn phong(normal: Vec3, view: Vec3, light: Vec3, shadowed: bool, colour: Vec3) -> Vec3 {
    // Seen from behind (a camera inside the fluid looks at the surface's inner side).
    let n = if normal.dot(view) > 0.0 {
        -normal
    } else {
        normal
    };
    let mut c = AMBIENT * colour;
    if !shadowed {
        let diffuse = n.dot(light).max(0.0);
        let reflected = light - 2.0 * light.dot(n) * n;
        let specular = if diffuse > 0.0 {
            reflected.dot(view).max(0.0).powi(SHININESS)
        } else {
            0.0
        };
        c += DIFFUSE * diffuse * colour + Vec3::splat(SPECULAR * specular);
    }
    c
}

/// sRGB byte → linear.
pub fn to_linear(c: [u8; 3]) -> Vec3 {
    let f = |b: u8| {
        let x = b as f32 / 255.0;
        if x <= 0.04045 {
            x / 12.92
        } else {
            ((x + 0.055) / 1.055).powf(2.4)
        }
    };
    Vec3::new(f(c[0]), f(c[1]), f(c[2]))
}

/// Linear → sRGB byte, clamped.
pub fn to_srgb(c: Vec3) -> [u8; 3] {
    let f = |x: f32| {
        let x = x.clamp(0.0, 1.0);
        let s = if x <= 0.003_130_8 {
            12.92 * x
        } else {
            1.055 * x.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0 + 0.5) as u8
    };
    [f(c.x), f(c.y), f(c.z)]
}
