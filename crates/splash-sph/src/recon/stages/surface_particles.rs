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
use crate::neighbours::neighbourhood::map_particles;

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
    let scale = criteria.gradient_scale();
    let flags = map_particles(handlers, criteria.support, |near, x| {
        let [gx, gy, gz, neighbours] = colour_sums(near, x, inv_h2);
        criteria.on_surface(scale, colour_gradient([gx, gy, gz], inv_h2), neighbours)
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
    let scale = criteria.gradient_scale();
    let (flags, volumes): (Vec<bool>, Vec<f32>) = map_particles(handlers, h, |near, x| {
        let [gx, gy, gz, neighbours, splines] = colour_and_splines(near, x, (inv_h2, inv_h));
        (
            criteria.on_surface(scale, colour_gradient([gx, gy, gz], inv_h2), neighbours),
            particle_volume(splines, h),
        )
    })
    .into_iter()
    .unzip();
    (positions_flagged(handlers, &flags), volumes)
}

impl SurfaceCriteria {
    /// |∇c|·h per unit of the gradient sum (see [`colour_gradient`]) for the poly6 kernel
    /// W = 315/(64π h⁹)(h² − d²)³ written with q = d/h:
    /// ∇c = −V·945/(32π h⁴) Σ (1 − q²)² (x_i − x_j)/h.
    fn gradient_scale(&self) -> f32 {
        self.volume * 945.0 / (32.0 * PI * self.support.powi(3))
    }

    /// Whether a particle with this colour gradient sum and count of neighbours is on the
    /// surface; `scale` is [`gradient_scale`](Self::gradient_scale).
    fn on_surface(&self, scale: f32, gradient: Vec3, neighbours: f32) -> bool {
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
    /// The colour field's sums ([`colour`]) and the number of particles with 0 < q < 1
    /// (particles at `x` itself are left out).
    vector fn colour_sums(inv_h2: f32) -> [4] |dx, dy, dz| {
        colour(dx, dy, dz, inv_h2)
    }
}

lane_sums! {
    /// [`colour_sums`], then the density field's Σ W(d_j) of `spline_sum`, from the same
    /// squared distances.
    vector fn colour_and_splines(inv: (f32, f32)) -> [5] |dx, dy, dz| {
        let [gx, gy, gz, count] = colour(dx, dy, dz, inv.0);
        [gx, gy, gz, count, spline(dx, dy, dz, inv.1)]
    }
}

/// (1 − q²)² d_j with d_j = x_j − x, and whether 0 < q < 1.
#[inline(always)]
fn colour<L: Lane>(dx: L, dy: L, dz: L, inv_h2: f32) -> [L; 4] {
    let q2 = (dx * dx + dy * dy + dz * dz) * L::splat(inv_h2);
    let t = (L::splat(1.0) - q2).max(L::splat(0.0));
    let w = t * t;
    [w * dx, w * dy, w * dz, q2.between(0.0, 1.0)]
}

/// Σ (1 − q²)² (x − x_j)/h from the sums over x_j − x: those negated, exactly.
fn colour_gradient(sums: [f32; 3], inv_h2: f32) -> Vec3 {
    -Vec3::from_array(sums) * inv_h2.sqrt()
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::{colour_gradient, colour_sums};
    use crate::neighbours::lane_sums::tests::on_every_path;
    use crate::neighbours::neighbourhood::Neighbourhood;

    #[test]
    fn one_pass_gives_the_two_passes_surface_and_volumes_bit_for_bit() {
        use super::{SurfaceCriteria, surface_particles, surface_particles_and_volumes};
        use crate::field::density::particle_volumes;
        use crate::neighbours::handler_array::HandlerArray;
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
            let runs = on_every_path(|| colour_sums(&near, x, 1.0).map(f32::to_bits));
            for (path, sums) in &runs {
                assert_eq!(sums, &runs[0].1, "{path:?} at {x}");
            }
            let sums = runs[0].1.map(f32::from_bits);
            assert!(sums.iter().all(|s| s.is_finite()));
            assert!(sums[3] > 10.0, "neighbours counted");
            // Against the sums written out, one particle at a time (x − x_j, as the colour
            // field has it), in the lanes' order.
            let mut lanes = [[0.0f32; 4]; 8];
            for (j, p) in points.iter().enumerate() {
                let d = x - *p;
                let q2 = d.length_squared();
                let w = (1.0 - q2).max(0.0).powi(2);
                let lane = &mut lanes[j % 8];
                for (k, v) in (w * d).to_array().into_iter().enumerate() {
                    lane[k] += v;
                }
                lane[3] += f32::from(u8::from(q2 > 0.0 && q2 < 1.0));
            }
            let total = |k: usize| lanes.iter().map(|l| l[k]).sum::<f32>();
            let gradient = colour_gradient([sums[0], sums[1], sums[2]], 1.0);
            assert_eq!(gradient, Vec3::new(total(0), total(1), total(2)), "at {x}");
            assert_eq!(sums[3], total(3));
        }
    }
}
