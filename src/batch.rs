//! A run over many frames: one mesh per input file, each written whole or not at all, a failing
//! frame reported without stopping the others.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};

use splash_sph::io::{self, VertexAttributes};
use splash_sph::iso::{self, IsoRequest};
use splash_sph::{
    Attribute, Config, FrameStats, InputFormat, MeshFormat, Particles, Reconstructor, TriMesh,
    attribute_names, estimate_spacing, read_particles,
};

use crate::memory::reconstruct_measured;
use crate::sequence::{Shard, frame_number, padded_stem, path_frame_number};

/// Frame numbers in directory output names are zero-padded to this many digits, as Blender's
/// sequence importers expect (`fluid_0001.obj`).
pub const FRAME_DIGITS: usize = 4;

/// Where the meshes go.
#[derive(Debug, Clone)]
pub enum Output {
    /// Beside each input, as `{stem}_surface.{ext}`.
    BesideInput,
    /// Into a directory, as `{stem}.{ext}`, the stem's frame number padded to
    /// [`FRAME_DIGITS`] digits (`f_9.ply` → `f_0009.obj`).
    Directory(PathBuf),
    /// A file name with `{stem}` and/or `{frame}` (`{frame:04}` pads to 4 digits) replaced per
    /// frame; a plain name is allowed for a single input.
    Pattern(String),
}

impl Output {
    /// `-o` as a user writes it: a trailing separator or an existing directory means a
    /// directory.
    pub fn parse(text: &str) -> Output {
        if text.ends_with('/')
            || text.ends_with(std::path::MAIN_SEPARATOR)
            || Path::new(text).is_dir()
        {
            Output::Directory(PathBuf::from(text))
        } else {
            Output::Pattern(text.to_string())
        }
    }

    /// The mesh format a file name asks for by its extension.
    pub fn format_hint(&self) -> Option<MeshFormat> {
        match self {
            Output::Pattern(p) => MeshFormat::from_path(Path::new(p)),
            _ => None,
        }
    }

    /// The extension of an output file name, if it has one.
    pub fn extension(&self) -> Option<String> {
        match self {
            Output::Pattern(p) => Some(Path::new(p).extension()?.to_string_lossy().into_owned()),
            _ => None,
        }
    }

    fn path_for(&self, input: &Path, format: MeshFormat) -> Result<PathBuf> {
        self.path_with(input, "_surface", format.extension())
    }

    /// The output of `input` for files of extension `ext`; beside the input its name is
    /// `{stem}{suffix}.{ext}`.
    pub fn path_with(&self, input: &Path, suffix: &str, ext: &str) -> Result<PathBuf> {
        let stem = crate::sequence::input_stem(input)
            .ok_or_else(|| anyhow!("{}: no file name", input.display()))?;
        Ok(match self {
            Output::BesideInput => input.with_file_name(format!("{stem}{suffix}.{ext}")),
            Output::Directory(dir) => {
                dir.join(format!("{}.{ext}", padded_stem(&stem, FRAME_DIGITS)))
            }
            Output::Pattern(p) => PathBuf::from(expand_pattern(p, &stem)?),
        })
    }
}

fn expand_pattern(pattern: &str, stem: &str) -> Result<String> {
    let mut out = pattern.replace("{stem}", stem);
    while let Some(start) = out.find("{frame") {
        let end = start
            + out[start..]
                .find('}')
                .ok_or_else(|| anyhow!("unclosed '{{frame' in output pattern '{pattern}'"))?;
        let spec = &out[start + "{frame".len()..end];
        let width = match spec.strip_prefix(':') {
            None if spec.is_empty() => 0,
            Some(w) => w
                .parse::<usize>()
                .map_err(|_| anyhow!("bad '{{frame{spec}}}' in output pattern '{pattern}': use {{frame}} or {{frame:04}}"))?,
            None => bail!("bad '{{frame{spec}}}' in output pattern '{pattern}'"),
        };
        let number = frame_number(stem).ok_or_else(|| {
            anyhow!("'{stem}' has no frame number for the output pattern '{pattern}'")
        })?;
        out.replace_range(start..=end, &format!("{number:0width$}"));
    }
    Ok(out)
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    }
}

