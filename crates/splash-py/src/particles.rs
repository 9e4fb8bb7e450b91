//! `read_particles` and the `Particles` it returns.

use std::collections::BTreeMap;
use std::path::PathBuf;

use numpy::{PyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyKeyError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use splash_sph::InputFormat;
use splash_sph::Vec3;
use splash_sph::attribute_names::{self, Location};
use splash_sph::io::Attribute;

use crate::arrays;
use crate::errors::to_py;

/// One particle frame: positions and per-particle attributes.
///
/// ``len(p)`` is the number of particles, ``p["velocity"]`` (or ``p.attributes["velocity"]``)
/// an attribute by the name the file gives it, ``p.attribute("v")`` one by any usual spelling
/// (the alias table of ``--attributes``), ``p.attribute_names`` their names, and
/// ``"velocity" in p`` tells whether the file has one of that name.
#[pyclass(frozen, module = "splash_sph")]
pub struct Particles {
    /// Particle positions, shape (N, 3), float32.
    #[pyo3(get)]
    positions: Py<PyArray2<f32>>,
    /// Per-particle attributes by name (``velocity``, ``density``, ...): arrays of shape
    /// (N, 3) for vectors and (N,) for scalars, float32.
    #[pyo3(get)]
    attributes: Py<PyDict>,
}

impl Particles {
    /// The positions (copied: the array may have been edited or replaced).
    pub(crate) fn positions(&self, py: Python<'_>) -> PyResult<Vec<Vec3>> {
        Ok(arrays::points(self.positions.bind(py).as_any(), "positions")?.into_vec())
    }

    /// Positions and every attribute by name, as the library takes a frame (copied: the
    /// arrays may have been edited or replaced since the file was read).
    pub(crate) fn columns(
        &self,
        py: Python<'_>,
    ) -> PyResult<(Vec<Vec3>, BTreeMap<String, Attribute>)> {
        let positions = self.positions(py)?;
        let mut columns = BTreeMap::new();
        for (name, values) in self.attributes.bind(py).iter() {
            let name: String = name.extract()?;
            let what = format!("attributes['{name}']");
            let a = arrays::column(&values, &what, positions.len())?;
            columns.insert(name, a);
        }
        Ok((positions, columns))
    }
}

#[pymethods]
impl Particles {
    fn __len__(&self, py: Python<'_>) -> usize {
        self.positions.bind(py).shape()[0]
    }

    fn __getitem__<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        self.attributes
            .bind(py)
            .get_item(name)?
            .ok_or_else(|| PyKeyError::new_err(name.to_string()))
    }

    /// The attribute that ``name`` names in any of its usual spellings, as ``--attributes``
    /// finds it: ``"v"``, ``"vel"`` and ``"velocities"`` find ``velocity``, ``"rho"`` finds
    /// ``density``, and three scalars ``vx vy vz`` (or ``velocity_x …``) come as one (N, 3)
    /// array. Raises KeyError, listing the frame's attributes, when it has none of these.
    fn attribute<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        let dict = self.attributes.bind(py);
        let mut names = Vec::with_capacity(dict.len());
        for (k, v) in dict.iter() {
            names.push((k.extract::<String>()?, arrays::is_scalar(&v)?));
        }
        let found = attribute_names::locate(names.iter().map(|(k, s)| (k.as_str(), *s)), name);
        match found {
            Some(Location::Whole(k)) => self.__getitem__(py, &k),
            Some(Location::Components(keys)) => {
                let mut columns = Vec::with_capacity(3);
                for k in &keys {
                    columns.push(arrays::scalars(&self.__getitem__(py, k)?, k)?);
                }
                let vectors = (0..columns[0].len())
                    .map(|i| Vec3::new(columns[0][i], columns[1][i], columns[2][i]))
                    .collect();
                Ok(arrays::points_array(py, vectors).into_any())
            }
            None => Err(PyKeyError::new_err(format!(
                "no attribute '{name}' (in any of its spellings); the frame has: {}",
                if names.is_empty() {
                    "none".to_string()
                } else {
                    names
                        .iter()
                        .map(|(k, _)| k.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                }
            ))),
        }
    }

    /// The names of the attributes, as the file gives them, sorted.
    #[getter]
    fn attribute_names(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        let mut names: Vec<String> = self.attributes.bind(py).keys().extract()?;
        names.sort();
        Ok(names)
    }

    fn __contains__(&self, py: Python<'_>, name: &str) -> PyResult<bool> {
        self.attributes.bind(py).contains(name)
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let names: Vec<String> = self.attributes.bind(py).keys().extract()?;
        Ok(format!(
            "Particles({} particles, attributes: [{}])",
            self.__len__(py),
            names.join(", ")
        ))
    }
}

/// Reads one particle frame: PLY (ascii or binary), CSV/TXT tables, raw little-endian
/// float32 x y z triples (``.bin``/``.raw``), legacy VTK (``.vtk``), VTK XML (``.vtu``,
/// ``.vtp``), classic BGEO (``.bgeo``, ``.bgeo.gz``) or ``.xyz`` (raw triples, or text).
///
/// ``format`` (``"ply"``, ``"csv"``, ``"raw"``, ``"vtk"``, ``"vtu"``, ``"bgeo"`` or ``"xyz"``)
/// overrides the guess from the extension.
/// The GIL is released while reading.
///
/// Raises FileNotFoundError for a missing file, OSError when it cannot be read, and
/// ValueError when its content is not a valid frame (the message names the file and says
/// what is wrong where).
#[pyfunction]
#[pyo3(signature = (path, format=None))]
pub fn read_particles(py: Python<'_>, path: PathBuf, format: Option<&str>) -> PyResult<Particles> {
    let format = format.map(InputFormat::parse).transpose().map_err(to_py)?;
    let frame = py
        .detach(|| splash_sph::read_particles(&path, format))
        .map_err(to_py)?;
    let attributes = PyDict::new(py);
    for (name, values) in frame.attributes {
        match values {
            Attribute::Scalar(v) => attributes.set_item(name, arrays::scalars_array(py, v))?,
            Attribute::Vector(v) => attributes.set_item(name, arrays::points_array(py, v))?,
        }
    }
    Ok(Particles {
        positions: arrays::points_array(py, frame.positions).unbind(),
        attributes: attributes.unbind(),
    })
}
