//! Surface particles (Sec. 4): the smoothed colour field of Müller et al. 2003 flags the
//! particles of the main body's surface; particles with few neighbours (splashes, whose colour
//! field gradient vanishes by symmetry) are flagged as well.

use std::f32::consts::PI;

use glam::Vec3;

use crate::config::Params;
use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::lane_sums::{Lanes, lanes_path};
use crate::neighbours::neighbourhood::{LANES, Neighbourhood, map_particles};

pub struct SurfaceCriteria {
    /// Colour field support h; also the neighbour count radius.
    pub support: f32,
    /// Particle volume m/ρ, r³ for particles at spacing r.
    pub volume: f32,
    /// Threshold on the dimensionless |∇c|·h.
    pub colour_threshold: f32,
    pub min_neighbours: u32,
}

impl SurfaceCriteria {
    pub fn of(params: &Params) -> SurfaceCriteria {
        SurfaceCriteria {
            support: params.colour_support,
            volume: params.spacing.powi(3),
            colour_threshold: params.colour_threshold,
            min_neighbours: params.min_neighbours,
        }
    }
}

/// Positions of the surface particles, in handler order.
pub fn surface_particles(handlers: &HandlerArray, criteria: &SurfaceCriteria) -> Vec<Vec3> {
    let h = criteria.support;
    // |∇c|·h for the poly6 kernel W = 315/(64π h⁹)(h² − d²)³ written with q = d/h:
    // ∇c = −V·945/(32π h⁴) Σ (1 − q²)² (x_i − x_j)/h.
    let scale = criteria.volume * 945.0 / (32.0 * PI * h.powi(3));
    let inv_h2 = 1.0 / (h * h);
    let flags = map_particles(handlers, h, |near, x| {
        let (gradient, neighbours) = colour_gradient(near, x, inv_h2);
        // Neighbours at the particle's own position (itself, duplicates) are not counted: a
        // point mass of 30 coincident particles has a zero gradient by symmetry and would
        // otherwise count as inside, leaving no surface particle and an empty mesh.
        neighbours < criteria.min_neighbours as f32
            || gradient.length() * scale > criteria.colour_threshold
    });
    handlers
        .positions
        .iter()
        .zip(&flags)
        .filter_map(|(&p, &s)| s.then_some(p))
        .collect()
}

/// Returns Σ (1 − q²)² (x − x_j)/h and the number of particles with 0 < q < 1 (particles at
/// `x` itself are left out), summed in `LANES` lanes. Inlined into the per-particle closure.
#[inline(always)]
fn colour_gradient(near: &Neighbourhood, x: Vec3, inv_h2: f32) -> (Vec3, f32) {
    // The kernel sums' choice of path (and the tests' pin on it).
    match lanes_path() {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the CPU has AVX2 (AVX-512 implies it), as `lanes_path` checked.
        Lanes::Avx2 | Lanes::Avx512 => unsafe { lanes_avx2(near, x, inv_h2) },
        Lanes::Scalar => lanes(near, x, inv_h2),
    }
}

/// The lanes' sums in lane order, as both paths add them.
fn total(g: &[[f32; LANES]; 3], count: &[f32; LANES], inv_h: f32) -> (Vec3, f32) {
    let sum = |a: &[f32; LANES]| a.iter().sum::<f32>();
    (
        Vec3::new(sum(&g[0]), sum(&g[1]), sum(&g[2])) * inv_h,
        sum(count),
    )
}

#[inline(always)]
fn lanes(near: &Neighbourhood, x: Vec3, inv_h2: f32) -> (Vec3, f32) {
    let mut g = [[0.0f32; LANES]; 3];
    let mut count = [0.0f32; LANES];
    for ((cx, cy), cz) in near
        .x
        .chunks_exact(LANES)
        .zip(near.y.chunks_exact(LANES))
        .zip(near.z.chunks_exact(LANES))
    {
        for l in 0..LANES {
            let (dx, dy, dz) = (x.x - cx[l], x.y - cy[l], x.z - cz[l]);
            let q2 = (dx * dx + dy * dy + dz * dz) * inv_h2;
            let t = (1.0 - q2).max(0.0);
            let w = t * t;
            g[0][l] += w * dx;
            g[1][l] += w * dy;
            g[2][l] += w * dz;
            count[l] += if q2 < 1.0 && q2 > 0.0 { 1.0 } else { 0.0 };
        }
    }
    total(&g, &count, inv_h2.sqrt())
}