pub struct Batch {
    /// The selected frames, in frame order: the whole sequence, before sharding.
    pub inputs: Vec<PathBuf>,
    pub input_format: Option<InputFormat>,
    pub output: Output,
    /// The mesh format: the configuration's, else the one the output name implies.
    pub format: MeshFormat,
    /// Everything else: the reconstruction, and the up axis and attributes of the output.
    pub config: Config,
    /// This job's part of the sequence; None: all of it.
    pub shard: Option<Shard>,
    /// Leaves frames whose output exists alone. Outputs are renamed into place whole, so an
    /// existing output is complete; an interrupted write leaves only a hidden temporary.
    pub skip_existing: bool,
    /// Stops at the first failing frame instead of going on with the others.
    pub fail_fast: bool,
    /// An isosurface of a particle quantity per frame (`splash iso`) instead of the surface.
    pub iso: Option<IsoRequest>,
}

/// What happened to one frame: its figures `S` (recon's [`FrameStats`], preview's) or error.
pub struct FrameOutcome<S = FrameStats> {
    pub input: PathBuf,
    pub output: PathBuf,
    /// Frame number from the input's name.
    pub frame: Option<u64>,
    pub result: Result<S>,
}

/// This job's share of the sequence, known before any frame is read.
#[derive(Debug, Clone)]
pub struct Plan {
    /// Frames selected (by the inputs and --frames).
    pub selected: usize,
    pub shard: Option<Shard>,
    /// Frames of this shard.
    pub assigned: usize,
    /// Frames of this shard whose output exists, left alone.
    pub skipped: Vec<PathBuf>,
    /// Frames to reconstruct.
    pub to_do: usize,
}

/// The end of a run.
pub struct RunReport<S = FrameStats> {
    pub plan: Plan,
    /// The frames attempted, in frame order.
    pub outcomes: Vec<FrameOutcome<S>>,
    /// Frames not attempted because a frame failed with `fail_fast` set.
    pub not_attempted: usize,
}

impl<S> RunReport<S> {
    pub fn failed(&self) -> impl Iterator<Item = &FrameOutcome<S>> {
        self.outcomes.iter().filter(|o| o.result.is_err())
    }

    /// Every frame of this job has its output: written now or found complete.
    pub fn complete(&self) -> bool {
        self.not_attempted == 0 && self.failed().next().is_none()
    }
}

/// Messages for the user as the run goes on.
pub trait Progress<S = FrameStats> {
    fn started(&mut self, _plan: &Plan) {}
    fn spacing_estimated(&mut self, from: &Path, spacing: f32);
    /// Something that makes the output suspect, about frame `input` or the run (None).
    fn warning(&mut self, input: Option<&Path>, message: &str);
    fn frame_done(&mut self, outcome: &FrameOutcome<S>, done: usize, total: usize);
}

impl Batch {
    /// Output paths of all frames, checked for collisions before any work starts.
    pub fn outputs(&self) -> Result<Vec<PathBuf>> {
        let outputs: Vec<PathBuf> = self
            .inputs
            .iter()
            .map(|i| self.output.path_for(i, self.format))
            .collect::<Result<_>>()?;
        if let Output::Pattern(p) = &self.output
            && self.inputs.len() > 1
            && !p.contains("{stem}")
            && !p.contains("{frame")
        {
            bail!(
                "-o {p} names one file for {} inputs: give a directory (ending in /) or a pattern with {{stem}} or {{frame:04}}",
                self.inputs.len()
            );
        }
        for (input, output) in self.inputs.iter().zip(&outputs) {
            if self.inputs.iter().any(|i| same_file(i, output)) {
                bail!(
                    "the mesh of {} would overwrite the input {}: choose another -o or --format",
                    input.display(),
                    output.display()
                );
            }
        }
        let mut sorted: Vec<(&PathBuf, &PathBuf)> = outputs.iter().zip(&self.inputs).collect();
        sorted.sort();
        for w in sorted.windows(2) {
            if w[0].0 == w[1].0 {
                bail!(
                    "{} and {} would both be written to {}",
                    w[0].1.display(),
                    w[1].1.display(),
                    w[0].0.display()
                );
            }
        }
        Ok(outputs)
    }

