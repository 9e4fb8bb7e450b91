//! The frame pipeline that the command line, Python and Blender all run: read → attributes →
//! reconstruct (Akinci et al. 2012) or isosurface (Marching Correctors) → post-process →
//! interpolate → write, with an [`Observer`](crate::Observer) for stage times; and the plan
//! and run of a whole sequence (shards, `skip_existing`, `fail_fast`, progress per frame, a
//! run report), its reading and writing overlapped with the reconstruction.
//!
//! ```no_run
//! use splash_sph::frames::{Output, select};
//! use splash_sph::pipeline::{Batch, FrameOutcome, Progress};
//! use splash_sph::{Config, MeshFormat};
//!
//! struct Print;
//! impl Progress for Print {
//!     fn frame_done(&mut self, o: &FrameOutcome, done: usize, total: usize) {
//!         println!("{done}/{total} {}: {}", o.input.display(), o.result.is_ok());
//!     }
//! }
//!
//! let inputs = select(&["sim/".into()], Some("1-100x2"))?.files;
//! let batch = Batch {
//!     inputs,
//!     input_format: None,
//!     output: Output::parse("mesh/fluid_{frame:04}.ply"),
//!     format: MeshFormat::PlyBinary,
//!     config: Config { spacing: Some(0.014), ..Config::default() },
//!     shard: None,
//!     skip_existing: true,
//!     fail_fast: false,
//!     iso: None,
//! };
//! let report = batch.run(&mut Print)?;
//! assert!(report.complete());
//! # Ok::<(), splash_sph::Error>(())
//! ```

mod batch;
mod following;
mod frame;
#[cfg(test)]
mod level_set_output;
mod overlap;
mod plan;
mod run;
mod surface;

pub use batch::Batch;
pub(crate) use frame::FramePipeline;
pub use plan::Plan;
pub use run::{FrameOutcome, Progress, RunReport, run_plan};
pub use surface::{FrameParticles, Surface, surface, surface_following};
