//! A run over many frames: one mesh per input file, each written whole or not at all, a failing
//! frame reported without stopping the others.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};

use crate::config::{Config, Params};
use crate::io::{self, InputFormat, MeshFormat};
use crate::mesh::TriMesh;
use crate::recon::{Engine, reconstruct};
use crate::report::FrameStats;
use crate::spacing::estimate_spacing;

/// Particles sampled for the spacing estimate.
const SPACING_SAMPLES: usize = 20_000;

/// Where the meshes go.
#[derive(Debug, Clone)]
pub enum Output {
    /// Beside each input, as `{stem}_surface.{ext}`.
    BesideInput,
    /// Into a directory, as `{stem}.{ext}`.
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

    fn path_for(&self, input: &Path, format: MeshFormat) -> Result<PathBuf> {
        let stem = input
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .ok_or_else(|| anyhow!("{}: no file name", input.display()))?;
        let ext = format.extension();
        Ok(match self {
            Output::BesideInput => input.with_file_name(format!("{stem}_surface.{ext}")),
            Output::Directory(dir) => dir.join(format!("{stem}.{ext}")),
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

/// The last run of digits in a file stem: `frame_0042` → 42.
pub fn frame_number(stem: &str) -> Option<u64> {
    let end = stem.rfind(|c: char| c.is_ascii_digit())? + 1;
    let start = stem[..end]
        .rfind(|c: char| !c.is_ascii_digit())
        .map_or(0, |i| i + 1);
    stem[start..end].parse().ok()
}

pub struct Batch {
    pub inputs: Vec<PathBuf>,
    pub input_format: Option<InputFormat>,
    pub output: Output,
    pub format: MeshFormat,
    pub config: Config,
    pub engine: Engine,
}

/// What happened to one frame.
pub struct FrameOutcome {
    pub input: PathBuf,
    pub output: PathBuf,
    pub result: Result<FrameStats>,
}

/// Messages for the user as the run goes on.
pub trait Progress {
    fn spacing_estimated(&mut self, from: &Path, spacing: f32);
    fn frame_done(&mut self, outcome: &FrameOutcome, done: usize, total: usize);
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

    /// Reconstructs every frame; returns the outcomes in input order.
    pub fn run(&self, progress: &mut dyn Progress) -> Result<Vec<FrameOutcome>> {
        let outputs = self.outputs()?;
        self.config.validate()?;
        let mut spacing = self.config.spacing;
        let mut outcomes = Vec::with_capacity(self.inputs.len());
        for (k, (input, output)) in self.inputs.iter().zip(outputs).enumerate() {
            let result = self.frame(input, &output, &mut spacing, progress);
            let outcome = FrameOutcome {
                input: input.clone(),
                output,
                result,
            };
            progress.frame_done(&outcome, k + 1, self.inputs.len());
            outcomes.push(outcome);
        }
        Ok(outcomes)
    }

    fn frame(
        &self,
        input: &Path,
        output: &Path,
        spacing: &mut Option<f32>,
        progress: &mut dyn Progress,
    ) -> Result<FrameStats> {
        let start = Instant::now();
        let particles = io::read_particles(input, self.input_format)?;
        let read = start.elapsed();
        if particles.is_empty() {
            // Nothing to reconstruct, and nothing to estimate a spacing from.
            io::write_mesh_file(output, &TriMesh::default(), self.format)?;
            let mut stats = FrameStats::default();
            stats.timings.read = read;
            return Ok(stats);
        }
        // One spacing, hence one grid, for the whole sequence.
        let r = match *spacing {
            Some(r) => r,
            None => {
                let r = estimate_spacing(&particles, SPACING_SAMPLES).ok_or_else(|| {
                    anyhow!(
                        "cannot estimate the particle spacing from {} particles; give --spacing or --particle-radius",
                        particles.len()
                    )
                })?;
                progress.spacing_estimated(input, r);
                *spacing = Some(r);
                r
            }
        };
        let params = Params::resolve(&self.config, r);
        let rec = reconstruct(&particles, &params, self.engine).context("reconstruction failed")?;
        drop(particles);
        let start = Instant::now();
        io::write_mesh_file(output, &rec.mesh, self.format)?;
        let mut stats = rec.stats;
        stats.timings.read = read;
        stats.timings.write = start.elapsed();
        Ok(stats)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_numbers_come_from_the_last_digits() {
        assert_eq!(frame_number("frame_0042"), Some(42));
        assert_eq!(frame_number("run2_f_9"), Some(9));
        assert_eq!(frame_number("fluid"), None);
    }

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