    /// Reconstructs this job's frames in frame order.
    pub fn run(&self, progress: &mut dyn Progress) -> Result<RunReport> {
        // Every output of the whole sequence is checked, so that all shards agree.
        let outputs = self.outputs()?;
        self.config.validate()?;
        if !self.config.output.attributes.is_empty() && !self.format.holds_attributes() {
            bail!(
                "--attributes {} needs PLY, VTK, VTU or VTP output (--format ply, ply-ascii, vtk, \
                 vtu or vtp): .{} files have no place for vertex attributes",
                self.config.output.attributes.join(","),
                self.format.extension()
            );
        }
        let assigned: Vec<usize> = (0..self.inputs.len())
            .filter(|&i| self.shard.is_none_or(|s| s.takes(i)))
            .collect();
        let (skipped, to_do): (Vec<usize>, Vec<usize>) = assigned
            .iter()
            .partition(|&&i| self.skip_existing && outputs[i].is_file());
        let plan = Plan {
            selected: self.inputs.len(),
            shard: self.shard,
            assigned: assigned.len(),
            skipped: skipped.iter().map(|&i| self.inputs[i].clone()).collect(),
            to_do: to_do.len(),
        };
        // A directory that cannot take the meshes fails the run now, not after each frame's
        // reconstruction.
        let mut dirs: Vec<&Path> = to_do.iter().map(|&i| output_dir(&outputs[i])).collect();
        dirs.sort();
        dirs.dedup();
        for dir in dirs {
            check_writable(dir)?;
        }
        progress.started(&plan);
        let mut reconstructor = None;
        let mut spacing = self.config.spacing;
        if spacing.is_none()
            && let Some(&first) = to_do.first()
        {
            // The spacing comes from the sequence's first frame, whichever frames this job
            // does, so that every shard and every restart uses the same grid.
            spacing = self.reference_spacing(&self.inputs[..first], progress);
        }
        let mut outcomes = Vec::with_capacity(to_do.len());
        let mut not_attempted = 0;
        // The given spacing is compared with the first reconstructed frame's particles.
        let mut checked = self.config.spacing.is_none();
        for (k, &i) in to_do.iter().enumerate() {
            let input = &self.inputs[i];
            let output = outputs[i].clone();
            let result = self.frame(
                input,
                &output,
                &mut spacing,
                &mut reconstructor,
                &mut checked,
                progress,
            );
            let outcome = FrameOutcome {
                input: input.clone(),
                output,
                frame: path_frame_number(input),
                result,
            };
            progress.frame_done(&outcome, k + 1, to_do.len());
            let failed = outcome.result.is_err();
            outcomes.push(outcome);
            if failed && self.fail_fast {
                not_attempted = to_do.len() - k - 1;
                break;
            }
        }
        Ok(RunReport {
            plan,
            outcomes,
            not_attempted,
        })
    }

    /// The spacing estimated from the first readable, non-empty frame of `earlier` (frames
    /// before this job's first one), as a run over the whole sequence would estimate it.
    fn reference_spacing(&self, earlier: &[PathBuf], progress: &mut dyn Progress) -> Option<f32> {
        for input in earlier {
            // A bad frame is reported by the job that owns it.
            let Ok(Particles { positions, .. }) = read_particles(input, self.input_format) else {
                continue;
            };
            if positions.is_empty() {
                continue;
            }
            let r = estimate_spacing(&positions)?;
            progress.spacing_estimated(input, r);
            return Some(r);
        }
        None
    }

