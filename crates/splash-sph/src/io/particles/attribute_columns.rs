//! The per-particle attributes of a file as its reader gathers them: which columns (PLY vertex
//! properties, CSV columns) make which attribute (the rules are on [`super::read_particles`]),
//! and the values read so far. A triple whose name is already a column's, or another triple's,
//! stays scalars, so that no values are lost to a clash.

use std::collections::BTreeMap;

use glam::Vec3;

use crate::data::Attribute;

/// What one column of the file holds.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Role {
    /// Not an attribute: a coordinate, a list, a column that is not numeric or repeats a name.
    Skip,
    /// Attribute `scalars[i]`.
    Scalar(usize),
    /// Component `c` of attribute `vectors[i]`.
    Vector(usize, usize),
}

pub(in crate::io) struct AttributeColumns {
    /// One per column of the file.
    roles: Vec<Role>,
    scalars: Vec<(String, Vec<f32>)>,
    vectors: Vec<(String, Vec<Vec3>)>,
}

impl AttributeColumns {
    /// For a file without attributes.
    pub fn none() -> Self {
        Self {
            roles: Vec::new(),
            scalars: Vec::new(),
            vectors: Vec::new(),
        }
    }

    /// Sorts the columns `names` into attributes: every column except the `coordinates` and
    /// those that are not `numeric`. Names compare ignoring ASCII case if `ignore_case`.
    pub fn new(
        names: &[&str],
        coordinates: [usize; 3],
        numeric: impl Fn(usize) -> bool,
        ignore_case: bool,
    ) -> Self {
        let same = |a: &str, b: &str| same(a, b, ignore_case);
        let mut roles = vec![Role::Skip; names.len()];
        let free = |i: usize, roles: &[Role]| {
            !coordinates.contains(&i) && roles[i] == Role::Skip && numeric(i)
        };
        let mut vectors: Vec<(String, Vec<Vec3>)> = Vec::new();
        for (i, name) in names.iter().enumerate() {
            let Some((stem, vector)) = vector_name(name, ignore_case) else {
                continue;
            };
            let clash = names.iter().any(|n| same(n, &vector))
                || vectors.iter().any(|(v, _)| same(v, &vector));
            if !free(i, &roles) || clash {
                continue;
            }
            let find = |axis| {
                let wanted = format!("{stem}{axis}");
                (0..names.len()).find(|&j| free(j, &roles) && same(names[j], &wanted))
            };
            let (Some(j), Some(k)) = (find('y'), find('z')) else {
                continue;
            };
            for (c, column) in [i, j, k].into_iter().enumerate() {
                roles[column] = Role::Vector(vectors.len(), c);
            }
            vectors.push((vector, Vec::new()));
        }
        let mut scalars: Vec<(String, Vec<f32>)> = Vec::new();
        for (i, name) in names.iter().enumerate() {
            // A name repeated (CSV headers allow it) keeps its first column.
            let repeated = coordinates.iter().any(|&c| same(names[c], name))
                || scalars.iter().any(|(s, _)| same(s, name));
            if free(i, &roles) && !name.is_empty() && !repeated {
                roles[i] = Role::Scalar(scalars.len());
                scalars.push(((*name).to_owned(), Vec::new()));
            }
        }
        Self {
            roles,
            scalars,
            vectors,
        }
    }

    /// Whether column `i` holds an attribute.
    #[inline]
    pub fn reads(&self, i: usize) -> bool {
        self.roles.get(i).is_some_and(|&r| r != Role::Skip)
    }

    /// The last column that holds an attribute, or 0.
    pub fn last(&self) -> usize {
        self.roles
            .iter()
            .rposition(|&r| r != Role::Skip)
            .unwrap_or_default()
    }

    pub fn reserve(&mut self, records: usize) {
        self.scalars
            .iter_mut()
            .for_each(|(_, v)| v.reserve(records));
        self.vectors
            .iter_mut()
            .for_each(|(_, v)| v.reserve(records));
    }

    /// Makes every attribute `records` long, new records zero until set.
    pub fn resize(&mut self, records: usize) {
        self.scalars
            .iter_mut()
            .for_each(|(_, v)| v.resize(records, 0.0));
        let zero = Vec3::ZERO;
        self.vectors
            .iter_mut()
            .for_each(|(_, v)| v.resize(records, zero));
    }

    /// Appends a record of zeros, for [`Self::set_last`] to fill.
    #[inline]
    pub fn push(&mut self) {
        self.scalars.iter_mut().for_each(|(_, v)| v.push(0.0));
        self.vectors
            .iter_mut()
            .for_each(|(_, v)| v.push(Vec3::ZERO));
    }

    /// Sets column `i` of the last record (nothing if it holds no attribute).
    #[inline]
    pub fn set_last(&mut self, i: usize, value: f32) {
        match self.roles.get(i) {
            Some(&Role::Scalar(a)) => {
                if let Some(slot) = self.scalars[a].1.last_mut() {
                    *slot = value;
                }
            }
            Some(&Role::Vector(a, c)) => {
                if let Some(slot) = self.vectors[a].1.last_mut() {
                    slot[c] = value;
                }
            }
            Some(Role::Skip) | None => {}
        }
    }

    /// Sets column `i` of the records from `first` on to `values`; `None` if one is `None`.
    #[inline]
    pub fn fill(
        &mut self,
        i: usize,
        first: usize,
        values: impl Iterator<Item = Option<f32>>,
    ) -> Option<()> {
        match self.roles.get(i) {
            Some(&Role::Scalar(a)) => {
                for (slot, value) in self.scalars[a].1[first..].iter_mut().zip(values) {
                    *slot = value?;
                }
            }
            Some(&Role::Vector(a, c)) => {
                for (slot, value) in self.vectors[a].1[first..].iter_mut().zip(values) {
                    slot[c] = value?;
                }
            }
            Some(Role::Skip) | None => {}
        }
        Some(())
    }

    pub fn into_map(self) -> BTreeMap<String, Attribute> {
        let scalars = self
            .scalars
            .into_iter()
            .map(|(name, v)| (name, Attribute::Scalar(v)));
        let vectors = self
            .vectors
            .into_iter()
            .map(|(name, v)| (name, Attribute::Vector(v)));
        scalars.chain(vectors).collect()
    }
}

/// If `name` can be the x component of a vector (`vx`, `nx`, `{stem}_x`): the name without its
/// last letter, and the vector's.
fn vector_name(name: &str, ignore_case: bool) -> Option<(&str, String)> {
    let stem = name
        .strip_suffix('x')
        .or_else(|| name.strip_suffix('X').filter(|_| ignore_case))?;
    let vector = if same(stem, "v", ignore_case) {
        "velocity"
    } else if same(stem, "n", ignore_case) {
        "normal"
    } else {
        stem.strip_suffix('_').filter(|s| !s.is_empty())?
    };
    Some((stem, vector.to_owned()))
}

fn same(a: &str, b: &str, ignore_case: bool) -> bool {
    a == b || ignore_case && a.eq_ignore_ascii_case(b)
}
