//! Lone particles: surface particles with no other particle near enough to shape the field
//! anywhere around their band (a droplet of one particle, as spray is). Their surface is the
//! isosurface of one particle's kernel, a sphere whose radius the field gives, so their band
//! shrinks from the box of half-width w (Sec. 4.1) to that sphere's box plus one cell, or two
//! when grid normals take differences: the same crossed cells, with every corner and neighbour
//! they read, from a fraction of the vertices (729 → 343 per droplet at cell r/2).
//!
//! Exact, not a heuristic: every vertex the box loses lies more than a cell outside the sphere,
//! where only the lone particle reaches, so no cell with such a corner is crossed.

use glam::Vec3;
use rayon::prelude::*;

use crate::config::{Normals, Params};
use crate::error::Result;
use crate::field::ScalarField;
use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::neighbourhood::Neighbourhood;

/// Steps per cell of the scan for a lone particle's surface.
const STEPS_PER_CELL: f32 = 64.0;

/// The band's half-width around each of the `surface` particles: `params.band_half_width`, or
/// for a lone particle its sphere's box. `handlers` hold all of the frame's particles.
pub fn band_half_widths<F: ScalarField + ?Sized>(
    surface: &[Vec3],
    handlers: &HandlerArray,
    field: &F,
    params: &Params,
) -> Result<Vec<f32>> {
    let w = params.band_half_width;
    #[cfg(test)]
    if tests::OFF.get() {
        return Ok(vec![w; surface.len()]);
    }
    let margin = if params.normals == Normals::Grid {
        2.0
    } else {
        1.0
    };
    let narrowed = match lone_radius(field, params.cell)? {
        Some(radius) => radius + margin * params.cell,
        None => w,
    };
    // Unless the box loses a layer of vertices, narrowing it gains nothing.
    if (narrowed / params.cell).floor() >= (w / params.cell).floor() {
        return Ok(vec![w; surface.len()]);
    }
    // Another particle changes the field only within the support, and the box's vertices
    // (and the cells they are corners of) lie within w + cell of its particle on each axis.
    let apart = (field.support() + w + params.cell) * 1.01;
    Ok(surface
        .par_iter()
        .map(|&p| {
            let alone = !handlers.more_near_than(p - apart, p + apart, 1);
            if alone { narrowed } else { w }
        })
        .collect())
}

/// The distance from a particle alone in its support at which the field last is negative,
/// widened by a scan step and 1 % for rounding in other directions; 0 where it is never
/// negative. `None` for fields whose particles differ in reach (the anisotropic field), or
/// whose lone particle is inside at the edge of its support (no closed surface to bound).
fn lone_radius<F: ScalarField + ?Sized>(field: &F, cell: f32) -> Result<Option<f32>> {
    if field.reach_channel().is_some() {
        return Ok(None);
    }
    let support = field.support();
    let one = HandlerArray::new(&[Vec3::ZERO], support)?;
    let channels = field.particle_channels(&one);
    let mut near = Neighbourhood::default();
    near.pick(
        Vec3::ZERO,
        [(0, true)].into_iter(),
        &one.positions,
        &channels,
    );
    let step = cell / STEPS_PER_CELL;
    let steps = (support / step).ceil() as u32;
    let inside = |k: u32| field.value(&near, Vec3::new(k as f32 * step, 0.0, 0.0)) < 0.0;
    if inside(steps) {
        return Ok(None);
    }
    let last = (0..steps).rev().find(|&k| inside(k));
    Ok(Some(last.map_or(0.0, |k| (k + 1) as f32 * step * 1.01)))
}

#[cfg(test)]
pub(crate) mod tests {
    use std::cell::Cell;

    use glam::Vec3;

    use crate::Engine;
    use crate::config::Normals;
    use crate::tests::common::{lattice_ball, reconstruct};

    thread_local!(pub static OFF: Cell<bool> = const { Cell::new(false) });

    #[test]
    fn lone_droplets_keep_their_mesh_from_fewer_band_vertices() {
        let r = 0.01;
        let mut ps = lattice_ball(Vec3::ZERO, 5.0 * r, r);
        // Lone droplets on a spiral around the ball, a pair 1.5r apart (not lone), one 4r
        // from the ball's surface (not lone either).
        ps.extend((0..40).map(|i| {
            let a = i as f32 * 2.399;
            Vec3::new(a.cos(), a.sin(), i as f32 / 20.0 - 1.0) * (12.0 + i as f32 * 0.7) * r
        }));
        ps.extend([
            Vec3::new(0.0, 0.0, 40.0 * r),
            Vec3::new(1.5 * r, 0.0, 40.0 * r),
        ]);
        ps.push(Vec3::new(9.0 * r, 0.0, 0.0));
        for (kind, cell, normals) in [
            ("density", "r/2", Normals::Field),
            ("density", "r/2", Normals::Grid),
            ("density", "r", Normals::Field),
            ("blobby", "r/2", Normals::Grid),
            ("metaball", "r/2", Normals::Field),
        ] {
            // Resolved with its normals, which choose the density field's band.
            let config = crate::Config {
                cell: crate::Length::parse(cell).unwrap(),
                field: crate::field::FieldConfig::named(kind).unwrap(),
                normals,
                ..crate::Config::default()
            };
            let params = crate::config::Params::resolve(&config, r);
            let run = |off: bool| {
                OFF.set(off);
                let out = reconstruct(&ps, &params, Engine::NarrowBand).unwrap();
                OFF.set(false);
                out
            };
            let (narrowed, full) = (run(false), run(true));
            let what = format!("{kind} at cell {cell}, {normals:?} normals");
            let bits = |v: &[Vec3]| {
                v.iter()
                    .map(|p| p.to_array().map(f32::to_bits))
                    .collect::<Vec<_>>()
            };
            assert!(!full.mesh.triangles.is_empty(), "{what}");
            let (a, b) = (&narrowed.mesh, &full.mesh);
            assert!(a.triangles == b.triangles, "{what}: the triangles differ");
            assert!(
                bits(&a.vertices) == bits(&b.vertices),
                "{what}: the vertices differ"
            );
            assert!(
                bits(&a.normals) == bits(&b.normals),
                "{what}: the normals differ"
            );
            assert!(
                narrowed.stats.surface_vertices * 10 < full.stats.surface_vertices * 9,
                "{what}: {} of {} band vertices",
                narrowed.stats.surface_vertices,
                full.stats.surface_vertices
            );
        }
    }
}
