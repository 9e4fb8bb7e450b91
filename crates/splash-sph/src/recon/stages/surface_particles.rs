//! Surface particles (Sec. 4): the smoothed colour field of Müller et al. 2003 flags the
//! particles of the main body's surface; particles with few neighbours (splashes, whose colour
//! field gradient vanishes by symmetry) are flagged as well.

use std::f32::consts::PI;

use glam::Vec3;

use crate::config::Params;
use crate::field::density::{particle_volume, spline};
use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::lane::Lane;
use crate::neighbours::lane_sums::lane_sums;
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
    let inv_h2 = 1.0 / (criteria.support * criteria.support);
    let flags = map_particles(handlers, criteria.support, |near, x| {
        let (gradient, neighbours) = colour_gradient(near, x, inv_h2);
        criteria.on_surface(gradient, neighbours)
    });
    positions_flagged(handlers, &flags)
}

/// [`surface_particles`] and the density field's particle volumes (of support
/// `criteria.support`, as `field::density::particle_volumes` gives them, bit for bit) from one
/// pass over the particles' neighbourhoods: one gather, and one loop for both sums.
pub fn surface_particles_and_volumes(
    handlers: &HandlerArray,
    criteria: &SurfaceCriteria,
) -> (Vec<Vec3>, Vec<f32>) {
    let h = criteria.support;
    let (inv_h2, inv_h) = (1.0 / (h * h), 1.0 / h);
    let (flags, volumes): (Vec<bool>, Vec<f32>) = map_particles(handlers, h, |near, x| {
        let [gx, gy, gz, neighbours, splines] = colour_and_splines(near, x, (inv_h2, inv_h));
        // The sums of x_j − x: the colour field's of x − x_j negated, exactly.
        let gradient = -Vec3::new(gx, gy, gz) * inv_h2.sqrt();
        (
            criteria.on_surface(gradient, neighbours),
            particle_volume(splines, h),
        )
    })
    .into_iter()
    .unzip();
    (positions_flagged(handlers, &flags), volumes)
}

impl SurfaceCriteria {
    /// Whether a particle with this colour gradient sum (see [`colour_gradient`]) and count
    /// of neighbours is on the surface.
    fn on_surface(&self, gradient: Vec3, neighbours: f32) -> bool {
        let h = self.support;
        // |∇c|·h for the poly6 kernel W = 315/(64π h⁹)(h² − d²)³ written with q = d/h:
        // ∇c = −V·945/(32π h⁴) Σ (1 − q²)² (x_i − x_j)/h.
        let scale = self.volume * 945.0 / (32.0 * PI * h.powi(3));
        // Neighbours at the particle's own position (itself, duplicates) are not counted: a
        // point mass of 30 coincident particles has a zero gradient by symmetry and would
        // otherwise count as inside, leaving no surface particle and an empty mesh.
        neighbours < self.min_neighbours as f32 || gradient.length() * scale > self.colour_threshold
    }
}

fn positions_flagged(handlers: &HandlerArray, flags: &[bool]) -> Vec<Vec3> {
    handlers
        .positions
        .iter()
        .zip(flags)
        .filter_map(|(&p, &s)| s.then_some(p))
        .collect()
}

lane_sums! {
    /// [`colour_gradient`]'s sums with d_j = x_j − x (the same terms negated) and its count,
    /// then the density field's Σ W(d_j) of `spline_sum`, from the same squared distances.
    vector fn colour_and_splines(inv: (f32, f32)) -> [5] |dx, dy, dz| {
        colour_and_spline(dx, dy, dz, inv)
    }
}

#[inline(always)]
fn colour_and_spline<L: Lane>(dx: L, dy: L, dz: L, (inv_h2, inv_h): (f32, f32)) -> [L; 5] {
    let q2 = (dx * dx + dy * dy + dz * dz) * L::splat(inv_h2);
    let t = (L::splat(1.0) - q2).max(L::splat(0.0));
    let w = t * t;
    [
        w * dx,
        w * dy,
        w * dz,
        q2.between(0.0, 1.0),
        spline(dx, dy, dz, inv_h),
    ]
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
    fn one_pass_gives_the_two_passes_surface_and_volumes_bit_for_bit() {
        use super::{SurfaceCriteria, surface_particles, surface_particles_and_volumes};
        use crate::field::density::particle_volumes;
        use crate::neighbours::handler_array::HandlerArray;
        use crate::neighbours::lane_sums::tests::on_every_path;
        // A ball of fluid at spacing 1, jittered, splashes, and a particle twice over.
        let mut next = crate::tests::common::uniform(23);
        let mut ps = crate::tests::common::lattice_ball(Vec3::ZERO, 8.0, 1.0);
        for p in &mut ps {
            *p += (crate::tests::common::uniform_point(&mut next) - 0.5) * 0.2;
        }
        ps.extend((0..40).map(|_| crate::tests::common::uniform_point(&mut next) * 30.0 - 15.0));
        ps.push(ps[0]);
        let h = 2.0;
        let handlers = HandlerArray::new(&ps, h).unwrap();
        let criteria = SurfaceCriteria {
            support: h,
            volume: 1.0,
            colour_threshold: 0.4,
            min_neighbours: 25,
        };
        let bits = |v: &[Vec3]| v.iter().map(|p| p.to_array().map(f32::to_bits)).collect();
        let runs = on_every_path(|| {
            let two: (Vec<[u32; 3]>, Vec<u32>) = (
                bits(&surface_particles(&handlers, &criteria)),
                particle_volumes(&handlers, h)
                    .iter()
                    .map(|v| v.to_bits())
                    .collect(),
            );
            let (surface, volumes) = surface_particles_and_volumes(&handlers, &criteria);
            let one = (
                bits(&surface),
                volumes.iter().map(|v| v.to_bits()).collect(),
            );
            (one, two)
        });
        let (some, all) = (runs[0].1.1.0.len(), ps.len());
        assert!(
            some > 100 && some < all - 100,
            "{some} of {all} on the surface"
        );
        for (path, (one, two)) in &runs {
            assert_eq!(one, two, "{path:?}");
            assert_eq!(one, &runs[0].1.0, "{path:?} against the scalar path");
        }
    }

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