/// [`lanes`] written out in AVX2: the compiler kept its accumulators as single floats and
/// rebuilt the vectors every step (a third of the colour field's time). The same IEEE
/// operations in every lane: max(1 − q², 0) is 0 for NaN as `f32::max` is, and 1 − q² is never
/// −0.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn lanes_avx2(near: &Neighbourhood, x: Vec3, inv_h2: f32) -> (Vec3, f32) {
    use std::arch::x86_64::*;
    let n = near.len() / LANES * LANES;
    let (xs, ys, zs) = (&near.x[..n], &near.y[..n], &near.z[..n]);
    let at = x.to_array().map(|v| _mm256_set1_ps(v));
    let (inv, one, zero) = (
        _mm256_set1_ps(inv_h2),
        _mm256_set1_ps(1.0),
        _mm256_setzero_ps(),
    );
    let (mut g, mut count) = ([zero; 3], zero);
    for i in (0..n).step_by(LANES) {
        // SAFETY: i + 8 ≤ n, the length of all three slices.
        let load = |v: &[f32]| unsafe { _mm256_loadu_ps(v.as_ptr().add(i)) };
        let d = [
            _mm256_sub_ps(at[0], load(xs)),
            _mm256_sub_ps(at[1], load(ys)),
            _mm256_sub_ps(at[2], load(zs)),
        ];
        let sq = d.map(|d| _mm256_mul_ps(d, d));
        let q2 = _mm256_mul_ps(_mm256_add_ps(_mm256_add_ps(sq[0], sq[1]), sq[2]), inv);
        let t = _mm256_max_ps(_mm256_sub_ps(one, q2), zero);
        let w = _mm256_mul_ps(t, t);
        for k in 0..3 {
            g[k] = _mm256_add_ps(g[k], _mm256_mul_ps(w, d[k]));
        }
        let inside = _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_LT_OQ>(q2, one),
            _mm256_cmp_ps::<_CMP_GT_OQ>(q2, zero),
        );
        count = _mm256_add_ps(count, _mm256_and_ps(inside, one));
    }
    let lanes = |v: __m256| {
        let mut out = [0.0f32; LANES];
        // SAFETY: `out` holds 8 floats.
        unsafe { _mm256_storeu_ps(out.as_mut_ptr(), v) };
        out
    };
    total(&g.map(lanes), &lanes(count), inv_h2.sqrt())
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::colour_gradient;
    use crate::neighbours::lane_sums::Lanes;
    use crate::neighbours::lane_sums::tests::FORCED;
    use crate::neighbours::neighbourhood::Neighbourhood;

    #[test]
    fn colour_lanes_are_the_same_on_every_path() {
        let mut next = crate::tests::common::uniform(11);
        let mut points: Vec<Vec3> = (0..203)
            .map(|_| crate::tests::common::uniform_point(&mut next) * 2.0 - 1.0)
            .collect();
        // A particle at the point itself and one at the support's edge.
        points.extend([Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0)]);
        let mut near = Neighbourhood::default();
        near.set(Vec3::ZERO, &points);
        for x in [Vec3::ZERO, Vec3::new(0.3, -0.2, 0.1), Vec3::splat(0.9)] {
            let run = |scalar: bool| {
                FORCED.set(scalar.then_some(Lanes::Scalar));
                let (g, n) = colour_gradient(&near, x, 1.0);
                FORCED.set(None);
                (g.to_array().map(f32::to_bits), n.to_bits())
            };
            let (simd, scalar) = (run(false), run(true));
            assert_eq!(simd, scalar, "at {x}");
            assert!(scalar.0.iter().all(|&b| f32::from_bits(b).is_finite()));
            assert!(f32::from_bits(scalar.1) > 10.0, "neighbours counted");
        }
    }
}
