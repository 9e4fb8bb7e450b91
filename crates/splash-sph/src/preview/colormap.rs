//! Viridis (van der Walt & Smith 2015, matplotlib's perceptually uniform map, lightness rising
//! monotonically from dark purple to yellow) as the 6th-degree polynomial fit of Matt Zucconi
//! (Shadertoy "WlfXRN", CC0, 2019), within about 4/255 of the tabulated map per channel.

use glam::Vec3;

/// Coefficients c0..c6 of sRGB(t) = Σ c_k t^k, t in [0, 1].
const VIRIDIS: [[f32; 3]; 7] = [
    [0.277_727_33, 0.005_407_344_5, 0.334_099_8],
    [0.105_093_04, 1.404_613_5, 1.384_590_2],
    [-0.330_861_83, 0.214_847_56, 0.095_095_16],
    [-4.634_230_6, -5.799_101, -19.332_441],
    [6.228_27, 14.179_933, 56.690_55],
    [4.776_385, -13.745_145, -65.353_035],
    [-5.435_456, 4.645_852_6, 26.312_435],
];

/// Viridis at `t` (clamped to [0, 1]) as sRGB components in [0, 1].
pub fn viridis(t: f32) -> Vec3 {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let c = |k: usize| Vec3::from_array(VIRIDIS[k]);
    let v = c(0) + t * (c(1) + t * (c(2) + t * (c(3) + t * (c(4) + t * (c(5) + t * c(6))))));
    v.clamp(Vec3::ZERO, Vec3::ONE)
}

/// Viridis at `t` as sRGB bytes.
pub fn viridis_srgb(t: f32) -> [u8; 3] {
    let v = viridis(t) * 255.0 + 0.5;
    [v.x as u8, v.y as u8, v.z as u8]
}

/// CIE L* (0–100) of sRGB components in [0, 1]: the lightness a perceptual map keeps monotone
/// (the tests' check of the map).
#[cfg(test)]
pub fn lightness(srgb: Vec3) -> f32 {
    let lin = |c: f32| {
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let y = 0.2126 * lin(srgb.x) + 0.7152 * lin(srgb.y) + 0.0722 * lin(srgb.z);
    if y > 216.0 / 24389.0 {
        116.0 * y.cbrt() - 16.0
    } else {
        y * 24389.0 / 27.0
    }
}
