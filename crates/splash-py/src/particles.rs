//! `read_particles` and the `Particles` it returns.

use std::path::PathBuf;

use numpy::{PyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyKeyError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use splash_sph::InputFormat;
use splash_sph::io::Attribute;

use crate::arrays;
use crate::errors::to_py;

/// One particle frame: positions and per-particle attributes.
///
/// ``len(p)`` is the number of particles, ``p["velocity"]`` an attribute and
/// ``"velocity" in p`` tells whether the file has it.
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
