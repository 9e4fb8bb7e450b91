//! Blinn–Phong shading in linear RGB, stored as sRGB: a key light from the camera's side (above
//! and left of the viewer) with a hard shadow, a dimmer fill from the right and a sky ambient,
//! the fill and ambient scaled by ambient occlusion where it is traced.

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
    /// Rays per pixel (`[preview] samples`).
    pub samples: u32,
    /// Ambient-occlusion rays per pixel, 0 for none (`[preview] ao`).
    pub ao: u32,
    /// Whether an image coloured by an attribute gets its colour scale.
    pub legend: bool,
}

impl Default for Style {
    fn default() -> Self {
        Style {
            background: [236, 238, 242],
            colour: [58, 123, 213],
            shadows: true,
            samples: 1,
            ao: 0,
            legend: true,
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

const AMBIENT: f32 = 0.16;
const KEY: f32 = 0.78;
const FILL: f32 = 0.28;
const SPECULAR: f32 = 0.3;
const SHININESS: i32 = 64;

/// The directions towards the lights of a camera, and its up direction (the sky's).
#[derive(Debug, Clone, Copy)]
pub struct Lights {
    /// Key light: from the viewer's side, above and to the left, so that the faces turned
    /// to the camera are lit and the relief shades (not a silhouette lit from behind).
    pub key: Vec3,
    /// Fill light: low on the right, no shadow, lifting the key's shadowed side.
    pub fill: Vec3,
    /// The image's up direction: the ambient is brighter on faces turned up.
    pub up: Vec3,
}

impl Lights {
    /// The lights of a camera with viewing direction `forward` and image axes `right`, `up`.
    pub fn new(forward: Vec3, right: Vec3, up: Vec3) -> Lights {
        Lights {
            key: (-0.55 * right + 0.6 * up - 0.75 * forward).normalize(),
            fill: (0.8 * right + 0.1 * up - 0.6 * forward).normalize(),
            up,
        }
    }
}

/// Linear RGB of a surface point with unit `normal` seen along unit `view` (from the eye),
/// lit by `lights` (the key unless `shadowed`), its fill and ambient scaled by `open` (1 where
/// nothing occludes the hemisphere).
pub fn shade(
    normal: Vec3,
    view: Vec3,
    lights: &Lights,
    shadowed: bool,
    open: f32,
    colour: Vec3,
) -> Vec3 {
    // Seen from behind (a camera inside the fluid looks at the surface's inner side).
    let n = if normal.dot(view) > 0.0 {
        -normal
    } else {
        normal
    };
    let sky = 0.7 + 0.3 * n.dot(lights.up);
    let mut c = (AMBIENT * sky + FILL * n.dot(lights.fill).max(0.0)) * open * colour;
    let diffuse = n.dot(lights.key);
    if !shadowed && diffuse > 0.0 {
        let half = (lights.key - view).normalize_or_zero();
        let specular = n.dot(half).max(0.0).powi(SHININESS);
        c += KEY * diffuse * colour + Vec3::splat(SPECULAR * specular);
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
