//! A whole sequence, `splash recon`'s and `splash iso`'s: every output named and checked
//! before any work, this job's share planned, the spacing taken from the sequence's first frame
//! whatever the shard, then each frame through the [`FramePipeline`].

use std::path::PathBuf;

use super::overlap::run_overlapped;
use super::{FramePipeline, Plan, Progress, RunReport};
use crate::config::Config;
use crate::error::Result;
use crate::frames::{Output, Shard, output_paths};
use crate::io::{InputFormat, MeshFormat};
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
        let plan = Plan::new(&self.inputs, &outputs, self.shard, self.skip_existing);
        Ok(plan)
    }

    /// Reconstructs this job's frames in frame order, the next frame read and the last mesh
    /// written while a frame is reconstructed (on two threads besides the caller's workers),
    /// with the outputs, outcomes and messages of one frame after the other. Errors before the
    /// first frame (bad settings, outputs that collide or cannot be written) end the run; a
    /// frame's error is in its outcome.
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
        Ok(run_overlapped(
            plan,
            self.fail_fast,
            progress,
            &mut pipeline,
        ))
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
}
