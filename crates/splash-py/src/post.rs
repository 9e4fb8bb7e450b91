//! `postprocess`: any closed triangle mesh (a `Mesh`, a `MeshArrays` or a (vertices, faces)
//! pair) through the library's post-processing (`splash_sph::mesh::post::postprocess_mesh`),
//! with the GIL released while it works.

use std::time::Instant;

use numpy::{PyArray2, PyArrayDescrMethods, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use splash_sph::TriMesh;
use splash_sph::mesh::post::{Volumes, postprocess_mesh};

use crate::arrays;
use crate::errors::to_py;
use crate::mesh::Mesh;
use crate::particles::Particles;
use crate::recon::as_written;
use crate::settings::{self, Overrides};

/// A post-processed copy of a closed triangle mesh: the default post-processing of
/// ``reconstruct`` (Taubin smoothing, each closed part's volume restored, tangential
/// relaxation), then the box, the small parts and the decimation where asked.
///
/// ``mesh``: a ``Mesh`` (from ``reconstruct`` or ``iso``), a ``MeshArrays`` (``read_mesh``),
/// any object with ``vertices`` and ``faces`` arrays, or a ``(vertices, faces)`` pair:
/// vertices an (V, 3) floating-point array, faces an (F, 3) integer array of vertex indices.
/// The mesh must be closed, manifold and consistently wound, as every mesh splash writes (the
/// volume, the inside and the box caps of an open surface are not defined); ValueError says how
/// many boundary, non-manifold and wrongly wound edges it has otherwise, or which triangle
/// references a missing vertex, or which vertex is not finite.
///
/// ``particles``: the particles the mesh encloses, an (N, 3) array or a ``Particles``: each
/// closed part's volume is brought to N_c·r³ for the N_c particles inside it, as
/// ``reconstruct`` does (``postprocess(reconstruct(x, r, raw=True), particles=x)`` gives
/// ``reconstruct(x, r)``'s vertices and faces, bit for bit). Without particles each closed
/// part keeps the volume it encloses on input: volume-true smoothing of any mesh.
///
/// ``spacing``: the particle spacing r, the unit of ``max_offset``, ``decimate`` and
/// ``min_component``; by default the config's, else the ``Mesh``'s ``report["spacing"]``.
/// ``cell``: the reconstruction's cell (it places the particles' rays); by default the
/// ``Mesh``'s ``report["cell"]``, else the config's (``"r/2"``).
///
/// The post-processing settings (``[post]`` of the config; None keeps the config's, the
/// defaults by default): ``raw=True`` skips smoothing and volume restoration;
/// ``smoothing_iterations`` (0), ``lambda_`` (0.6) and ``mu`` (−0.64): Taubin's λ|μ pairs, after
/// ``relax_first`` (4) tangential relaxation steps;
/// ``volume_rounds`` (4), ``volume_scope`` (``"frame"``: one offset for the whole mesh;
/// ``"component"``: each closed component to its own particles' volume), ``max_offset``
/// (0.5 r per step), ``refine_angle`` (0: off; in
/// degrees, bisects the edges where the surface bends more), ``relax_iterations`` (12),
/// ``volume_steps`` (1); ``mesh_aabb``, ``min_component`` and ``decimate`` as in
/// ``reconstruct``. ``config``: a TOML file's path or a dict, as ``reconstruct`` takes it.
/// ``threads``: worker threads, all cores by default; the result does not depend on it.
///
/// Returns a new ``Mesh``: normals when the input has them (area-weighted where vertices
/// moved), the input ``Mesh``'s attributes when neither ``mesh_aabb``, ``min_component`` nor
/// ``decimate`` is set (smoothing moves the vertices but keeps them; those three change
/// them), and the ``Mesh``'s output format and up axis. Its ``report``: ``vertices``,
/// ``triangles``, ``spacing``, ``cell`` (None without particles) and ``times`` (``post``,
/// ``total``, seconds). The input is not changed. The GIL is released while working.
#[allow(clippy::too_many_arguments)]
#[pyfunction]
#[pyo3(signature = (mesh, *, particles=None, spacing=None, cell=None, config=None, raw=None,
    smoothing_iterations=None, lambda_=None, mu=None, relax_first=None, volume_rounds=None,
    volume_scope=None,
    max_offset=None,
    refine_angle=None, relax_iterations=None, volume_steps=None, mesh_aabb=None, min_component=None,
    decimate=None, threads=None))]
