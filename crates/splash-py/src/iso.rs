//! `iso`: the isosurface of a particle quantity (Marching Correctors) as a `Mesh`, as
//! `splash iso` computes it, with the GIL released while the library works.

use std::collections::BTreeMap;

use pyo3::exceptions::{PyKeyError, PyTypeError, PyUserWarning, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use splash_sph::iso::{Derived, IsoRequest, IsoStats, extract};
use splash_sph::{Attribute, Error};

use crate::arrays;
use crate::errors::to_py;
use crate::mesh::Mesh;
use crate::particles::Particles;
use crate::settings::{self, Overrides};

/// The name the values of ``iso(positions, values, ...)`` take in the library.
const VALUES: &str = "value";

/// The isosurface A = ``level`` of a particle quantity, exact with respect to the SPH
/// interpolant A(x) = Σ_j (m_j/ρ_j) A_j W(x − x_j, 2h_j) (Marching Correctors), as
/// ``splash iso`` computes it: the same settings give the same mesh.
///
/// ``particles``: a ``Particles`` (from ``read_particles``) with ``attribute`` the name of one
/// of its attributes (any spelling of the alias table: ``"v"`` finds ``velocity``, ``vx vy vz``
/// make one vector); or an (N, 3) positions array with ``attribute`` an (N,) or (N, 3) array of
/// per-particle values.
///
/// ``magnitude``: the isosurface of |A| of a vector attribute; ``vorticity``: of |∇ × v| of a
/// velocity (SPH curl); ``lambda2``: of λ2, the middle eigenvalue of S² + Ω² of a velocity's
/// SPH gradient (vortex cores are where λ2 < 0: take a negative level). ``spacing``: the particle spacing r (required unless the config gives
/// it). ``cell``: the virtual grid's cell (``"r/2"`` by default, ``"r"``, a number).
/// ``correct``: Newton steps per vertex along its cube edge (3 by default, 0: plain Marching
/// Cubes vertices). ``shepard``: normalise by the sum of weights Σ V W (plain SPH by default).
/// ``kernel_scale``: multiplies every particle's kernel support (a UserWarning says when it
/// leaves fewer than 10 particles in a support on average: the surface then breaks up). ``attributes``: names of the
/// particles' attributes to interpolate onto the vertices (with a ``Particles`` only); they come
/// back in ``Mesh.attributes``. ``threads``: worker threads (all cores by default; the mesh does
/// not depend on it). ``config``: a TOML file's path or a dict, as for ``reconstruct`` (its
/// ``[iso]`` table holds the thresholds); the keyword arguments override it.
///
/// The mesh's normals are the SPH gradient, pointing towards larger A; triangles are trimmed
/// where the sum of weights falls (open surfaces at the free surface). ``Mesh.report`` holds
/// the figures of the JSON log's ``iso`` object (``seed_cells``, ``visited_cells``,
/// ``crossed_cells``, ``cache_hit_ratio``, ``correction``, ``times`` in seconds, ...).
///
/// Raises KeyError for an attribute the particles do not have (listing theirs), ValueError for
/// a vector without ``magnitude``/``vorticity``/``lambda2``, bad arrays or settings; TypeError for a wrong
/// kind of argument.
#[allow(clippy::too_many_arguments)]
#[pyfunction]
#[pyo3(signature = (particles, attribute, level, *, spacing=None, magnitude=false,
    vorticity=false, lambda2=false, cell=None, correct=None, shepard=None, kernel_scale=None, attributes=None,
    threads=None, config=None))]
