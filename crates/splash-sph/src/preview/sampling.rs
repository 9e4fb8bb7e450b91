//! Deterministic sample positions: every random number is a hash of (pixel, sample, dimension),
//! so an image is the same bytes whatever the thread count and run. Pixel samples are
//! stratified (Shirley 1991, *Discrepancy as a quality measure for sample distributions*): a
//! jittered k×k grid when N = k², else N-rooks; ambient-occlusion rays are cosine-weighted.

use glam::Vec3;

/// Chris Wellons' "lowbias32" integer hash (hash-prospector, 2018).
fn mix(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

/// A number in [0, 1) fixed by pixel (`x`, `y`), sample `s` and dimension `dim`.
pub fn uniform(x: u32, y: u32, s: u32, dim: u32) -> f32 {
    let h = mix(mix(mix(mix(x) ^ y) ^ s.wrapping_mul(0x9e37_79b9)) ^ dim);
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Where sample `s` of `n` falls in pixel (`x`, `y`), in [0, 1)²; one sample is the centre.
pub fn pixel_offset(x: u32, y: u32, s: u32, n: u32) -> (f32, f32) {
    if n <= 1 {
        return (0.5, 0.5);
    }
    let (jx, jy) = (uniform(x, y, s, 0), uniform(x, y, s, 1));
    let k = (n as f64).sqrt().round() as u32;
    if k * k == n {
        return (
            ((s % k) as f32 + jx) / k as f32,
            ((s / k) as f32 + jy) / k as f32,
        );
    }
    // N-rooks: sample s in column s and in the row of a hash-ordered permutation.
    let row = rank(x, y, s, n);
    ((s as f32 + jx) / n as f32, (row as f32 + jy) / n as f32)
}

/// The position of sample `s` among the `n` samples of the pixel ordered by a hash.
fn rank(x: u32, y: u32, s: u32, n: u32) -> u32 {
    let key = |i: u32| (mix(x ^ mix(y ^ mix(i ^ 0x5bd1_e995))), i);
    let mine = key(s);
    (0..n).filter(|&i| key(i) < mine).count() as u32
}

/// A cosine-weighted direction about the unit `normal` from two numbers in [0, 1).
pub fn cosine_direction(normal: Vec3, u1: f32, u2: f32) -> Vec3 {
    let (a, b) = normal.any_orthonormal_pair();
    let r = u1.sqrt();
    let phi = std::f32::consts::TAU * u2;
    let z = (1.0 - u1).max(0.0).sqrt();
    (r * phi.cos() * a + r * phi.sin() * b + z * normal).normalize()
}