pub fn postprocess<'py>(
    py: Python<'py>,
    mesh: &Bound<'py, PyAny>,
    particles: Option<&Bound<'py, PyAny>>,
    spacing: Option<f32>,
    cell: Option<Bound<'py, PyAny>>,
    config: Option<&Bound<'py, PyAny>>,
    raw: Option<bool>,
    smoothing_iterations: Option<i64>,
    lambda_: Option<f32>,
    mu: Option<f32>,
    relax_first: Option<i64>,
    volume_rounds: Option<i64>,
    volume_scope: Option<String>,
    max_offset: Option<f32>,
    refine_angle: Option<f32>,
    relax_iterations: Option<i64>,
    volume_steps: Option<i64>,
    mesh_aabb: Option<Vec<f32>>,
    min_component: Option<f64>,
    decimate: Option<Bound<'py, PyAny>>,
    threads: Option<i64>,
) -> PyResult<Mesh> {
    let given_cell = cell.is_some();
    let overrides = Overrides {
        spacing,
        cell,
        threads,
        raw,
        decimate,
        min_component,
        mesh_aabb,
        volume_scope,
        ..Overrides::default()
    };
    let mut config = settings::resolve(config, overrides)?;
    let post = &mut config.post;
    // Counts: a negative or huge one is refused naming its keyword.
    let set = |slot: &mut u32, value: Option<i64>, name: &str| -> PyResult<()> {
        if let Some(v) = value {
            *slot = u32::try_from(v).map_err(|_| {
                PyValueError::new_err(format!("{name} must be a count from 0, got {v}"))
            })?;
        }
        Ok(())
    };
    set(
        &mut post.smoothing_iterations,
        smoothing_iterations,
        "smoothing_iterations",
    )?;
    set(&mut post.relax_first, relax_first, "relax_first")?;
    set(&mut post.volume_rounds, volume_rounds, "volume_rounds")?;
    set(
        &mut post.relax_iterations,
        relax_iterations,
        "relax_iterations",
    )?;
    set(&mut post.volume_steps, volume_steps, "volume_steps")?;
    post.lambda = lambda_.unwrap_or(post.lambda);
    post.mu = mu.unwrap_or(post.mu);
    post.max_offset = max_offset.unwrap_or(post.max_offset);
    post.refine_angle = refine_angle.unwrap_or(post.refine_angle);
    post.validate().map_err(to_py)?;

    let input = MeshInput::of(mesh)?;
    let report_value = |key: &str| -> PyResult<Option<f32>> {
        match &input.report {
            Some(r) => match r.get_item(key)? {
                Some(v) if !v.is_none() => Ok(Some(v.extract()?)),
                _ => Ok(None),
            },
            None => Ok(None),
        }
    };
    let Some(r) = config.spacing.or(report_value("spacing")?) else {
        return Err(PyValueError::new_err(
            "the particle spacing is not set: pass spacing=r (the unit of max_offset, \
             decimate and min_component) or give spacing in the config",
        ));
    };
    let cell = match report_value("cell")? {
        Some(c) if !given_cell => c,
        _ => config.cell.resolve(r),
    };
    let positions = match particles {
        None => None,
        Some(p) => Some(match p.cast::<Particles>() {
            Ok(p) => p.get().positions(py)?,
            Err(_) => arrays::points(p, "particles")?.into_vec(),
        }),
    };
    let threads = config.threads;
    let post = config.post.clone();
    let keeps_vertices =
        post.mesh_aabb.is_none() && post.min_component.is_none() && post.decimate.is_none();
    let mut out = input.mesh;
    let normals = !out.normals.is_empty();
    let start = Instant::now();
    py.detach(|| {
        let volumes = match &positions {
            Some(particles) => Volumes::Particles { particles, cell },
            None => Volumes::Kept,
        };
        splash_sph::install(threads, || {
            postprocess_mesh(&mut out, r, volumes, &post, normals)
        })?
    })
    .map_err(to_py)?;
    let seconds = start.elapsed().as_secs_f64();

    let times = PyDict::new(py);
    times.set_item("post", seconds)?;
    times.set_item("total", seconds)?;
    let report = PyDict::new(py);
    report.set_item("vertices", out.vertices.len())?;
    report.set_item("triangles", out.triangles.len())?;
    report.set_item("spacing", as_written(r))?;
    report.set_item("cell", positions.is_some().then(|| as_written(cell)))?;
    report.set_item("times", times)?;
    let attributes = match (&input.attributes, keeps_vertices) {
        (Some(a), true) => a.copy()?,
        _ => PyDict::new(py),
    };
    Ok(Mesh::new(
        py,
        out,
        attributes,
        report,
        input.format,
        input.up_axis,
    ))
}

