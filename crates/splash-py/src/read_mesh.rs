//! `read_mesh`: a mesh file that splash wrote, back as numpy arrays in a `MeshArrays` named
//! tuple, through the library's readers (`splash_sph::io::read_mesh`).

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::PyDict;
use splash_sph::Attribute;

use crate::arrays;
use crate::errors::to_py;

/// The fields of `MeshArrays`, in order.
const FIELDS: [&str; 4] = ["vertices", "faces", "normals", "attributes"];

/// Adds the named tuple type `MeshArrays` to the module.
pub fn add_type(m: &Bound<'_, PyModule>) -> PyResult<()> {
    crate::add_named_tuple(
        m,
        "MeshArrays",
        &FIELDS,
        "A triangle mesh read from a file: vertices (V, 3) float32, faces (F, 3) uint32, \
         normals (V, 3) float32 or (0, 3) when the file has none, and attributes, a dict of \
         per-vertex float32 arrays ((V, 3) vectors, (V,) scalars).",
    )
}

/// Reads a mesh written by ``splash recon`` or ``Mesh.write``, by its extension: ``.obj``,
/// ``.ply`` (binary or ascii), ``.vtk`` (legacy), ``.vtu`` or ``.vtp``; returns a
/// ``MeshArrays``.
///
/// PLY properties ``vx vy vz`` become the attribute ``velocity``, ``{name}_x {name}_y
/// {name}_z`` the vector ``{name}``, other vertex properties scalars; VTK point data arrays
/// keep their names (``Normals`` are the normals). Faces must be triangles. The GIL is
/// released while reading.
///
/// Raises FileNotFoundError for a missing file, OSError when it cannot be read, and
/// ValueError naming the file when its content is not such a mesh.
#[pyfunction]
pub fn read_mesh(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyAny>> {
    let file = py
        .detach(|| splash_sph::io::read_mesh(&path))
        .map_err(to_py)?;
    let attributes = PyDict::new(py);
    for (name, values) in file.attributes {
        match values {
            Attribute::Scalar(v) => attributes.set_item(name, arrays::scalars_array(py, v))?,
            Attribute::Vector(v) => attributes.set_item(name, arrays::points_array(py, v))?,
        }
    }
    let mesh = file.mesh;
    let kind = py.import("splash_sph._native")?.getattr("MeshArrays")?;
    kind.call1((
        arrays::points_array(py, mesh.vertices),
        arrays::triangles_array(py, mesh.triangles),
        arrays::points_array(py, mesh.normals),
        attributes,
    ))
}