    fn frame(
        &self,
        input: &Path,
        output: &Path,
        spacing: &mut Option<f32>,
        reconstructor: &mut Option<Reconstructor>,
        checked: &mut bool,
        progress: &mut dyn Progress,
    ) -> Result<FrameStats> {
        let start = Instant::now();
        let mut frame = read_particles(input, self.input_format)?;
        let outside_box = match self.config.particle_aabb {
            Some(aabb) => frame.retain_in_box(aabb),
            None => 0,
        };
        let Particles {
            positions: particles,
            attributes,
        } = frame;
        if let Some(request) = &self.iso {
            let read = start.elapsed();
            let mut stats = self.iso_frame(
                input, output, request, particles, attributes, spacing, progress,
            )?;
            stats.timings.read = read;
            stats.particles_outside_box = outside_box;
            return Ok(stats);
        }
        let wanted = particle_attributes(input, attributes, &self.config.output.attributes)?;
        let read = start.elapsed();
        if particles.is_empty() {
            // Nothing to reconstruct, and nothing to estimate a spacing from.
            let mut empty: Vec<(String, Attribute)> = wanted
                .iter()
                .map(|(name, a)| {
                    let empty = match a {
                        Attribute::Scalar(_) => Attribute::Scalar(Vec::new()),
                        Attribute::Vector(_) => Attribute::Vector(Vec::new()),
                    };
                    (name.clone(), empty)
                })
                .collect();
            self.write_mesh(output, &mut TriMesh::default(), &mut empty)?;
            let mut stats = FrameStats::default();
            stats.timings.read = read;
            stats.particles_outside_box = outside_box;
            return Ok(stats);
        }
        let r = sequence_spacing(input, &particles, spacing, progress)?;
        // One reconstructor, hence one thread pool, for the whole run.
        let reconstructor = match reconstructor {
            Some(rec) => rec,
            None => reconstructor.insert(Reconstructor::new(Config {
                spacing: Some(r),
                // The CLI runs in its global pool, sized by the same setting.
                threads: None,
                ..self.config.clone()
            })?),
        };
        if !*checked {
            *checked = true;
            for warning in reconstructor.warnings(&particles) {
                progress.warning(Some(input), &warning);
            }
        }
        let rec =
            reconstruct_measured(reconstructor, &particles).context("reconstruction failed")?;
        let mut mesh = rec.mesh;
        let columns: Vec<&Attribute> = wanted.iter().map(|(_, a)| a).collect();
        let interpolated = reconstructor.interpolate_all(&mesh, &particles, &columns)?;
        drop(columns);
        let names = wanted.into_iter().map(|(name, _)| name);
        let mut vertex_attributes: Vec<(String, Attribute)> = names.zip(interpolated).collect();
        drop(particles);
        let start = Instant::now();
        self.write_mesh(output, &mut mesh, &mut vertex_attributes)?;
        let mut stats = rec.stats;
        stats.particles_outside_box = outside_box;
        stats.timings.read = read;
        stats.timings.write = start.elapsed();
        Ok(stats)
    }
}

impl Batch {
    /// Writes a frame's mesh and its vertex attributes, turned upright if asked, whole or not
    /// at all.
    fn write_mesh(
        &self,
        output: &Path,
        mesh: &mut TriMesh,
        named: &mut [(String, Attribute)],
    ) -> Result<()> {
        if let Some(axis) = self.config.output.up_axis {
            axis.rotate_mesh(mesh, named);
        }
        let attributes = VertexAttributes {
            named,
            ..Default::default()
        };
        Ok(io::write_mesh_file_with(
            output,
            mesh,
            &attributes,
            self.format,
        )?)
    }

    /// One frame's isosurface, written with its extra attributes.
    #[allow(clippy::too_many_arguments)]
    fn iso_frame(
        &self,
        input: &Path,
        output: &Path,
        request: &IsoRequest,
        particles: Vec<splash_sph::Vec3>,
        attributes: BTreeMap<String, Attribute>,
        spacing: &mut Option<f32>,
        progress: &mut dyn Progress,
    ) -> Result<FrameStats> {
        let r = match *spacing {
            None if particles.is_empty() => 1.0,
            _ => sequence_spacing(input, &particles, spacing, progress)?,
        };
        let config = Config {
            spacing: Some(r),
            // The CLI runs in its global pool, sized by the same setting.
            threads: None,
            ..self.config.clone()
        };
        let surface = iso::extract(&particles, attributes, request, &config)
            .with_context(|| format!("'{}'", input.display()))?;
        let (mut mesh, mut named) = (surface.mesh, surface.attributes);
        let start = Instant::now();
        self.write_mesh(output, &mut mesh, &mut named)?;
        let mut stats = FrameStats {
            spacing: r,
            cell: surface.stats.cell,
            particles: particles.len(),
            triangles: mesh.triangles.len(),
            vertices: mesh.vertices.len(),
            iso: Some(surface.stats),
            peak_rss: crate::memory::peak_rss().unwrap_or(0),
            ..FrameStats::default()
        };
        stats.timings.write = start.elapsed();
        Ok(stats)
    }
}

