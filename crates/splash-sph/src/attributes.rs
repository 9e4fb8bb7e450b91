//! Particle quantities carried onto mesh vertices, for renderers: a velocity per vertex lets
//! them blur by motion.
//!
//! A vertex gets the average of the particle velocities within the field's support R, weighted
//! by the kernel of the SSP07 field, k(s) = max(0, (1 − s²)³) with s = |x − x_j| / R (eq. 5 of
//! Solenthaler et al. 2007): the weights that place the surface there.

use crate::error::Result;
use glam::Vec3;
use rayon::prelude::*;

use crate::neighbours::handler_array::HandlerArray;

/// Velocities of `vertices`, interpolated from the particles' with support `support`. A vertex
/// with no particle within the support (which the field's surface never has) gets zero.
pub fn interpolate_velocities(
    vertices: &[Vec3],
    particles: &[Vec3],
    velocities: &[Vec3],
    support: f32,
) -> Result<Vec<Vec3>> {
    if particles.len() != velocities.len() {
        bail_input!(
            "{} particles but {} velocities",
            particles.len(),
            velocities.len()
        );
    }
    if particles.is_empty() || support.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Ok(vec![Vec3::ZERO; vertices.len()]);
    }
    // Velocities ride along the handler array's sort as three channels.
    let channels = (0..3)
        .map(|a| velocities.iter().map(|v| v[a]).collect())
        .collect();
    let handlers = HandlerArray::with_channels(particles, support, channels)?;
    let inv_r2 = 1.0 / (support * support);
    Ok(vertices
        .par_iter()
        .map(|&x| {
            let (mut sum, mut weight) = (Vec3::ZERO, 0.0f32);
            let c = handlers.cell_of(x);
            handlers.for_each_in_cells(c - 1, c + 1, |range| {
                for i in range {
                    let p = handlers.positions[i];
                    let t = (1.0 - (p - x).length_squared() * inv_r2).max(0.0);
                    let k = t * t * t;
                    let v = Vec3::new(
                        handlers.channels[0][i],
                        handlers.channels[1][i],
                        handlers.channels[2][i],
                    );
                    sum += k * v;
                    weight += k;
                }
            });
            if weight > 0.0 {
                sum / weight
            } else {
                Vec3::ZERO
            }
        })
        .collect())
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
        for v in interpolate_velocities(&vertices, &particles, &uniform, 0.4).unwrap() {
            assert!((v - uniform[0]).length() < 1e-5, "{v}");
        }
        // A symmetric kernel reproduces a linear field away from the boundary.
        let linear: Vec<Vec3> = particles
            .iter()
            .map(|p| Vec3::new(p.y, 2.0, -p.x))
            .collect();
        for (x, v) in vertices
            .iter()
            .zip(interpolate_velocities(&vertices, &particles, &linear, 0.25).unwrap())
        {
            let lattice_centre_bias = 0.02;
            assert!(
                (v - Vec3::new(x.y, 2.0, -x.x)).length() < lattice_centre_bias,
                "{x}: {v}"
            );
        }
        let far = interpolate_velocities(&[Vec3::splat(9.0)], &particles, &uniform, 0.4).unwrap();
        assert_eq!(far, [Vec3::ZERO]);
    }
}
