//! `reconstruct`: numpy positions to a `Mesh`, with the GIL released while the library works.

use std::time::{Duration, Instant};

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use splash_sph::pipeline::{self, FrameParticles};
use splash_sph::temporal::Followed;
use splash_sph::{
    Attribute as ParticleAttribute, Clock, Config, FrameStats, Reconstructor, TriMesh, Vec3,
};

use crate::arrays::{self, Points};
use crate::errors::to_py;
use crate::mesh::Mesh;
use crate::settings::{self, Overrides, options_function};

/// A per-particle attribute to carry onto the vertices. Scalars ride in the x of a vector:
/// the interpolation is a weighted mean per component.
struct Attribute<'py> {
    name: String,
    values: Points<'py>,
    scalar: bool,
}

/// What the library computed, with the times the report adds to its stage times.
struct Output {
    mesh: TriMesh,
    stats: FrameStats,
    attributes: Vec<Vec<Vec3>>,
    interpolation: Duration,
    followed: Option<Followed>,
    total: Duration,
}

options_function! {
/// The closed surface mesh of SPH particles.
///
/// ``positions``: an (N, 3) floating-point array, C- or F-ordered or a strided view. A
/// C-contiguous float32 array is read in place (leave it unchanged until the call returns),
/// others are copied once as float32; anything that ``numpy.asarray`` makes such an array of is
/// accepted, integer arrays are refused. Coordinates must be finite. An empty (0, 3) array
/// gives an empty mesh.
///
/// ``spacing``: Particle spacing r, the simulator's equilibrium distance between particles,
/// in world units. Required unless the config gives it: it is never guessed (see
/// ``estimate_spacing``).
///
/// Keyword arguments override the config (None leaves its value); each is the option of the
/// command line's flag of the same name (``--max-memory`` for ``max_memory``), where a number
/// is a length in world units:
///
/// - ``cell``: Marching Cubes cell size: 2r, r, r/2, r/N, Kr or a length; at most 4r.
///   Default ``"r/2"``.
/// - ``field``: Scalar field: ssp07, zb05, density, blobby, metaball or anisotropic, with its
///   default parameters unless the configuration gives the same kind. Default ``"ssp07"``.
/// - ``engine``: Reconstruction engine: narrow-band, full-gather, scatter or slices. Default
///   ``"narrow-band"``. full-gather, scatter and slices give the same surface, and the narrow
///   band too but for the blobs of a cell or two beyond its band at small cells, which it
///   misses (1 of 55 components on cbd-small frame 40 at cell r/2;
///   docs/reference/recon.md, Engines).
/// - ``normals``: Vertex normals: field (the field's gradient), grid (differences of the
///   sampled grid: faster) or none. Default ``"field"``.
/// - ``correct``: Newton steps moving each vertex along its cube edge onto the field's exact
///   isosurface (Marching Correctors); 0 keeps Marching Cubes' linear interpolation. Default
///   0; 3 is plenty.
/// - ``block``: Cubes per side of a block of the slices engine. Default 64.
/// - ``threads``: Worker threads, all cores when not given; the mesh does not depend on it.
///   Each calling thread keeps its workers for its next calls.
/// - ``max_memory``: Heap a frame may plan to use, e.g. 8G or 512M: every engine refuses a
///   frame that needs more. In bytes or as ``"8G"``.
/// - ``raw``: Keep the field's exact isosurface: no smoothing and no volume restoration.
///   ``raw=True`` skips the default post-processing (smoothing, each part given its
///   particles' volume N·r³; ``postprocess`` runs it on any mesh).
/// - ``volume_scope``: What the volume restoration brings to N·r³: frame (the whole mesh, one
///   offset) or component (each closed part to its own particles). Default ``"frame"``.
/// - ``decimate``: Decimate with quadric edge collapses, keeping every vertex and triangle
///   centre within this distance of the full surface: ``"0.1r"`` or a number.
/// - ``min_component``: Drop the parts of the mesh enclosing less than this many particle
///   volumes r³.
/// - ``mesh_aabb``: Keep only the mesh inside this box (min x, min y, min z, max x, max y,
///   max z); the cuts are capped, so it stays closed.
///
/// ``config``: a TOML file's path (as ``splash recon --config`` reads) or a dict shaped like
/// it (see ``default_config``). Its ``output.format`` and ``output.up_axis`` become the
/// defaults of ``Mesh.write``.
///
/// ``attributes``: per-particle values to carry onto the vertices, name -> (N, 3) or (N,)
/// array, interpolated as ``splash recon --attributes velocity`` does (the mean of the
/// particles within the field's support, weighted by the SSP07 kernel); they come back in
/// ``Mesh.attributes``.
///
/// ``ids`` and ``neighbours``: to make the surface follow the fluid from frame to frame, as
/// ``recon_sequence(temporal=True)`` does (issue 38): ``ids`` an (N,) integer array of the
/// particles' unique identities, ``neighbours`` the frames before and after as
/// ``((positions, ids), (positions, ids))``. The three frames are reconstructed (about three
/// times the work): this frame's field is averaged with its neighbours' where the particles
/// matched by id carry each vertex, and its surface moves towards their surfaces carried to its
/// time; particles without a match do not carry it. With
/// ``raw=True`` nothing follows. ``Mesh.report["followed"]`` gives the vertices ``moved`` and
/// the ``rms`` and ``max`` move in world units.
///
/// ``Mesh.report`` holds the counts (``particles``, ``surface_particles``, ``vertices``,
/// ``triangles``, ...), ``spacing`` and ``cell`` in world units, ``engine``, ``field``,
/// ``threads``, ``correction`` (with ``correct``: vertices ``moved``, their ``shift_mean`` and
/// ``shift_max`` in edge lengths, |f − iso| ``residual_before_mean``/``_max`` and
/// ``residual_after_mean``/``_max``), and ``times``: seconds per stage (``handler_array``,
/// ``surface_particles``, ``band``, ``scalar_field``, ``triangulation``, ``post`` (the
/// post-processing; 0 with ``raw=True`` and no ``decimate``, ``min_component`` or
/// ``mesh_aabb``), their sum ``reconstruction``, ``attributes``, and ``total`` for all the
/// native work).
///
/// The GIL is released while the library works: Python threads can reconstruct frames in
/// parallel. Raises ValueError for a bad array, bad settings (naming the key or value),
/// non-finite coordinates (naming the particle) or a grid over the memory limit; OSError when
/// the config file cannot be read.
fn reconstruct<'py>(
    py: Python<'py>,
    positions: &Bound<'py, PyAny>,
    spacing: Option<f32>,
) signature(positions, spacing=None, *,)
    then(config: Option<&Bound<'py, PyAny>>, attributes: Option<&Bound<'py, PyAny>>,
        ids: Option<&Bound<'py, PyAny>>, neighbours: Option<&Bound<'py, PyAny>>)
    -> PyResult<Mesh>, |options| {
    let overrides = Overrides { spacing, ..options };
    let config = settings::resolve(config, overrides)?;
    if config.spacing.is_none() {
        return Err(PyValueError::new_err(
            "the particle spacing is not set: pass spacing=r (the simulation's particle \
             spacing) or give spacing in the config; splash_sph.estimate_spacing(positions) \
             estimates it",
        ));
    }
    let points = arrays::points(positions, "positions")?;
    let attributes = attribute_values(attributes, points.as_slice().len())?;
    let frames = neighbour_frames(ids, neighbours)?;
    let (format, up_axis) = (config.output.format, config.output.up_axis);
    let (engine, field) = (config.engine.name(), config.field.kind());

    let positions = points.as_slice();
    let values: Vec<&[Vec3]> = attributes.iter().map(|a| a.values.as_slice()).collect();
    let frames = frames.as_ref().map(|n| {
        let frame = |positions, ids| FrameParticles { positions, ids };
        [
            frame(n.before.0.as_slice(), &n.before.1[..]),
            frame(positions, &n.ids[..]),
            frame(n.after.0.as_slice(), &n.after.1[..]),
        ]
    });
    let out = py
        .detach(|| run(config, positions, &values, frames))
        .map_err(to_py)?;

    let report = report(py, &out, engine, field)?;
    if let Some(f) = &out.followed {
        let followed = PyDict::new(py);
        followed.set_item("moved", f.moved)?;
        followed.set_item("rms", f.rms)?;
        followed.set_item("max", f.max)?;
        report.set_item("followed", followed)?;
    }
    let mesh_attributes = PyDict::new(py);
    for (a, values) in attributes.iter().zip(out.attributes) {
        if a.scalar {
            let values = values.iter().map(|v| v.x).collect();
            mesh_attributes.set_item(&a.name, arrays::scalars_array(py, values))?;
        } else {
            mesh_attributes.set_item(&a.name, arrays::points_array(py, values))?;
        }
    }
    Ok(Mesh::new(
        py,
        out.mesh,
        mesh_attributes,
        report,
        format,
        up_axis,
    ))
}
}