/// The directory a mesh is written into.
fn output_dir(output: &Path) -> &Path {
    match output.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    }
}

/// Creates `dir` if needed and writes (and removes) a small file in it.
fn check_writable(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| {
        anyhow!(
            "cannot create the output directory '{}': {e}; no frame was reconstructed",
            dir.display()
        )
    })?;
    let probe = dir.join(format!(".splash-write-check-{}", std::process::id()));
    let written = std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .open(&probe);
    let _ = std::fs::remove_file(&probe);
    written.map_err(|e| {
        anyhow!(
            "cannot write in the output directory '{}': {e}; no frame was reconstructed",
            dir.display()
        )
    })?;
    Ok(())
}

/// The attributes `names` (canonical spellings) of frame `input`, found through the alias
/// table, in the order asked; the frame's other attributes are dropped.
fn particle_attributes(
    input: &Path,
    mut attributes: BTreeMap<String, Attribute>,
    names: &[String],
) -> Result<Vec<(String, Attribute)>> {
    let mut out = Vec::with_capacity(names.len());
    for name in names {
        let Some(attribute) = attribute_names::take(&mut attributes, name) else {
            let mut has: Vec<&str> = attributes.keys().map(String::as_str).collect();
            has.extend(out.iter().map(|(n, _): &(String, Attribute)| n.as_str()));
            has.sort_unstable();
            let shown: Vec<&str> = has.iter().take(12).copied().collect();
            bail!(
                "'{}' has no particle attribute '{name}'; it has {}{}",
                input.display(),
                if has.is_empty() {
                    "none".to_string()
                } else {
                    shown.join(", ")
                },
                if has.len() > shown.len() {
                    format!(" and {} more", has.len() - shown.len())
                } else {
                    String::new()
                }
            );
        };
        // The reader leaves attributes as they are; interpolated, one of these would spread.
        let bad = match &attribute {
            Attribute::Scalar(s) => s
                .iter()
                .position(|x| !x.is_finite())
                .map(|i| (i, s[i].to_string())),
            Attribute::Vector(v) => v
                .iter()
                .position(|x| !x.is_finite())
                .map(|i| (i, format!("({}, {}, {})", v[i].x, v[i].y, v[i].z))),
        };
        if let Some((i, value)) = bad {
            let what = if name == "velocity" {
                "velocities"
            } else {
                name
            };
            bail!(
                "cannot read {what} from '{}': particle {i} has a non-finite {name} {value}",
                input.display()
            );
        }
        out.push((name.clone(), attribute));
    }
    Ok(out)
}

/// The sequence's spacing: the one given or found on an earlier frame, else estimated from this
/// frame's particles and kept, so that the whole sequence shares one spacing, hence one grid.
fn sequence_spacing(
    input: &Path,
    particles: &[splash_sph::Vec3],
    spacing: &mut Option<f32>,
    progress: &mut dyn Progress,
) -> Result<f32> {
    if let Some(r) = *spacing {
        return Ok(r);
    }
    let r = estimate_spacing(particles).ok_or_else(|| {
        anyhow!(
            "cannot estimate the particle spacing from {} particles; give --spacing or --particle-radius",
            particles.len()
        )
    })?;
    progress.spacing_estimated(input, r);
    *spacing = Some(r);
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_expand() {
        assert_eq!(
            expand_pattern("m/{stem}.obj", "frame_7").unwrap(),
            "m/frame_7.obj"
        );
        assert_eq!(
            expand_pattern("m/f_{frame:04}.obj", "frame_7").unwrap(),
            "m/f_0007.obj"
        );
        assert_eq!(expand_pattern("{frame}.ply", "x12").unwrap(), "12.ply");
        assert!(expand_pattern("{frame:x}.ply", "x12").is_err());
        assert!(expand_pattern("{frame}.ply", "nodigits").is_err());
    }
}
