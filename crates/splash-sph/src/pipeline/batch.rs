//! A whole sequence, `splash recon`'s and `splash iso`'s: every output named and checked
//! before any work, this job's share planned, the spacing taken from the sequence's first frame
//! whatever the shard, then each frame through the [`FramePipeline`]; for USD output, then the
//! stage that plays the frames' layers as one animated mesh.
//!
//! The stage is written after the frames, by every job, from the layers of the whole selection
//! that exist then (written whole, so complete): a failed frame, or one another shard has not
//! written yet, is left out, and the stage shows the frame before it there (with a warning
//! naming them); the run that writes the missing frames (`skip_existing`) writes the stage
//! again with them. Of shards ending together, the last to write the stage may have missed a
//! frame another wrote meanwhile: a run with `skip_existing` afterwards completes it.

use std::path::{Path, PathBuf};

use super::following::run_following;
use super::overlap::run_overlapped;
use super::{FramePipeline, Plan, Progress, RunReport};
use crate::config::Config;
use crate::error::Result;
use crate::frames::{Output, Shard, output_paths, path_frame_number};
use crate::io::{self, InputFormat, MeshFormat, UsdClip};
use crate::iso::IsoRequest;

/// A run over many frames: one mesh per input file, each written whole or not at all.
#[derive(Debug, Clone)]
pub struct Batch {
    /// The selected frames, in frame order: the whole sequence, before sharding.
    pub inputs: Vec<PathBuf>,
    /// Every input's format; None: from each file's extension.
    pub input_format: Option<InputFormat>,
    /// Where the meshes go.
    pub output: Output,
    /// The mesh format.
    pub format: MeshFormat,
    /// Everything else: the reconstruction, and the up axis and attributes of the output.
    /// With `threads` set the reconstruction runs on its own pool, else in the caller's.
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

impl Batch {
    /// Output paths of all frames, checked for collisions before any work starts.
    pub fn outputs(&self) -> Result<Vec<PathBuf>> {
        let ext = self.format.extension();
        output_paths(&self.inputs, &self.output, "mesh", "_surface", ext)
    }

    /// This job's share, with every output of the whole sequence checked (so that all shards
    /// agree) and the output directories checked writable.
    pub fn plan(&self) -> Result<Plan> {
        let outputs = self.outputs()?;
        if let Some(stage) = self.usd_stage(&outputs) {
            let topology = io::usd_topology_path(&stage);
            if let Some(o) = outputs.iter().find(|o| **o == stage || **o == topology) {
                bail_config!(
                    "the frame layer '{}' would be overwritten by the sequence's USD stage: \
                     rename the outputs so that they hold a frame number",
                    o.display()
                );
            }
        }
        let plan = Plan::new(&self.inputs, &outputs, self.shard, self.skip_existing);
        Ok(plan)
    }

    /// The USD stage this run writes after its frames, for USD output of a sequence: into a
    /// directory, by a pattern, or beside the inputs, not into one named file. It lies beside
    /// the first frame's layer, named after it without its frame number
    /// (`mesh/fluid_0001.usda` → `mesh/fluid.usda`).
    pub fn usd_stage(&self, outputs: &[PathBuf]) -> Option<PathBuf> {
        let one_file = matches!(&self.output, Output::Pattern(p) if !p.contains('{'));
        if self.format != MeshFormat::Usd || one_file {
            return None;
        }
        Some(io::usd_stage_path(outputs.first()?))
    }

    /// Writes the USD stage over the frame layers of the selection that exist; see the
    /// module's header. A stage needs every frame numbered, each number once.
    fn write_usd_stage(
        &self,
        stage: &Path,
        outputs: &[PathBuf],
        progress: &mut dyn Progress,
    ) -> Result<()> {
        let (mut clips, mut missing) = (Vec::<UsdClip>::new(), Vec::new());
        for (input, layer) in self.inputs.iter().zip(outputs) {
            let Some(time) = path_frame_number(input) else {
                let message = format!(
                    "no USD stage: '{}' has no frame number in its name, hence no time",
                    input.display()
                );
                progress.warning(None, &message);
                return Ok(());
            };
            if clips.last().is_some_and(|c| c.time == time) {
                let message = format!("no USD stage: two frames are numbered {time}");
                progress.warning(None, &message);
                return Ok(());
            }
            if layer.is_file() {
                clips.push(UsdClip {
                    time,
                    layer: layer.clone(),
                });
            } else {
                missing.push(time.to_string());
            }
        }
        if clips.is_empty() {
            return Ok(());
        }
        if !missing.is_empty() {
            let message = format!(
                "the USD stage '{}' leaves out frame{} {} (failed, or not written yet by another \
                 job), showing the frame before {} instead; a run with --skip-existing writes {} \
                 and the stage again",
                stage.display(),
                if missing.len() > 1 { "s" } else { "" },
                missing.join(", "),
                if missing.len() > 1 { "each" } else { "it" },
                if missing.len() > 1 { "them" } else { "it" },
            );
            progress.warning(None, &message);
        }
        io::write_usd_stage(
            stage,
            &clips,
            io::USD_FRAMES_PER_SECOND,
            self.config.output.up_axis,
        )
    }