/// This frame's ids and its neighbours' positions and ids, for following the fluid.
struct Neighbours<'py> {
    ids: Vec<u32>,
    before: (Points<'py>, Vec<u32>),
    after: (Points<'py>, Vec<u32>),
}

/// `ids` and `neighbours` checked: both or neither.
fn neighbour_frames<'py>(
    ids: Option<&Bound<'py, PyAny>>,
    neighbours: Option<&Bound<'py, PyAny>>,
) -> PyResult<Option<Neighbours<'py>>> {
    let (ids, neighbours) = match (ids, neighbours) {
        (None, None) => return Ok(None),
        (Some(ids), Some(n)) => (ids, n),
        _ => {
            return Err(PyValueError::new_err(
                "ids and neighbours go together: pass this frame's particle ids with the \
                 frames before and after as neighbours=((positions, ids), (positions, ids))",
            ));
        }
    };
    let pair: (Bound<'py, PyAny>, Bound<'py, PyAny>) = neighbours.extract().map_err(|_| {
        PyTypeError::new_err(
            "neighbours must be the frames before and after: ((positions, ids), (positions, ids))",
        )
    })?;
    let frame = |f: &Bound<'py, PyAny>, side: &str| -> PyResult<(Points<'py>, Vec<u32>)> {
        let (p, i): (Bound<'py, PyAny>, Bound<'py, PyAny>) = f.extract().map_err(|_| {
            PyTypeError::new_err(format!("neighbours' frame {side} must be (positions, ids)"))
        })?;
        let points = arrays::points(&p, &format!("the positions of the frame {side}"))?;
        let ids = arrays::ids(&i, &format!("the ids of the frame {side}"))?;
        Ok((points, ids))
    };
    Ok(Some(Neighbours {
        ids: arrays::ids(ids, "ids")?,
        before: frame(&pair.0, "before")?,
        after: frame(&pair.1, "after")?,
    }))
}

