//! One table of the usual spellings of particle attributes, so that `--attributes velocity`
//! finds a frame's velocities whatever its file calls them: `velocity`, `v` (Houdini), `vel`,
//! `velocities`, or the components `vx vy vz`, `velocity_x velocity_y velocity_z`, `v_x …`,
//! `vel_x …` when a reader left them as three numbers.
//!
//! Names compare ignoring ASCII case. A name that is in no row stands for itself.

use std::collections::BTreeMap;

use glam::Vec3;

use crate::data::Attribute;

/// Canonical name, then the spellings that mean it. The canonical name is the one written to
/// meshes.
const ALIASES: &[(&str, &[&str])] = &[
    ("velocity", &["velocity", "velocities", "vel", "vels", "v"]),
    ("normal", &["normal", "normals", "n"]),
    ("density", &["density", "densities", "rho", "dens"]),
    ("pressure", &["pressure", "pressures"]),
    ("mass", &["mass", "masses"]),
    ("h", &["h", "smoothing_length", "hsml"]),
    ("id", &["id", "ids", "particle_id", "pid"]),
];

/// The canonical name of `name`: `v` and `vel` are `velocity`, `rho` is `density`; a name of
/// no row comes back as it is.
pub(crate) fn canonical(name: &str) -> &str {
    let name = name.trim();
    ALIASES
        .iter()
        .find(|(_, spellings)| spellings.iter().any(|s| s.eq_ignore_ascii_case(name)))
        .map_or(name, |(canonical, _)| canonical)
}

/// The spellings of `name`'s canonical name (just `name` when it has no row).
fn spellings(name: &str) -> Vec<&str> {
    let canonical = canonical(name);
    match ALIASES.iter().find(|(c, _)| *c == canonical) {
        Some((_, spellings)) => spellings.to_vec(),
        None => vec![canonical],
    }
}

/// Where a frame keeps the attribute a name asks for: see [`locate`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Location {
    /// One attribute of this name.
    Whole(String),
    /// Three scalar attributes of these names, x, y and z of a vector.
    Components([String; 3]),
}

/// Where the attribute that `requested` names is among `names` (each attribute's name and
/// whether it is a scalar): the one of that exact name, else one whose name is another spelling
/// of it, else three scalar components (`{s}x {s}y {s}z` or `{s}_x {s}_y {s}_z` for a spelling
/// `s`). None when the frame has none of these.
pub fn locate<'a>(
    names: impl Iterator<Item = (&'a str, bool)> + Clone,
    requested: &str,
) -> Option<Location> {
    if let Some((k, _)) = names.clone().find(|(k, _)| *k == requested) {
        return Some(Location::Whole(k.to_string()));
    }
    let spellings = spellings(requested);
    if let Some((k, _)) = names
        .clone()
        .find(|(k, _)| spellings.iter().any(|s| s.eq_ignore_ascii_case(k)))
    {
        return Some(Location::Whole(k.to_string()));
    }
    for s in &spellings {
        for separator in ["", "_"] {
            let keys = ["x", "y", "z"].map(|c| {
                let n = format!("{s}{separator}{c}");
                names
                    .clone()
                    .find(|(k, scalar)| *scalar && k.eq_ignore_ascii_case(&n))
                    .map(|(k, _)| k.to_string())
            });
            if let [Some(x), Some(y), Some(z)] = keys {
                return Some(Location::Components([x, y, z]));
            }
        }
    }
    None
}

/// Takes the attribute that `requested` names out of `attributes` (see [`locate`]), three
/// components as one vector. None when the frame has none of these.
pub(crate) fn take(
    attributes: &mut BTreeMap<String, Attribute>,
    requested: &str,
) -> Option<Attribute> {
    let names = attributes
        .iter()
        .map(|(k, a)| (k.as_str(), matches!(a, Attribute::Scalar(_))));
    match locate(names, requested)? {
        Location::Whole(k) => attributes.remove(&k),
        Location::Components(keys) => {
            let [x, y, z] = keys.map(|k| match attributes.remove(&k) {
                Some(Attribute::Scalar(values)) => values,
                _ => unreachable!("located as a scalar"),
            });
            Some(Attribute::Vector(
                x.iter()
                    .zip(&y)
                    .zip(&z)
                    .map(|((&x, &y), &z)| Vec3::new(x, y, z))
                    .collect(),
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spellings_find_the_attribute() {
        assert_eq!(canonical("V"), "velocity");
        assert_eq!(canonical("velocities"), "velocity");
        assert_eq!(canonical("rho"), "density");
        assert_eq!(canonical("temperature"), "temperature");
        let velocity = Attribute::Vector(vec![Vec3::X]);
        for name in ["v", "vel", "Velocity", "velocity"] {
            let mut attributes = BTreeMap::from([(name.to_string(), velocity.clone())]);
            assert_eq!(
                take(&mut attributes, "velocity"),
                Some(velocity.clone()),
                "{name}"
            );
            assert!(attributes.is_empty());
        }
        for triple in [
            ["vx", "vy", "vz"],
            ["velocity_x", "velocity_y", "velocity_z"],
        ] {
            let mut attributes: BTreeMap<String, Attribute> = triple
                .iter()
                .zip([1.0, 2.0, 3.0])
                .map(|(n, x)| (n.to_string(), Attribute::Scalar(vec![x])))
                .collect();
            attributes.insert("density".into(), Attribute::Scalar(vec![1000.0]));
            let v = take(&mut attributes, "vel");
            assert_eq!(v, Some(Attribute::Vector(vec![Vec3::new(1.0, 2.0, 3.0)])));
            assert_eq!(attributes.len(), 1);
        }
        let mut attributes = BTreeMap::from([("rho".to_string(), Attribute::Scalar(vec![2.0]))]);
        assert!(take(&mut attributes, "pressure").is_none());
        assert!(take(&mut attributes, "density").is_some());
    }
}
