//! Each field's own kernel as a weight of distance alone, for carrying particle attributes onto
//! the mesh (issue 11): the same shape and support the field sums, so an attribute at a vertex
//! comes from the particles that make the surface there.

use crate::neighbours::lane::Lane;

/// A radial kernel w(d²) ≥ 0, zero from [`support`](Self::support) on. Constant factors are
/// left out: they cancel in the Shepard normalisation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum RadialKernel {
    /// (1 − d²/R²)³ of SSP07 eq. 5 (and ZB05's).
    Poly6 { support: f32 },
    /// The cubic spline of support h (the density field's; the anisotropic field's interior
    /// kernel, Σ̃ ≈ I, G ≈ I/h).
    CubicSpline { support: f32 },
    /// Blinn's bump exp(B(1 − d²/R²)) lowered to 0 at its cut-off (d²/R² = `cutoff_s2`).
    Blobby {
        radius: f32,
        blobbiness: f32,
        cutoff_s2: f32,
    },
    /// (1 − d²/R_c²)^α of the metaballs.
    Metaball { cutoff: f32, exponent: i32 },
}

impl RadialKernel {
    /// Particles at least this far away weigh nothing.
    pub(crate) fn support(&self) -> f32 {
        match *self {
            RadialKernel::Poly6 { support } | RadialKernel::CubicSpline { support } => support,
            RadialKernel::Blobby {
                radius, cutoff_s2, ..
            } => radius * cutoff_s2.sqrt(),
            RadialKernel::Metaball { cutoff, .. } => cutoff,
        }
    }

    /// The weight at squared distance `d2`, in one lane or eight (one branch that every call
    /// of a frame takes alike; the Gaussian and the metaballs' power lane by lane).
    #[inline(always)]
    pub(crate) fn weight<L: Lane>(&self, d2: L) -> L {
        match *self {
            RadialKernel::Poly6 { support } => {
                let t = (L::splat(1.0) - d2 / L::splat(support * support)).max(L::splat(0.0));
                t * t * t
            }
            RadialKernel::CubicSpline { support } => {
                super::cubic_spline::cubic_spline(d2.sqrt() / L::splat(support))
            }
            RadialKernel::Blobby {
                radius,
                blobbiness,
                cutoff_s2,
            } => d2.map(|d2| {
                let s2 = (d2 / (radius * radius)).min(cutoff_s2);
                (blobbiness * (1.0 - s2)).exp() - (blobbiness * (1.0 - cutoff_s2)).exp()
            }),
            RadialKernel::Metaball { cutoff, exponent } => {
                d2.map(|d2| (1.0 - d2 / (cutoff * cutoff)).max(0.0).powi(exponent))
            }
        }
    }
}