/// The mesh argument, copied into a `TriMesh`, with what a `Mesh` carries besides.
pub(crate) struct MeshInput<'py> {
    pub(crate) mesh: TriMesh,
    report: Option<Bound<'py, PyDict>>,
    attributes: Option<Bound<'py, PyDict>>,
    format: Option<splash_sph::MeshFormat>,
    up_axis: Option<splash_sph::UpAxis>,
}

impl<'py> MeshInput<'py> {
    pub(crate) fn of(mesh: &Bound<'py, PyAny>) -> PyResult<MeshInput<'py>> {
        let py = mesh.py();
        if let Ok(m) = mesh.cast::<Mesh>() {
            let m = m.get();
            let (format, up_axis) = m.output();
            return Ok(MeshInput {
                mesh: m.arrays(py)?,
                report: Some(m.report(py)),
                attributes: Some(m.attributes(py)),
                format,
                up_axis,
            });
        }
        let (vertices, faces, normals) = if mesh.hasattr("vertices")? && mesh.hasattr("faces")? {
            let normals = match mesh.getattr("normals") {
                Ok(n) if !n.is_none() => Some(n),
                _ => None,
            };
            (mesh.getattr("vertices")?, mesh.getattr("faces")?, normals)
        } else {
            match mesh.cast::<PyTuple>() {
                Ok(t) if t.len() == 2 => (t.get_item(0)?, t.get_item(1)?, None),
                _ => {
                    return Err(PyTypeError::new_err(
                        "mesh must be a Mesh, a MeshArrays, an object with vertices and \
                         faces arrays, or a (vertices, faces) tuple",
                    ));
                }
            }
        };
        let vertices = arrays::points(&vertices, "mesh vertices")?.into_vec();
        let triangles = indices(&faces)?;
        let normals = match normals {
            Some(n) => arrays::points(&n, "mesh normals")?.into_vec(),
            None => Vec::new(),
        };
        Ok(MeshInput {
            mesh: TriMesh {
                vertices,
                normals,
                triangles,
            },
            report: None,
            attributes: None,
            format: None,
            up_axis: None,
        })
    }
}

/// An (F, 3) array of vertex indices of any integer type as triangles; the library checks
/// them against the vertices.
fn indices(faces: &Bound<'_, PyAny>) -> PyResult<Vec<[u32; 3]>> {
    const WHAT: &str = "mesh faces";
    let numpy = faces.py().import("numpy")?;
    let array: Bound<'_, PyUntypedArray> = numpy.call_method1("asarray", (faces,))?.cast_into()?;
    let kind = array.dtype().kind();
    if kind != b'i' && kind != b'u' {
        return Err(PyValueError::new_err(format!(
            "{WHAT} must hold integer vertex indices, got {}",
            array.dtype()
        )));
    }
    let wide = array.call_method1("astype", ("int64",))?;
    let rows: Vec<[i64; 3]> = {
        if array.ndim() != 2 || array.shape()[1] != 3 {
            return Err(PyValueError::new_err(format!(
                "{WHAT} must be an array of shape (F, 3), got shape {:?}",
                array.shape()
            )));
        }
        let a = wide.cast::<PyArray2<i64>>()?.try_readonly()?;
        a.as_array()
            .rows()
            .into_iter()
            .map(|r| [r[0], r[1], r[2]])
            .collect()
    };
    rows.iter()
        .enumerate()
        .map(|(i, t)| {
            let out = t.map(|v| u32::try_from(v).ok());
            match out {
                [Some(a), Some(b), Some(c)] => Ok([a, b, c]),
                _ => Err(PyValueError::new_err(format!(
                    "{WHAT}: triangle {i} has the vertex index {}, negative or beyond 32 bits",
                    t.iter().find(|&&v| u32::try_from(v).is_err()).unwrap()
                ))),
            }
        })
        .collect()
}
