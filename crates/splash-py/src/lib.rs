//! The Python extension `splash_sph._native`: SPH particles (numpy arrays) to triangle meshes
//! with the splash-sph library. The Python package `splash_sph` re-exports it; its documented
//! API is in `python/splash_sph/_native.pyi`.

mod arrays;
mod errors;
mod iso;
mod level_set;
mod mesh;
mod particles;
mod post;
mod preview;
mod read_mesh;
mod recon;
mod sequence;
mod settings;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::settings::{Overrides, options_function};

/// The particle spacing r estimated from the particles' number density.
///
/// ``positions``: an (N, 3) floating-point array. Deterministic: the same particles give
/// the same estimate. Raises ValueError when fewer than 2 particles are given or all of them
/// coincide. The GIL is released while estimating.
#[pyfunction]
fn estimate_spacing(py: Python<'_>, positions: &Bound<'_, PyAny>) -> PyResult<f32> {
    let points = arrays::points(positions, "positions")?;
    let points = points.as_slice();
    py.detach(|| splash_sph::estimate_spacing(points))
        .ok_or_else(|| {
            PyValueError::new_err(format!(
                "cannot estimate the particle spacing from {} particles: it needs at least 2 \
                 distinct positions",
                points.len()
            ))
        })
}

/// The default configuration as a dict shaped like the TOML file (keys without a default,
/// such as ``spacing``, ``threads`` and ``max_memory``, are absent). Edit it and pass it as
/// ``reconstruct(..., config=d)``.
#[pyfunction]
fn default_config(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    settings::to_dict(py, &splash_sph::Config::default())
}

options_function! {
/// The configuration that ``recon_sequence`` (and ``reconstruct``, which takes the same
/// keyword arguments but the options of files and sequences) would use with the same
/// ``config`` and keyword arguments, as TOML text (what ``splash config show`` prints with the
/// flags of the same names; save it to reuse it with ``splash recon --config``). Raises
/// ValueError as ``reconstruct`` does for bad settings.
fn config_toml<'py>(config: Option<&Bound<'py, PyAny>>, spacing: Option<f32>)
    signature(config=None, *, spacing=None,) then() files -> PyResult<String>, |options| {
    Ok(settings::resolve(config, Overrides { spacing, ..options })?.to_toml())
}
}

/// Closed triangle meshes from SPH particles (native part; use the ``splash_sph`` package).
#[pymodule]
#[pyo3(name = "_native")]
fn native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(recon::reconstruct, m)?)?;
    m.add_function(wrap_pyfunction!(sequence::recon_sequence, m)?)?;
    m.add_function(wrap_pyfunction!(sequence::frame_number, m)?)?;
    m.add_function(wrap_pyfunction!(iso::iso, m)?)?;
    m.add_function(wrap_pyfunction!(post::postprocess, m)?)?;
    m.add_function(wrap_pyfunction!(preview::preview, m)?)?;
    m.add_function(wrap_pyfunction!(particles::read_particles, m)?)?;
    m.add_function(wrap_pyfunction!(read_mesh::read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(level_set::level_set, m)?)?;
    m.add_function(wrap_pyfunction!(level_set::write_vdb, m)?)?;
    read_mesh::add_type(m)?;
    level_set::add_type(m)?;
    m.add_function(wrap_pyfunction!(estimate_spacing, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::mesh_edges, m)?)?;
    m.add_function(wrap_pyfunction!(default_config, m)?)?;
    m.add_function(wrap_pyfunction!(config_toml, m)?)?;
    m.add_class::<mesh::Mesh>()?;
    m.add_class::<particles::Particles>()?;
    Ok(())
}

/// Adds to the module the named tuple type `name` with `fields` and the docstring `doc`.
fn add_named_tuple(
    m: &Bound<'_, PyModule>,
    name: &str,
    fields: &[&str],
    doc: &str,
) -> PyResult<()> {
    let namedtuple = m.py().import("collections")?.getattr("namedtuple")?;
    let kind = namedtuple.call1((name, fields.to_vec()))?;
    kind.setattr("__module__", "splash_sph")?;
    kind.setattr("__doc__", doc)?;
    m.add(name, kind)
}