fn run(
    mut config: Config,
    positions: &[Vec3],
    attributes: &[&[Vec3]],
    frames: Option<[FrameParticles<'_>; 3]>,
) -> splash_sph::Result<Output> {
    let start = Instant::now();
    // The library would start a pool of its own for every call.
    let threads = config.threads.take();
    let reconstructor = Reconstructor::new(config)?;
    splash_sph::install(threads, || {
        let columns: Vec<ParticleAttribute> = attributes
            .iter()
            .map(|values| ParticleAttribute::Vector(values.to_vec()))
            .collect();
        let columns: Vec<&ParticleAttribute> = columns.iter().collect();
        let (surface, followed) = match frames {
            None => (
                pipeline::surface(&reconstructor, positions, &columns, &mut Clock::default())?,
                None,
            ),
            Some(frames) => {
                let (surface, followed) = pipeline::surface_following(
                    &reconstructor,
                    frames,
                    &columns,
                    &mut Clock::default(),
                )?;
                (surface, Some(followed))
            }
        };
        let attributes = surface
            .attributes
            .into_iter()
            .map(|a| match a {
                ParticleAttribute::Vector(v) => v,
                ParticleAttribute::Scalar(_) => unreachable!("vectors in, vectors out"),
            })
            .collect();
        Ok(Output {
            mesh: surface.mesh,
            stats: surface.stats,
            attributes,
            interpolation: surface.interpolation,
            followed,
            total: start.elapsed(),
        })
    })?
}

/// The report's counts, lengths and times (seconds).
fn report<'py>(
    py: Python<'py>,
    out: &Output,
    engine: &str,
    field: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let s: &FrameStats = &out.stats;
    let t = &s.timings;
    let times = PyDict::new(py);
    for (name, d) in [
        ("handler_array", t.handler_array),
        ("surface_particles", t.surface_particles),
        ("band", t.band),
        ("scalar_field", t.scalar_field),
        ("triangulation", t.triangulation),
        ("post", t.post),
        ("reconstruction", t.reconstruction()),
        ("attributes", out.interpolation),
        ("total", out.total),
    ] {
        times.set_item(name, d.as_secs_f64())?;
    }
    let report = PyDict::new(py);
    report.set_item("particles", s.particles)?;
    report.set_item("surface_particles", s.surface_particles)?;
    report.set_item("vertices", s.vertices)?;
    report.set_item("triangles", s.triangles)?;
    report.set_item("surface_vertices", s.surface_vertices)?;
    report.set_item("closure_vertices", s.closure_vertices)?;
    report.set_item("deferred_values", s.deferred_values)?;
    report.set_item("flow_mean_vertices", s.flow_mean_vertices)?;
    report.set_item("surface_cells", s.surface_cells)?;
    report.set_item("bricks", s.bricks)?;
    report.set_item("grid", s.grid)?;
    report.set_item("spacing", as_written(s.spacing))?;
    report.set_item("cell", as_written(s.cell))?;
    report.set_item("engine", engine)?;
    report.set_item("field", field)?;
    report.set_item("threads", s.threads)?;
    report.set_item("peak_bytes", s.peak_bytes)?;
    let c = &s.correction;
    let correction = PyDict::new(py);
    correction.set_item("vertices", c.vertices)?;
    correction.set_item("moved", c.moved)?;
    correction.set_item("shift_mean", c.shift_mean)?;
    correction.set_item("shift_max", c.shift_max)?;
    correction.set_item("residual_before_mean", c.residual_before_mean)?;
    correction.set_item("residual_before_max", c.residual_before_max)?;
    correction.set_item("residual_after_mean", c.residual_after_mean)?;
    correction.set_item("residual_after_max", c.residual_after_max)?;
    report.set_item("correction", correction)?;
    report.set_item("times", times)?;
    Ok(report)
}

