//! Field sampling (Sec. 4.1): the field gathered per brick equals a brute-force sum over all
//! particles.

use crate::field::ScalarField;
use crate::field::ssp07::Ssp07;
use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::neighbourhood::Neighbourhood;
use crate::recon::bricks::band::{BRICK, Band, local_index};
use crate::recon::stages::field_sampling::{sample_field, vertex_position};
use crate::tests::common::lattice_ball;
use glam::{IVec3, Vec3};

#[test]
fn gathered_ssp07_matches_brute_force() {
    let r = 0.01;
    // A jittered ball with a dent, so that ∇x̄ and f vary.
    let mut seed = 7u32;
    let mut jitter = || {
        seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (seed >> 8) as f32 / (1u32 << 24) as f32 - 0.5
    };
    let ps: Vec<Vec3> = lattice_ball(Vec3::ZERO, 6.0 * r, r)
        .into_iter()
        .filter(|p| (*p - Vec3::new(6.0 * r, 0.0, 0.0)).length() > 3.0 * r)
        .map(|p| p + Vec3::new(jitter(), jitter(), jitter()) * 0.3 * r)
        .collect();
    let field = Ssp07 {
        support: 4.0 * r,
        radius: r,
        t_low: 0.4,
        t_high: 3.5,
    };
    let cell = 0.7 * r;
    let handlers = HandlerArray::new(&ps, 2.0 * r).unwrap();
    let band = Band::full(Vec3::splat(-7.0 * r), Vec3::splat(7.0 * r), cell, 4.0 * r).unwrap();
    let values = sample_field(&band, &handlers, &field).unwrap();
    let mut all = Neighbourhood::default();
    let (mut checked, mut inside, mut near_surface) = (0, 0, 0);
    for (b, brick) in band.bricks.iter().enumerate() {
        for i in (0..512).step_by(5) {
            let l = IVec3::new(i % 8, i / 8 % 8, i / 64);
            let got = values.get(&band.masks[b], b, local_index(l));
            if got.is_nan() {
                // Outside the requested box: not part of the band.
                continue;
            }
            let x = vertex_position(*brick * BRICK + l, cell);
            all.set(x, &ps);
            let expected = field.value(&all, Vec3::ZERO);
            assert!(
                (got - expected).abs() < 1e-4 * r,
                "at {x}: gathered {got}, brute force {expected}"
            );
            checked += 1;
            inside += usize::from(expected < 0.0);
            near_surface += usize::from(expected.abs() < r);
        }
    }
    assert!(
        checked > 1000 && inside > 100 && near_surface > 100,
        "{checked} {inside} {near_surface}"
    );
}

#[test]
fn gathered_anisotropic_matches_brute_force() {
    use crate::field::anisotropic::AnisotropicConfig;
    // A jittered ball with a dent and a few splash particles around it: flat kernels on the
    // surface, round ones inside and on the splashes. The fitted support must cover them all.
    let r = 0.01;
    let mut seed = 11u32;
    let mut jitter = || {
        seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (seed >> 8) as f32 / (1u32 << 24) as f32 - 0.5
    };
    let mut ps: Vec<Vec3> = lattice_ball(Vec3::ZERO, 5.0 * r, r)
        .into_iter()
        .filter(|p| (*p - Vec3::new(5.0 * r, 0.0, 0.0)).length() > 3.0 * r)
        .map(|p| p + Vec3::new(jitter(), jitter(), jitter()) * 0.3 * r)
        .collect();
    ps.extend([Vec3::new(0.0, 7.0, 0.0), Vec3::new(0.0, 7.8, 0.5)].map(|p| p * r));
    let field = AnisotropicConfig::default().resolve(r);
    let handlers = HandlerArray::new(&ps, 2.0 * r).unwrap();
    let fitted = field.fit(&handlers).unwrap().unwrap();
    let (field, handlers) = (fitted.field.as_ref(), &fitted.handlers);
    let cell = 0.7 * r;
    let band = Band::full(Vec3::splat(-9.0 * r), Vec3::splat(9.0 * r), cell, 0.0).unwrap();
    let values = sample_field(&band, handlers, field).unwrap();
    // Every particle, with its channels.
    let mut all = Neighbourhood::default();
    all.gather_box(handlers, Vec3::splat(-0.1), Vec3::splat(0.1), 0.0, None);
    assert_eq!(all.len().div_ceil(8), ps.len().div_ceil(8));
    let (mut checked, mut inside) = (0, 0);
    for (b, brick) in band.bricks.iter().enumerate() {
        for i in (0..512).step_by(7) {
            let l = IVec3::new(i % 8, i / 8 % 8, i / 64);
            let got = values.get(&band.masks[b], b, local_index(l));
            if got.is_nan() {
                continue;
            }
            let x = vertex_position(*brick * BRICK + l, cell);
            let expected = field.value(&all, x - all.anchor);
            assert!(
                (got - expected).abs() < 1e-4,
                "at {x}: gathered {got}, brute force {expected}"
            );
            checked += 1;
            inside += usize::from(expected < 0.0);
        }
    }
    assert!(checked > 1000 && inside > 100, "{checked} {inside}");
}