pub fn iso<'py>(
    py: Python<'py>,
    particles: &Bound<'py, PyAny>,
    attribute: &Bound<'py, PyAny>,
    level: f32,
    spacing: Option<f32>,
    magnitude: bool,
    vorticity: bool,
    lambda2: bool,
    cell: Option<Bound<'py, PyAny>>,
    correct: Option<i64>,
    shepard: Option<bool>,
    kernel_scale: Option<f32>,
    attributes: Option<Vec<String>>,
    threads: Option<i64>,
    config: Option<&Bound<'py, PyAny>>,
) -> PyResult<Mesh> {
    if usize::from(magnitude) + usize::from(vorticity) + usize::from(lambda2) > 1 {
        return Err(PyValueError::new_err(
            "magnitude, vorticity and lambda2 exclude each other: pass one",
        ));
    }
    let overrides = Overrides {
        spacing,
        cell,
        threads,
        ..Overrides::default()
    };
    let mut config = settings::resolve(config, overrides)?;
    if config.spacing.is_none() {
        return Err(PyValueError::new_err(
            "the particle spacing is not set: pass spacing=r (the simulation's particle \
             spacing) or give spacing in the config; splash_sph.estimate_spacing(positions) \
             estimates it",
        ));
    }
    if let Some(n) = correct {
        config.iso.correct = u32::try_from(n).map_err(|_| {
            PyValueError::new_err(format!(
                "correct must be from 0 to 32 Newton steps, got {n}"
            ))
        })?;
    }
    if let Some(s) = shepard {
        config.iso.shepard = s;
    }
    if let Some(k) = kernel_scale {
        config.iso.kernel_scale = k;
    }
    config.validate().map_err(to_py)?;

    let (positions, columns, name) = match particles.cast::<Particles>() {
        Ok(p) => {
            let name: String = attribute.extract().map_err(|_| {
                PyTypeError::new_err("with a Particles, attribute must be its attribute's name")
            })?;
            let (positions, columns) = p.get().columns(py)?;
            (positions, columns, name)
        }
        Err(_) => {
            if attribute.extract::<String>().is_ok() {
                return Err(PyTypeError::new_err(
                    "with a positions array, attribute must be an array of per-particle \
                     values; pass a Particles (read_particles) to name an attribute",
                ));
            }
            if attributes.as_ref().is_some_and(|a| !a.is_empty()) {
                return Err(PyValueError::new_err(
                    "attributes names attributes of a Particles; with a positions array \
                     there are none to carry",
                ));
            }
            let positions = arrays::points(particles, "positions")?.into_vec();
            let values = arrays::column(attribute, "attribute", positions.len())?;
            (
                positions,
                BTreeMap::from([(VALUES.to_string(), values)]),
                VALUES.to_string(),
            )
        }
    };
    config.output.attributes = attributes.unwrap_or_default();
    let request = IsoRequest {
        attribute: name,
        derived: match (magnitude, vorticity, lambda2) {
            (true, ..) => Derived::Magnitude,
            (_, true, _) => Derived::Vorticity,
            (.., true) => Derived::Lambda2,
            _ => Derived::Value,
        },
        level,
    };
    let (format, up_axis) = (config.output.format, config.output.up_axis);
    let threads = config.threads.take();
    let surface = py
        .detach(|| {
            splash_sph::install(threads, || extract(&positions, columns, &request, &config))?
        })
        .map_err(|e| match e {
            // A missing attribute is a missing key, as `Particles.attribute` raises.
            Error::Input(ref m) if m.starts_with("no particle attribute") => {
                PyKeyError::new_err(m.clone())
            }
            e => to_py(e),
        })?;

    for warning in &surface.warnings {
        let message = std::ffi::CString::new(warning.as_str())
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        PyErr::warn(py, &py.get_type::<PyUserWarning>(), &message, 1)?;
    }
    let report = report(py, &surface.stats, positions.len(), config.spacing)?;
    let mesh_attributes = PyDict::new(py);
    for (name, values) in surface.attributes {
        match values {
            Attribute::Scalar(v) => mesh_attributes.set_item(name, arrays::scalars_array(py, v))?,
            Attribute::Vector(v) => mesh_attributes.set_item(name, arrays::points_array(py, v))?,
        }
    }
    Ok(Mesh::new(
        py,
        surface.mesh,
        mesh_attributes,
        report,
        format,
        up_axis,
    ))
}

/// The `iso` figures of the JSON log, with times in seconds.
fn report<'py>(
    py: Python<'py>,
    s: &IsoStats,
    particles: usize,
    spacing: Option<f32>,
) -> PyResult<Bound<'py, PyDict>> {
    let report = PyDict::new(py);
    report.set_item("particles", particles)?;
    report.set_item("spacing", spacing)?;
    report.set_item("level", s.level)?;
    report.set_item("cell", s.cell)?;
    report.set_item("support_neighbours", s.support_neighbours)?;
    report.set_item("virtual_cells", s.virtual_cells)?;
    report.set_item("seed_cells", s.seed_cells)?;
    report.set_item("visited_cells", s.visited_cells)?;
    report.set_item("crossed_cells", s.crossed_cells)?;
    report.set_item("discarded_cells", s.discarded_cells)?;
    report.set_item("node_lookups", s.node_lookups)?;
    report.set_item("node_evaluations", s.node_evaluations)?;
    report.set_item("cache_hit_ratio", s.cache_hit_ratio)?;
    report.set_item("cache_peak_nodes", s.cache_peak_nodes)?;
    report.set_item("untrimmed_triangles", s.untrimmed_triangles)?;
    report.set_item("trim_cases", PyList::new(py, s.trim_cases)?)?;
    report.set_item("vertices", s.vertices)?;
    report.set_item("triangles", s.triangles)?;
    let c = &s.correction;
    let correction = PyDict::new(py);
    correction.set_item("vertices", c.vertices)?;
    correction.set_item("mean", c.mean)?;
    correction.set_item("max", c.max)?;
    correction.set_item("std_dev", c.std_dev)?;
    correction.set_item("mean_fraction", c.mean_fraction)?;
    correction.set_item("histogram", PyList::new(py, c.histogram)?)?;
    report.set_item("correction", correction)?;
    let t = &s.timings;
    let times = PyDict::new(py);
    for (name, d) in [
        ("grid_construction", t.grid_construction),
        ("seed_cells", t.seed_cells),
        ("surface_extraction", t.surface_extraction),
        ("correction", t.correction),
        ("finishing", t.finishing),
        ("total", s.total()),
    ] {
        times.set_item(name, d.as_secs_f64())?;
    }
    report.set_item("times", times)?;
    Ok(report)
}
