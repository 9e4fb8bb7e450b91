//! `recon_sequence`: a whole sequence of particle files to mesh files with the library's
//! planner and frame pipeline, as `splash recon` runs it (same output names, shards,
//! `skip_existing`, bytes); and `frame_number`, the rule that numbers frames.

use std::path::{Path, PathBuf};

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};
use splash_sph::frames::{self, Output, Shard};
use splash_sph::pipeline::{Batch, FrameOutcome, Plan, Progress, RunReport};
use splash_sph::{FrameStats, InputFormat};

use crate::errors::to_py;
use crate::settings::{self, Overrides, options_function};

/// The frame number of a file: the last run of digits in its name without the extension
/// (``frame_0042.ply`` → 42, ``fluid.0007.bgeo.gz`` → 7), as ``splash recon`` numbers and
/// orders frames; None for a name without digits.
#[pyfunction]
pub fn frame_number(path: PathBuf) -> Option<u64> {
    frames::path_frame_number(&path)
}

options_function! {
/// Reconstructs a sequence of particle files into mesh files, as ``splash recon`` does.
///
/// ``inputs``: a particle file, a directory of them (its frame sequence), a glob pattern
/// (``"sim/frame_*.ply"``), or a list of these. Frames run in frame-number order.
///
/// ``output``: a directory (ending in ``/``, or existing; frame numbers in names padded to 4
/// digits), or a pattern with ``{stem}``, ``{frame}`` or ``{frame:04}``
/// (``"mesh/fluid_{frame:04}.ply"``); a plain file name for a single input. The mesh format
/// comes from ``format``, else the name's extension, else OBJ.
///
/// ``progress(done, total, frame_report)`` is called after each frame; an exception raised in
/// it stops the run and is raised again. ``frames``: frame numbers to keep, ``"1-10,20,
/// 30-40x5"``. ``shard``: ``"K/N"`` (this job takes every N-th frame from the K-th) or
/// ``"auto/N"`` (K from ``SLURM_ARRAY_TASK_ID``). ``skip_existing``: leave frames whose output
/// exists alone. ``fail_fast``: stop at the first failing frame (by default it is reported
/// and the others go on).
/// ``input_format``: as the command line's ``--input-format``.
///
/// The options of files and sequences, besides ``reconstruct``'s:
///
/// - ``particle_aabb``: Drop the particles outside this box (min x, min y, min z, max x, max
///   y, max z) before reconstructing.
/// - ``format``: Mesh format: obj, ply, ply-ascii, pov, vtk, vtu, vtp, usd or vdb; from the
///   output's extension when not given, else obj. ``format="usd"`` also writes, after the
///   frames, the stage that plays their layers as one animated mesh, and takes the particles'
///   velocities whenever they have them.
/// - ``up_axis``: Rotate the mesh on output: z turns Y-up data Z-up, y turns Z-up data Y-up.
/// - ``attributes``: Particle attributes interpolated onto the mesh's vertices, by name
///   (velocity, density, …): a list of names or one comma-separated string; written to PLY,
///   VTK, VTU, VTP and USD.
/// - ``temporal``: In a sequence, average each frame's field and surface with its neighbouring
///   frames' carried by the fluid's motion (experimental). Less flicker for about 1.9× the
///   time; needs particle ids, or velocities with ``post.frame_time``; frames without both
///   neighbours are post-processed alone, with a warning.
///
/// The other keywords are ``reconstruct``'s; without ``spacing`` it is estimated once, on the
/// first frame of the whole selection, so that every shard uses one grid.
///
/// Returns the run report, a dict: ``selected``, ``shard`` (``"K/N"`` or None),
/// ``assigned``, ``skipped`` (inputs whose output existed), ``to_do``, ``written``,
/// ``failed`` (the failed frames' reports), ``not_attempted``, ``ok`` (every frame of this job
/// has its mesh), ``spacing``, ``warnings`` (strings) and ``frames``: a report per frame
/// attempted, with ``frame`` (number or None), ``input``, ``output``, ``status`` (``"ok"`` or
/// ``"error"``), and ``particles``, ``triangles``, ``vertices``, ``seconds`` and ``times``
/// (seconds: ``read``, ``reconstruction`` (of which ``post``: 0 with ``raw=True`` alone) and
/// ``write``, which add up to ``seconds``), or ``error``.
///
/// A failing frame does not raise: it is in ``failed``. Raises ValueError for bad settings,
/// inputs that select no frame or outputs that collide, OSError when an output directory
/// cannot be written, before any frame is reconstructed. The GIL is released between
/// ``progress`` calls.
fn recon_sequence<'py>(
    py: Python<'py>,
    inputs: &Bound<'py, PyAny>,
    output: &Bound<'py, PyAny>,
    progress: Option<Py<PyAny>>,
    frames: Option<String>,
    shard: Option<String>,
    skip_existing: bool,
    fail_fast: bool,
    input_format: Option<String>,
    spacing: Option<f32>,
) signature(inputs, output, *, progress=None, frames=None, shard=None, skip_existing=false,
    fail_fast=false, input_format=None, spacing=None,)
    then(config: Option<&Bound<'py, PyAny>>) files
    -> PyResult<Bound<'py, PyDict>>, |options| {
    let overrides = Overrides { spacing, ..options };
    let mut config = settings::resolve(config, overrides)?;
    let input_format = input_format
        .map(|f| InputFormat::parse(&f))
        .transpose()
        .map_err(to_py)?;
    let shard = shard
        .map(|s| Shard::from_env(&s))
        .transpose()
        .map_err(to_py)?;
    let output = Output::parse(&path_text(output, "output")?);
    let format = output.mesh_format(config.output.format).map_err(to_py)?;
    let inputs = input_paths(inputs)?;
    // Each frame runs on the caller's kept workers, as `reconstruct` does.
    let threads = config.threads.take();

    let mut events = Events {
        callback: progress,
        error: None,
        spacing: None,
        warnings: Vec::new(),
    };
    let run = py.detach(|| {
        let selection = frames::select(&inputs, frames.as_deref())?;
        events.warnings.extend(selection.warnings);
        let batch = Batch {
            inputs: selection.files,
            input_format,
            output,
            format,
            config,
            shard,
            skip_existing,
            fail_fast,
            iso: None,
        };
        splash_sph::install(threads, || batch.run(&mut events))?
    });
    if let Some(e) = events.error.take() {
        return Err(e);
    }
    let report = run.map_err(to_py)?;
    run_report(py, &report, &events)
}
}

