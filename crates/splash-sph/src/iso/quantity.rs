//! The scalar whose isosurface is extracted, per particle (Sec. V: any attribute, or a derived
//! one): an attribute's value, a vector's magnitude, the vorticity magnitude |∇ × v| from the
//! SPH curl, or λ2 from the SPH velocity gradient; with each particle's volume m/ρ and support,
//! sorted into the interpolant.

use std::collections::BTreeMap;

use glam::{DVec3, Vec3};

use super::sph_interpolant::{Channels, Interpolant};
use crate::attribute_names;
use crate::error::Result;
use crate::field::density::particle_volumes;
use crate::io::Attribute;
use crate::neighbours::handler_array::HandlerArray;

/// What is made of the named attribute.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Derived {
    /// The attribute itself (a scalar).
    #[default]
    Value,
    /// |A| of a vector attribute.
    Magnitude,
    /// |∇ × v| of a vector attribute (velocity), by the SPH curl at each particle.
    Vorticity,
    /// λ2 of a vector attribute (velocity): the middle eigenvalue of S² + Ω² from the SPH
    /// velocity gradient at each particle; vortex cores are where λ2 < 0 (Jeong & Hussain).
    Lambda2,
}

/// The isosurface asked for: `attribute` (any spelling of the alias table), what is derived
/// from it, and the level.
#[derive(Debug, Clone, PartialEq)]
pub struct IsoRequest {
    /// Particle attribute by name (`pressure`, `density`, `velocity`, …).
    pub attribute: String,
    /// Value, magnitude, vorticity or λ2.
    pub derived: Derived,
    /// The isovalue.
    pub level: f32,
}

/// Most components of extra attributes (`--attributes`) carried onto the vertices.
pub(crate) const MAX_EXTRA_COMPONENTS: usize = 32;

/// The attribute `name` of the frame through the alias table, left in it under its canonical
/// name.
fn lookup(attributes: &mut BTreeMap<String, Attribute>, name: &str) -> Option<Attribute> {
    let a = attribute_names::take(attributes, name)?;
    attributes.insert(attribute_names::canonical(name).to_string(), a.clone());
    Some(a)
}

/// The attribute `name` of the frame, found through the alias table (and left in it), or an
/// error listing what the frame has.
fn find(attributes: &mut BTreeMap<String, Attribute>, name: &str) -> Result<Attribute> {
    match lookup(attributes, name) {
        Some(a) => Ok(a),
        None => {
            let has: Vec<&str> = attributes.keys().map(String::as_str).collect();
            bail_input!(
                "no particle attribute '{name}'; the frame has {}",
                if has.is_empty() {
                    "none".to_string()
                } else {
                    has.join(", ")
                }
            )
        }
    }
}

fn check_finite(name: &str, a: &Attribute, n: usize) -> Result<()> {
    let (len, bad) = match a {
        Attribute::Scalar(s) => (s.len(), s.iter().position(|x| !x.is_finite())),
        Attribute::Vector(v) => (v.len(), v.iter().position(|x| !x.is_finite())),
    };
    if len != n {
        bail_input!("{n} particles but {len} values of '{name}'");
    }
    if let Some(i) = bad {
        bail_input!("particle {i} has a non-finite '{name}'");
    }
    Ok(())
}

/// Pushes an attribute's components as channels; returns its width.
fn push_columns(channels: &mut Vec<Vec<f32>>, a: &Attribute) -> usize {
    match a {
        Attribute::Scalar(s) => {
            channels.push(s.clone());
            1
        }
        Attribute::Vector(v) => {
            channels.extend((0..3).map(|c| v.iter().map(|v| v[c]).collect()));
            3
        }
    }
}

