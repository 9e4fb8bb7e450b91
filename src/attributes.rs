//! Particle quantities carried onto mesh vertices, for renderers: a velocity per vertex lets
//! them blur by motion.
//!
//! A vertex gets the average of the particle velocities within the field's support R, weighted
//! by the kernel of the SSP07 field, k(s) = max(0, (1 − s²)³) with s = |x − x_j| / R (eq. 5 of
//! Solenthaler et al. 2007): the weights that place the surface there.

use glam::{IVec3, Vec3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

/// Velocities of `vertices`, interpolated from the particles' with support `support`. A vertex
/// with no particle within the support (which the field's surface never has) gets zero.
pub fn interpolate_velocities(
    vertices: &[Vec3],
    particles: &[Vec3],
    velocities: &[Vec3],
    support: f32,
) -> Vec<Vec3> {
    assert_eq!(
        particles.len(),
        velocities.len(),
        "one velocity per particle"
    );
    if particles.is_empty() || support.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return vec![Vec3::ZERO; vertices.len()];
    }
    let grid = Grid::new(particles, velocities, support);
    let inv_r2 = 1.0 / (support * support);
    vertices
        .par_iter()
        .map(|&x| {
            let (mut sum, mut weight) = (Vec3::ZERO, 0.0f32);
            let c = grid.cell_of(x);
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let (ps, vs) = grid.cell(c + IVec3::new(dx, dy, dz));
                        for (&p, &v) in ps.iter().zip(vs) {
                            let t = (1.0 - (p - x).length_squared() * inv_r2).max(0.0);
                            let k = t * t * t;
                            sum += k * v;
                            weight += k;
                        }
                    }
                }
            }
            if weight > 0.0 {
                sum / weight
            } else {
                Vec3::ZERO
            }
        })
        .collect()
}

/// Particles bucketed by cells of the support's size, so that a point's neighbours lie in the
/// 27 cells around it; positions and velocities sorted alike.
struct Grid {
    cell_size: f32,
    positions: Vec<Vec3>,
    velocities: Vec<Vec3>,
    cells: FxHashMap<IVec3, (u32, u32)>,
}

impl Grid {
    fn new(particles: &[Vec3], velocities: &[Vec3], cell_size: f32) -> Grid {
        let cell_of = |p: Vec3| (p / cell_size).floor().as_ivec3();
        let mut order: Vec<(IVec3, u32)> = particles
            .par_iter()
            .enumerate()
            .map(|(i, &p)| (cell_of(p), i as u32))
            .collect();
        order.par_sort_unstable_by_key(|&(c, i)| (c.z, c.y, c.x, i));
        let positions = order
            .par_iter()
            .map(|&(_, i)| particles[i as usize])
            .collect();
        let sorted = order
            .par_iter()
            .map(|&(_, i)| velocities[i as usize])
            .collect();
        let mut cells = FxHashMap::default();
        let mut start = 0;
        for end in 1..=order.len() {
            if end == order.len() || order[end].0 != order[start].0 {
                cells.insert(order[start].0, (start as u32, end as u32));
                start = end;
            }
        }
        Grid {
            cell_size,
            positions,
            velocities: sorted,
            cells,
        }
    }

    fn cell_of(&self, p: Vec3) -> IVec3 {
        (p / self.cell_size).floor().as_ivec3()
    }

    fn cell(&self, c: IVec3) -> (&[Vec3], &[Vec3]) {
        match self.cells.get(&c) {
            Some(&(s, e)) => {
                let range = s as usize..e as usize;
                (&self.positions[range.clone()], &self.velocities[range])
            }
            None => (&[], &[]),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_uniform_or_linear_velocity_is_reproduced() {
        let mut particles = Vec::new();
        for z in 0..12 {
            for y in 0..12 {
                for x in 0..12 {
                    particles.push(Vec3::new(x as f32, y as f32, z as f32) * 0.1);
                }
            }
        }
        let vertices = [Vec3::splat(0.55), Vec3::new(0.3, 0.62, 0.48)];
        let uniform = vec![Vec3::new(1.0, -2.0, 0.5); particles.len()];
        for v in interpolate_velocities(&vertices, &particles, &uniform, 0.4) {
            assert!((v - uniform[0]).length() < 1e-5, "{v}");
        }
        // A symmetric kernel reproduces a linear field away from the boundary.
        let linear: Vec<Vec3> = particles
            .iter()
            .map(|p| Vec3::new(p.y, 2.0, -p.x))
            .collect();
        for (x, v) in vertices
            .iter()
            .zip(interpolate_velocities(&vertices, &particles, &linear, 0.25))
        {
            let lattice_centre_bias = 0.02;
            assert!(
                (v - Vec3::new(x.y, 2.0, -x.x)).length() < lattice_centre_bias,
                "{x}: {v}"
            );
        }
        let far = interpolate_velocities(&[Vec3::splat(9.0)], &particles, &uniform, 0.4);
        assert_eq!(far, [Vec3::ZERO]);
    }
}
