//! The serial scatter engine of Akinci et al. 2012 Sec. 4.1 and Tables 3–4: each particle adds
//! its contribution to every grid vertex within the support, into per-vertex kernel sums over the
//! full grid; the field value of every vertex follows from its sums, and every cell is
//! triangulated by the same code as the other engines.
//!
//! A field scatters when its value is a function of per-vertex sums that a particle can add to
//! one at a time ([`Scattering`]; SSP07 so far).

use crate::error::{Error, Result};
use glam::{IVec3, Vec3};

use super::full_grid::{self, Grid};
use super::prepared::Reconstruction;
use super::prepared::{finish, triangles_and_normals};
use crate::config::Params;
use crate::field::Scattering;
use crate::neighbours::handler_array::HandlerArray;
use crate::recon::bricks::band::{BRICK, BRICK_VERTICES, Band, local_index};
use crate::recon::bricks::brick_signs::Signs;
use crate::recon::bricks::brick_values::BrickValues;
use crate::recon::bricks::edge_tables::EdgeTables;
use crate::recon::budget;
use crate::recon::stages::triangulation::triangulate;
use crate::report::{Stage, Stages};

/// The scatter engine's reconstruction: the scatter needs no neighbour search, only the
/// normals do.
pub fn reconstruct(
    particles: &[Vec3],
    params: &Params,
    grid: &Grid,
    mut stages: Stages<'_>,
) -> Result<Reconstruction> {
    let field = params.field.as_ref();
    let scattering = params.scattering()?;
    let band = stages.run(Stage::Band, || full_grid::band(particles, params))?;
    let values = stages.run(Stage::ScalarField, || {
        scatter_field(particles, &band, grid, field.support(), scattering)
    })?;
    // The field's normals gather the particles around each vertex, like the other engines:
    // only they need a handler array.
    let triangulation = triangles_and_normals(
        &mut stages,
        params,
        field,
        || {
            let signs = Signs::of(&band, &values);
            let tables = EdgeTables::of(&band, &signs);
            triangulate(&band, &values, signs, tables, |mesh| {
                let held = (band.heap_bytes() + values.heap_bytes()) as u64;
                budget::check(params, held.saturating_add(mesh), || {
                    "the mesh of the full grid's surface".into()
                })
                .map(drop)
            })
        },
        || HandlerArray::new(particles, field.support() / 2.0),
    )?;
    Ok(finish(stages.stats, &band, &values, 0, triangulation))
}

/// Field values on every vertex of `band` (the full band of `grid`), by scattering each
/// particle into the vertices within `support`.
pub fn scatter_field(
    particles: &[Vec3],
    band: &Band,
    grid: &Grid,
    support: f32,
    field: &dyn Scattering,
) -> Result<BrickValues> {
    let cell = band.cell;
    let [nx, ny, nz] = grid.resolution();
    let n = usize::try_from(nx * ny * nz).map_err(|_| {
        Error::limit(format!(
            "{nx} × {ny} × {nz} grid vertices do not fit in memory"
        ))
    })?;
    let stride = field.sums_per_vertex();
    let mut sums: Vec<f32> = Vec::new();
    if n.checked_mul(stride)
        .is_none_or(|len| sums.try_reserve_exact(len).is_err())
    {
        bail_limit!("cannot allocate the kernel sums of {n} grid vertices");
    }
    sums.resize(n * stride, 0.0);
    // World coordinates of the grid planes, computed as `vertex_position` does.
    let axis = |a: usize, len: u64| -> Vec<f32> {
        (0..len as i32)
            .map(|i| (f64::from(grid.lo[a] + i) * f64::from(cell)) as f32)
            .collect()
    };
    let (xs, ys, zs) = (axis(0, nx), axis(1, ny), axis(2, nz));
    let r2 = support * support;
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
                let xr = range(0, p.x, rest.sqrt(), nx);
                let vertices = &mut sums[(row + xr.start) * stride..(row + xr.end) * stride];
                field.add_to_row(vertices, p, &xs[xr], ys[j], zs[k]);
            }
        }
    }
    BrickValues::sample(
        band,
        || (),
        |_, b| {
            let (brick, mask) = (band.bricks[b], &band.masks[b]);
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
                        v[i] = field.value_of_sums(&sums[at * stride..(at + 1) * stride]);
                    }
                }
            }
            v
        },
    )
}