/// Builds the interpolant of `request` over the frame: supports from an `h` column (2h) or
/// `support`, times `scale`; volumes m/ρ from `mass` and `density` columns when the frame has
/// both, else 1/Σ_j W_ij as the density field computes them; `extras` ride along.
pub(crate) fn interpolant(
    positions: &[Vec3],
    attributes: &mut BTreeMap<String, Attribute>,
    request: &IsoRequest,
    extras: &[String],
    support: f32,
    scale: f32,
    shepard: bool,
) -> Result<Interpolant> {
    let n = positions.len();
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        bail_input!("particle {i} has a non-finite position");
    }
    let quantity = find(attributes, &request.attribute)?;
    check_finite(&request.attribute, &quantity, n)?;
    match (&quantity, request.derived) {
        (Attribute::Vector(_), Derived::Value) => bail_input!(
            "'{}' is a vector attribute: ask for its magnitude (--magnitude) or, for a velocity, \
             its vorticity (--vorticity) or λ2 (--lambda2)",
            request.attribute
        ),
        (Attribute::Scalar(_), Derived::Magnitude | Derived::Vorticity | Derived::Lambda2) => {
            bail_input!(
                "'{}' is a scalar attribute: --magnitude, --vorticity and --lambda2 need a vector \
                 (velocity)",
                request.attribute
            )
        }
        _ => {}
    }
    let supports: Vec<f32> = match lookup(attributes, "h") {
        Some(Attribute::Scalar(h)) if h.len() == n => {
            if let Some(i) = h.iter().position(|h| !(h.is_finite() && *h > 0.0)) {
                bail_input!(
                    "particle {i} has a smoothing length h = {} (not positive)",
                    h[i]
                );
            }
            h.iter().map(|h| 2.0 * h * scale).collect()
        }
        _ => vec![support * scale; n],
    };
    let max_support = supports.iter().copied().fold(0.0f32, f32::max);
    let mut columns = vec![supports];
    let raw = columns.len();
    push_columns(&mut columns, &quantity);
    let mut extra_widths = Vec::with_capacity(extras.len());
    for name in extras {
        let a = find(attributes, name)?;
        check_finite(name, &a, n)?;
        extra_widths.push(push_columns(&mut columns, &a));
    }
    if extra_widths.iter().sum::<usize>() > MAX_EXTRA_COMPONENTS {
        bail_input!("at most {MAX_EXTRA_COMPONENTS} attribute components can be interpolated");
    }
    let volumes = match (lookup(attributes, "mass"), lookup(attributes, "density")) {
        (Some(Attribute::Scalar(m)), Some(Attribute::Scalar(rho)))
            if m.len() == n && rho.len() == n =>
        {
            if let Some(i) = rho.iter().position(|r| !(r.is_finite() && *r > 0.0)) {
                bail_input!("particle {i} has a density {} (not positive)", rho[i]);
            }
            Some(m.iter().zip(&rho).map(|(m, r)| m / r).collect::<Vec<f32>>())
        }
        _ => None,
    };
    let volume_given = volumes.is_some();
    if let Some(v) = volumes {
        columns.push(v);
    }
    let mut handlers =
        HandlerArray::with_channels(positions, max_support.max(f32::MIN_POSITIVE), columns)?;
    if !volume_given {
        // 1/(σ Σ_j W_ij) with one support: the density field's volumes (m = ρ₀ r³ cancels).
        let v = particle_volumes(&handlers, support * scale);
        handlers.channels.push(v);
    }
    let volume = handlers.channels.len() - 1;
    let mut extra_channels = Vec::with_capacity(extra_widths.len());
    let mut next = raw
        + if matches!(quantity, Attribute::Vector(_)) {
            3
        } else {
            1
        };
    for w in extra_widths {
        extra_channels.push((next, w));
        next += w;
    }
    let mut interpolant = Interpolant {
        handlers,
        channels: Channels {
            support: 0,
            volume,
            value: raw,
            extras: extra_channels,
        },
        shepard,
    };
    if matches!(quantity, Attribute::Vector(_)) {
        let derived = match request.derived {
            Derived::Vorticity => vorticity(&interpolant, raw),
            Derived::Lambda2 => super::lambda2::lambda2(&interpolant, raw),
            _ => magnitude(&interpolant.handlers.channels[raw..raw + 3]),
        };
        interpolant.handlers.channels.push(derived);
        interpolant.channels.value = interpolant.handlers.channels.len() - 1;
    }
    Ok(interpolant)
}

fn magnitude(c: &[Vec<f32>]) -> Vec<f32> {
    (0..c[0].len())
        .map(|i| Vec3::new(c[0][i], c[1][i], c[2][i]).length())
        .collect()
}

/// |ω_i| with ω_i = Σ_j V_j ∇W(x_i − x_j) × (v_j − v_i): the curl of the interpolated velocity
/// at each particle, minus v_i × Σ V_j ∇W_ij, which vanishes in the bulk but not at the free
/// surface.
fn vorticity(it: &Interpolant, first: usize) -> Vec<f32> {
    it.velocity_sums(
        first,
        |w: &mut DVec3, grad, dv, volume| *w += grad.cross(dv) * volume,
        |w| w.length() as f32,
    )
}
