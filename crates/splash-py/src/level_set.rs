//! `level_set` and `write_vdb`: a closed mesh's narrow-band signed distance on a voxel grid
//! (`splash_sph::level_set`), as numpy arrays or as an OpenVDB file.

use std::path::PathBuf;

use numpy::PyArray2;
use numpy::ndarray::Array2;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use splash_sph::Attribute;
use splash_sph::level_set::LevelSet;

use crate::arrays;
use crate::errors::to_py;
use crate::post::MeshInput;

/// The fields of `LevelSetArrays`, in order.
const FIELDS: [&str; 4] = ["ijk", "values", "voxel", "half_width"];

/// Adds the named tuple type `LevelSetArrays` to the module.
pub fn add_type(m: &Bound<'_, PyModule>) -> PyResult<()> {
    crate::add_named_tuple(
        m,
        "LevelSetArrays",
        &FIELDS,
        "A narrow-band level set: ijk (N, 3) int32 indices of the active voxels, voxel ijk \
         centred at ijk * voxel; values (N,) float32 signed distances, negative inside; voxel, \
         the voxels' edge; half_width, the band's half width in world units.",
    )
}

fn compute(py: Python<'_>, mesh: &Bound<'_, PyAny>, voxel: f32) -> PyResult<LevelSet> {
    let input = MeshInput::of(mesh)?;
    py.detach(|| LevelSet::of_mesh(&input.mesh, voxel))
        .map_err(to_py)
}

/// The narrow-band level set of a closed triangle mesh: its signed distance (negative inside)
/// at the centres of the voxels within 3 voxels of it, voxel ``ijk`` centred at
/// ``ijk * voxel``; returns a ``LevelSetArrays``.
///
/// ``mesh``: a ``Mesh``, a ``MeshArrays``, any object with ``vertices`` and ``faces`` arrays,
/// or a ``(vertices, faces)`` pair; closed and wound counter-clockwise seen from outside, as
/// every mesh splash makes. ``voxel``: the voxels' edge in world units (``splash recon
/// --format vdb`` uses the cell). The GIL is released while computing. Raises ValueError for
/// a bad mesh or voxel.
#[pyfunction]
pub fn level_set<'py>(
    py: Python<'py>,
    mesh: &Bound<'py, PyAny>,
    voxel: f32,
) -> PyResult<Bound<'py, PyAny>> {
    let ls = compute(py, mesh, voxel)?;
    let ijk = ls.coordinates();
    let n = ijk.len();
    let flat: Vec<i32> = ijk.into_iter().flatten().collect();
    let ijk = Array2::from_shape_vec((n, 3), flat).expect("3 indices per voxel");
    let kind = py.import("splash_sph._native")?.getattr("LevelSetArrays")?;
    kind.call1((
        PyArray2::from_owned_array(py, ijk),
        arrays::scalars_array(py, ls.values),
        ls.voxel,
        ls.half_width,
    ))
}

/// Writes the level set of ``mesh`` (as ``level_set`` makes it) to the OpenVDB file ``path``
/// atomically: the float grid ``surface`` (class level set, background the band's half width),
/// and one grid per entry of ``grids`` over the same voxels, each an (N,) or (N, 3) float32
/// array with a value per voxel in the order of ``level_set(mesh, voxel).ijk`` (``velocity``
/// is written as the vector grid ``v``, as Blender's and Houdini's motion blur read it). The
/// GIL is released while computing and writing.
///
/// Raises OSError when the file cannot be written, ValueError for a bad mesh, voxel or grid.
#[pyfunction]
#[pyo3(signature = (path, mesh, voxel, grids=None))]
pub fn write_vdb(
    py: Python<'_>,
    path: PathBuf,
    mesh: &Bound<'_, PyAny>,
    voxel: f32,
    grids: Option<&Bound<'_, PyDict>>,
) -> PyResult<()> {
    let ls = compute(py, mesh, voxel)?;
    let mut named: Vec<(String, Attribute)> = Vec::new();
    for (key, value) in grids.into_iter().flat_map(|g| g.iter()) {
        let name: String = key.extract()?;
        let what = format!("grids['{name}']");
        let attribute = arrays::column_of(&value, &what, ls.values.len(), "active voxels")?;
        named.push((name, attribute));
    }
    py.detach(|| ls.write_file(&path, &named)).map_err(to_py)
}