    /// Reconstructs this job's frames in frame order, the next frame read and the last mesh
    /// written while a frame is reconstructed (on two threads besides the caller's workers),
    /// with the outputs, outcomes and messages of one frame after the other. Errors before the
    /// first frame (bad settings, outputs that collide or cannot be written) end the run; a
    /// frame's error is in its outcome. For USD output the stage is written after the frames;
    /// a stage that cannot be written is the run's error.
    pub fn run(&self, progress: &mut dyn Progress) -> Result<RunReport> {
        let plan = self.plan()?;
        let mut pipeline = FramePipeline::new(
            self.input_format,
            self.format,
            self.config.clone(),
            self.iso.clone(),
        )?;
        plan.check_writable()?;
        progress.started(&plan);
        if let Some(first) = plan.first {
            pipeline.spacing_from(&self.inputs[..first], progress);
        }
        let report = if pipeline.follows_fluid() && self.inputs.len() > 1 {
            run_following(&self.inputs, plan, self.fail_fast, progress, &mut pipeline)
        } else {
            let reading: Vec<PathBuf> = plan.frames.iter().map(|(i, _)| i.clone()).collect();
            run_overlapped(
                plan,
                self.fail_fast,
                progress,
                &mut pipeline,
                &reading,
                |pipeline, input, reads, progress| {
                    let loaded = reads.next()?;
                    pipeline.make(input, loaded, progress)
                },
            )
        };
        let outputs = self.outputs()?;
        if let Some(stage) = self.usd_stage(&outputs) {
            self.write_usd_stage(&stage, &outputs, progress)?;
        }
        Ok(report)
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::pipeline::FrameOutcome;
    use crate::reconstructor::Reconstructor;
    use crate::tests::common::ball_frames;

    #[derive(Default)]
    struct Record(Vec<(usize, usize, bool)>, Vec<f32>);

    impl Progress for Record {
        fn spacing_estimated(&mut self, _from: &Path, spacing: f32) {
            self.1.push(spacing);
        }

        fn frame_done(&mut self, o: &FrameOutcome, done: usize, total: usize) {
            self.0.push((done, total, o.result.is_ok()));
        }
    }

    fn batch(inputs: &[PathBuf], out: &Path, shard: Option<Shard>) -> Batch {
        let mut config = Config::default();
        config.output.attributes = vec!["velocity".into()];
        Batch {
            inputs: inputs.to_vec(),
            input_format: None,
            output: Output::Directory(out.to_path_buf()),
            format: MeshFormat::PlyBinary,
            config,
            shard,
            skip_existing: true,
            fail_fast: false,
            iso: None,
        }
    }

    /// Two shards write the bytes one whole run writes (the spacing of both is frame 1's,
    /// whichever frames a shard does), a restart with `skip_existing` does nothing, and each
    /// mesh is the reconstruction of its frame at that spacing.
    #[test]
    fn shards_and_restarts_write_what_one_run_writes() {
        let dir = std::env::temp_dir().join(format!("splash-batch-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("sim")).unwrap();
        let inputs = ball_frames(&dir.join("sim"), 3);
        let (whole, sharded) = (dir.join("whole"), dir.join("sharded"));
        let mut seen = Record::default();
        let report = batch(&inputs, &whole, None).run(&mut seen).unwrap();
        assert!(report.complete());
        assert_eq!(seen.0, [(1, 3, true), (2, 3, true), (3, 3, true)]);
        let [r] = seen.1[..] else {
            panic!("one spacing: {:?}", seen.1)
        };
        for k in [2, 1] {
            let mut shard = Record::default();
            let b = batch(&inputs, &sharded, Some(Shard::new(k, 2).unwrap()));
            b.run(&mut shard).unwrap();
            assert_eq!(shard.1, [r], "shard {k}/2 estimates on frame 1");
        }
        for f in 1..=3 {
            let name = format!("f_{f:04}.ply");
            let bytes = std::fs::read(whole.join(&name)).unwrap();
            assert_eq!(bytes, std::fs::read(sharded.join(&name)).unwrap(), "{name}");
        }
        let mut again = Record::default();
        let restart = batch(&inputs, &whole, None).run(&mut again).unwrap();
        assert_eq!((restart.plan.skipped.len(), restart.plan.to_do()), (3, 0));
        assert!(again.0.is_empty() && restart.complete());

        // Frame 3 by hand, at frame 1's spacing.
        let mut particles = crate::read_particles(&inputs[2], None).unwrap();
        let velocity = particles.attributes.remove("velocity").unwrap();
        let config = Config {
            spacing: Some(r),
            ..Config::default()
        };
        let reconstructor = Reconstructor::new(config).unwrap();
        let rec = reconstructor.reconstruct(&particles.positions).unwrap();
        let v = reconstructor
            .interpolate(&rec.mesh, &particles.positions, &velocity)
            .unwrap();
        let named = &mut [("velocity".to_string(), v)];
        let attributes = crate::io::VertexAttributes {
            named,
            ..Default::default()
        };
        let by_hand = dir.join("by_hand.ply");
        crate::io::write_mesh_file_with(&by_hand, &rec.mesh, &attributes, MeshFormat::PlyBinary)
            .unwrap();
        assert_eq!(
            std::fs::read(by_hand).unwrap(),
            std::fs::read(whole.join("f_0003.ply")).unwrap()
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// USD output: the stage lists every frame's layer at its number, a failed frame is left
    /// out (and named in a warning) until a run with `skip_existing` writes it and the stage
    /// again; a plan whose stage would overwrite a frame's layer is refused.
    #[test]
    fn usd_stages_list_the_layers_that_exist() {
        #[derive(Default)]
        struct Warnings(Vec<String>);
        impl Progress for Warnings {
            fn warning(&mut self, _input: Option<&Path>, message: &str) {
                self.0.push(message.to_string());
            }
            fn frame_done(&mut self, _o: &FrameOutcome, _done: usize, _total: usize) {}
        }
        let dir = std::env::temp_dir().join(format!("splash-batch-usd-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("sim")).unwrap();
        let inputs = ball_frames(&dir.join("sim"), 3);
        let good = std::fs::read(&inputs[1]).unwrap();
        std::fs::write(&inputs[1], "x,y,z\n1,2\n").unwrap();
        let usd = Batch {
            format: MeshFormat::Usd,
            config: Config {
                spacing: Some(0.1),
                ..Config::default()
            },
            ..batch(&inputs, &dir.join("usd"), None)
        };
        let mut seen = Warnings::default();
        let report = usd.run(&mut seen).unwrap();
        assert_eq!(report.failed().count(), 1);
        let stage = dir.join("usd/f.usda");
        let text = std::fs::read_to_string(&stage).unwrap();
        assert!(text.contains("(1, 0),\n                (3, 1)\n"), "{text}");
        assert!(text.contains("@./f_0003.usda@") && !text.contains("f_0002"));
        assert!(
            seen.0.iter().any(|w| w.contains("leaves out frame 2 ")),
            "{:?}",
            seen.0
        );
        let layer = std::fs::read_to_string(dir.join("usd/f_0003.usda")).unwrap();
        assert!(layer.contains("    vector3f[] velocities.timeSamples = {\n        3: ["));

        std::fs::write(&inputs[1], good).unwrap();
        let report = usd.run(&mut Warnings::default()).unwrap();
        assert!(report.complete() && report.plan.skipped.len() == 2);
        let text = std::fs::read_to_string(&stage).unwrap();
        assert!(text.contains("(1, 1),\n                (2, 2),\n                (3, 3)\n"));

        let clash = Batch {
            output: Output::Pattern(dir.join("usd/{stem}.usda").display().to_string()),
            inputs: vec![dir.join("sim/f_1.csv"), dir.join("sim/f.csv")],
            ..usd
        };
        let e = clash.plan().unwrap_err().to_string();
        assert!(e.contains("overwritten by the sequence's USD stage"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