/// The float whose shortest decimal form is `x`'s (0.014, not 0.014000000432133675), so that
/// the report gives back the spacing as it was passed.
pub(crate) fn as_written(x: f32) -> f64 {
    x.to_string()
        .parse()
        .expect("a float's decimal form parses")
}

/// The attributes dict as (name, values), checked against the number of particles.
fn attribute_values<'py>(
    attributes: Option<&Bound<'py, PyAny>>,
    particles: usize,
) -> PyResult<Vec<Attribute<'py>>> {
    let Some(attributes) = attributes else {
        return Ok(Vec::new());
    };
    let dict = attributes
        .cast::<PyDict>()
        .map_err(|_| PyTypeError::new_err("attributes must be a dict: name -> array"))?;
    let mut out = Vec::new();
    for (name, array) in dict.iter() {
        let name: String = name.extract()?;
        let what = format!("attributes['{name}']");
        let scalar = arrays::is_scalar(&array)?;
        let values = if scalar {
            let x = arrays::scalars(&array, &what)?;
            Points::Owned(x.into_iter().map(|s| Vec3::new(s, 0.0, 0.0)).collect())
        } else {
            arrays::points(&array, &what)?
        };
        let len = values.as_slice().len();
        if len != particles {
            return Err(PyValueError::new_err(format!(
                "{what} has {len} values for {particles} particles"
            )));
        }
        out.push(Attribute {
            name,
            values,
            scalar,
        });
    }
    Ok(out)
}