/// The frame's report as `progress` and the run report give it.
fn frame_report<'py>(py: Python<'py>, o: &FrameOutcome) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("frame", o.frame)?;
    d.set_item("input", path_str(&o.input))?;
    d.set_item("output", path_str(&o.output))?;
    match &o.result {
        Ok(s) => {
            d.set_item("status", "ok")?;
            d.set_item("particles", s.particles)?;
            d.set_item("triangles", s.triangles)?;
            d.set_item("vertices", s.vertices)?;
            d.set_item("seconds", seconds(s))?;
            let t = &s.timings;
            let times = PyDict::new(py);
            for (name, d) in [
                ("read", t.read),
                ("reconstruction", t.reconstruction()),
                ("post", t.post),
                ("write", t.write),
            ] {
                times.set_item(name, d.as_secs_f64())?;
            }
            d.set_item("times", times)?;
        }
        Err(e) => {
            d.set_item("status", "error")?;
            d.set_item("error", e.to_string())?;
        }
    }
    Ok(d)
}

/// Reading, reconstructing and writing, as the command line's logs count a frame's time.
fn seconds(s: &FrameStats) -> f64 {
    let t = s.timings;
    (t.read + t.reconstruction() + t.write).as_secs_f64()
}

fn run_report<'py>(
    py: Python<'py>,
    report: &RunReport,
    events: &Events,
) -> PyResult<Bound<'py, PyDict>> {
    let plan: &Plan = &report.plan;
    let d = PyDict::new(py);
    d.set_item("selected", plan.selected)?;
    d.set_item("shard", plan.shard.map(|s| s.to_string()))?;
    d.set_item("assigned", plan.assigned)?;
    let skipped: Vec<String> = plan.skipped.iter().map(|p| path_str(p)).collect();
    d.set_item("skipped", skipped)?;
    d.set_item("to_do", plan.to_do())?;
    let frames = PyList::empty(py);
    let failed = PyList::empty(py);
    for o in &report.outcomes {
        let f = frame_report(py, o)?;
        if o.result.is_err() {
            failed.append(&f)?;
        }
        frames.append(f)?;
    }
    d.set_item("written", report.outcomes.len() - failed.len())?;
    d.set_item("failed", failed)?;
    d.set_item("not_attempted", report.not_attempted)?;
    d.set_item("ok", report.complete())?;
    d.set_item("spacing", events.spacing)?;
    d.set_item("warnings", events.warnings.clone())?;
    d.set_item("frames", frames)?;
    Ok(d)
}

/// The run's messages for Python: `progress` called per frame (with the GIL), the spacing
/// and warnings kept for the report, and the first exception of `progress` (or a
/// KeyboardInterrupt) stopping the run.
struct Events {
    callback: Option<Py<PyAny>>,
    error: Option<PyErr>,
    spacing: Option<f32>,
    warnings: Vec<String>,
}

impl Progress for Events {
    fn spacing_estimated(&mut self, _from: &Path, spacing: f32) {
        self.spacing = Some(spacing);
    }

    fn warning(&mut self, input: Option<&Path>, message: &str) {
        self.warnings.push(match input {
            Some(input) => format!("{}: {message}", input.display()),
            None => message.to_string(),
        });
    }

    fn frame_done(&mut self, outcome: &FrameOutcome, done: usize, total: usize) {
        if self.spacing.is_none()
            && let Ok(s) = &outcome.result
            && s.spacing > 0.0
        {
            self.spacing = Some(s.spacing);
        }
        let Some(callback) = &self.callback else {
            return;
        };
        if self.error.is_some() {
            return;
        }
        let called = Python::attach(|py| {
            let report = frame_report(py, outcome)?;
            callback.call1(py, (done, total, report)).map(drop)
        });
        self.error = called.err();
    }

    fn cancelled(&mut self) -> bool {
        if self.error.is_none() {
            self.error = Python::attach(|py| py.check_signals()).err();
        }
        self.error.is_some()
    }
}

fn path_str(path: &Path) -> String {
    path.to_string_lossy().into_owned()
}

/// A str or os.PathLike as text (a str keeps a trailing `/`, which marks a directory).
fn path_text(value: &Bound<'_, PyAny>, what: &str) -> PyResult<String> {
    if value.is_instance_of::<PyString>() {
        return value.extract();
    }
    let path: PathBuf = value
        .extract()
        .map_err(|_| PyTypeError::new_err(format!("{what} must be a str or os.PathLike")))?;
    Ok(path_str(&path))
}

/// One path or a list of them.
fn input_paths(inputs: &Bound<'_, PyAny>) -> PyResult<Vec<PathBuf>> {
    if let Ok(path) = path_text(inputs, "inputs") {
        return Ok(vec![PathBuf::from(path)]);
    }
    let items = inputs.try_iter().map_err(|_| {
        PyTypeError::new_err("inputs must be a path, a glob pattern or a list of them")
    })?;
    items
        .map(|item| Ok(PathBuf::from(path_text(&item?, "each input")?)))
        .collect()
}
