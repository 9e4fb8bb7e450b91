//! The serial scatter engine of Akinci et al. 2012 Sec. 4.1 and Tables 3–4: each particle adds
//! its contribution to every grid vertex within the support, into per-vertex kernel sums over the
//! full grid; the field value of every vertex follows from its sums, and every cell is
//! triangulated by the same code as the other engines.
//!
//! Only the SSP07 field scatters so far: its value is a function of per-vertex sums
//! ([`Sums`]), which a particle can add to one at a time.

use crate::error::{Error, Result};
use glam::{IVec3, Vec3};

use super::Reconstruction;
use super::band::{BRICK, BRICK_VERTICES, Band, local_index};
use super::field_sampling::BrickValues;
use super::full_grid::{self, Grid};
use super::handler_array::HandlerArray;
use super::normals::set_normals;
use super::prepared::finish;
use super::triangulation::triangulate;
use crate::config::Params;
use crate::field::FieldConfig;
use crate::field::ssp07::{Ssp07, Sums};
use crate::report::{Stage, Stages};

/// The scatter engine's reconstruction: the scatter needs no neighbour search, only the
/// normals do.
pub fn reconstruct(
    particles: &[Vec3],
    params: &Params,
    grid: &Grid,
    mut stages: Stages<'_>,
) -> Result<Reconstruction> {
    // Only SSP07's value is a function of sums a particle can add to, so far.
    let FieldConfig::Ssp07(ssp07) = &params.field else {
        bail_config!(
            "the scatter engine supports the ssp07 field only, not {}: use the narrow-band or full-gather engine",
            params.field.kind()
        );
    };
    let field = ssp07.resolve(params.spacing);
    let band = stages.run(Stage::Band, || full_grid::band(particles, params))?;
    let values = stages.run(Stage::ScalarField, || {
        scatter_field(particles, &band, grid, &field)
    })?;
    // The field's normals gather the particles around each vertex, like the other engines:
    // only they need a handler array.
    let triangulation = stages.run(Stage::Triangulation, || -> Result<_> {
        let mut t = triangulate(&band, &values);
        let handlers = || HandlerArray::new(particles, field.support / 2.0);
        set_normals(
            params.normals,
            &mut t.mesh,
            &t.brick_vertices,
            band.cell,
            handlers,
            &field,
        )?;
        Ok(t)
    })?;
    Ok(finish(stages.stats, &band, &values, 0, triangulation))
}

/// Field values on every vertex of `band` (the full band of `grid`), by scattering.
pub fn scatter_field(
    particles: &[Vec3],
    band: &Band,
    grid: &Grid,
    field: &Ssp07,
) -> Result<BrickValues> {
    let cell = band.cell;
    let [nx, ny, nz] = grid.resolution();
    let n = usize::try_from(nx * ny * nz).map_err(|_| {
        Error::limit(format!(
            "{nx} × {ny} × {nz} grid vertices do not fit in memory"
        ))
    })?;
    let mut sums: Vec<Sums> = Vec::new();
    if sums.try_reserve_exact(n).is_err() {
        bail_limit!("cannot allocate the kernel sums of {n} grid vertices");
    }
    sums.resize(n, Sums::default());
    // World coordinates of the grid planes, computed as `vertex_position` does.
    let axis = |a: usize, len: u64| -> Vec<f32> {
        (0..len as i32)
            .map(|i| (f64::from(grid.lo[a] + i) * f64::from(cell)) as f32)
            .collect()
    };
    let (xs, ys, zs) = (axis(0, nx), axis(1, ny), axis(2, nz));
    let support = field.support;
    let r2 = support * support;
    let inv_r2 = 1.0 / r2;
    let (nx, ny) = (nx as usize, ny as usize);
    // Indices of the planes within `s` of `c` on axis `a`, empty when none.
    let range = |a: usize, c: f32, s: f32, len: usize| -> std::ops::Range<usize> {
        let lo = (f64::from(c - s) / f64::from(cell)).ceil() as i64 - i64::from(grid.lo[a]);
        let hi = (f64::from(c + s) / f64::from(cell)).floor() as i64 - i64::from(grid.lo[a]);
        let lo = lo.clamp(0, len as i64) as usize;
        let end = (hi + 1).clamp(0, len as i64) as usize;
        lo..end.max(lo)
    };
    for &p in particles {
        let (zr, yr) = (
            range(2, p.z, support, nz as usize),
            range(1, p.y, support, ny),
        );
        for k in zr {
            let dz = p.z - zs[k];
            for j in yr.clone() {
                let dy = p.y - ys[j];
                let rest = r2 - dy * dy - dz * dz;
                if rest < 0.0 {
                    continue;
                }
                let row = (k * ny + j) * nx;
                for i in range(0, p.x, rest.sqrt(), nx) {
                    sums[row + i].add(Vec3::new(p.x - xs[i], dy, dz), inv_r2);
                }
            }
        }
    }
    let mut values: BrickValues = Vec::new();
    if values.try_reserve_exact(band.bricks.len()).is_err() {
        bail_limit!(
            "cannot allocate the field values of {} bricks",
            band.bricks.len()
        );
    }
    for (&brick, mask) in band.bricks.iter().zip(&band.masks) {
        let mut v = [f32::NAN; BRICK_VERTICES];
        let base = brick * BRICK;
        for z in 0..BRICK {
            for y in 0..BRICK {
                for x in 0..BRICK {
                    let l = IVec3::new(x, y, z);
                    let i = local_index(l);
                    if mask[z as usize] >> (i % 64) & 1 == 0 {
                        continue;
                    }
                    let g = (base + l - grid.lo).as_uvec3();
                    let at = (g.z as usize * ny + g.y as usize) * nx + g.x as usize;
                    v[i] = field.value_of_sums(&sums[at]);
                }
            }
        }
        values.push(v);
    }
    Ok(values)
}
