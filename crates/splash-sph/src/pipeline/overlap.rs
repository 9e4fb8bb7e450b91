//! A sequence's frames in a three-stage software pipeline: while frame k is made on the
//! caller's workers, the next file is read on one thread and frame k−1's mesh written on
//! another, so that neither the parsing nor the formatting nor the disk's fsync holds the
//! workers up. At most one file read ahead and one mesh being written are held besides what the
//! make step keeps. The caller is told of every frame in frame order, with the messages,
//! outcomes and files that [`run_plan`] gives frame after frame.

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::thread;

use super::frame::{Loaded, Loader, Made};
use super::{FrameOutcome, FramePipeline, Plan, Progress, RunReport, run_plan};
use crate::error::{Error, Result};
use crate::frames::path_frame_number;
use crate::report::{FrameStats, Observer};

/// The files a run reads, handed to its make step in the order of the run's list.
pub(super) trait Reads {
    /// The next file of the list, read.
    fn next(&mut self) -> Result<Loaded>;
}

/// Files read on the reader's thread, one ahead.
struct Ahead<'a>(&'a mpsc::Receiver<Result<Loaded>>);

impl Reads for Ahead<'_> {
    fn next(&mut self) -> Result<Loaded> {
        // Only a panic of the reader ends the channel early; the scope raises it again.
        self.0
            .recv()
            .unwrap_or_else(|_| Err(Error::input("the reader thread stopped")))
    }
}

/// Files read when the make step asks (a run without its writer's thread).
struct InPlace<'a> {
    loader: Loader,
    files: std::slice::Iter<'a, PathBuf>,
}

impl Reads for InPlace<'_> {
    fn next(&mut self) -> Result<Loaded> {
        let file = self.files.next().expect("no more reads than the list");
        self.loader.load(file)
    }
}

/// Runs the plan's frames, overlapped (see the module's header): `make(pipeline, input,
/// reads, progress)` makes each frame of the plan in turn, taking from `reads` the files of
/// `reading` in their order (one per frame when frames are meshed alone; a following sequence
/// reads its neighbours too).
pub(super) fn run_overlapped(
    plan: Plan,
    fail_fast: bool,
    progress: &mut dyn Progress,
    pipeline: &mut FramePipeline,
    reading: &[PathBuf],
    mut make: impl FnMut(&mut FramePipeline, &Path, &mut dyn Reads, &mut dyn Progress) -> Result<Made>,
) -> RunReport {
    let (loader, writer) = (pipeline.loader(), pipeline.writer());
    // The writer formats on one thread of its own: the caller's workers are reconstructing,
    // and a pool of one keeps a text writer from reaching for rayon's global pool.
    let Ok(write_pool) = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .thread_name(|_| "splash-writer".into())
        .build()
    else {
        let mut reads = InPlace {
            loader,
            files: reading.iter(),
        };
        return run_plan(plan, fail_fast, progress, |input, output, progress| {
            let made = make(pipeline, input, &mut reads, progress)?;
            writer.write(output, made)
        });
    };
    let total = plan.frames.len();
    let mut outcomes = Vec::with_capacity(total);
    let mut not_attempted = 0;
    thread::scope(|s| {
        let frames = &plan.frames;
        // A rendezvous: the reader holds one file until the make step takes it.
        let (read, reads) = mpsc::sync_channel(0);
        s.spawn(move || {
            for input in reading {
                if read.send(loader.load(input)).is_err() {
                    return;
                }
            }
        });
        let (write, writes) = mpsc::sync_channel::<(&Path, Made)>(0);
        let (wrote, written) = mpsc::channel();
        s.spawn(move || {
            write_pool.install(|| {
                for (output, made) in writes {
                    if wrote.send(writer.write(output, made)).is_err() {
                        return;
                    }
                }
            })
        });
        let mut frames_done = Reports {
            outcomes: &mut outcomes,
            frames,
            total,
        };
        // The frame whose mesh the writer has.
        let mut writing: Option<usize> = None;
        for (k, (input, output)) in frames.iter().enumerate() {
            if progress.cancelled() {
                not_attempted = total - k;
                break;
            }
            // The messages of frame k wait for frame k−1's end, as they would frame after frame.
            let mut deferred = Deferred {
                progress: &mut *progress,
                held: writing.is_some(),
                messages: Vec::new(),
            };
            let made = make(pipeline, input, &mut Ahead(&reads), &mut deferred);
            let messages = deferred.messages;
            if let Some(previous) = writing.take() {
                let Ok(result) = written.recv() else { break };
                let failed = frames_done.report(previous, result, progress);
                if (failed && fail_fast) || progress.cancelled() {
                    // Frame k is dropped unwritten, as a run frame after frame never starts it.
                    not_attempted = total - k;
                    break;
                }
            }
            for message in messages {
                message.tell(progress);
            }
            let made = match made {
                Ok(made) if k + 1 < total => {
                    if write.send((output, made)).is_err() {
                        break;
                    }
                    writing = Some(k);
                    continue;
                }
                other => other,
            };
            // A failed frame, or the last: nothing to overlap its write with, so it is written
            // here, formatted on the caller's workers.
            let result = made.and_then(|made| writer.write(output, made));
            let failed = frames_done.report(k, result, progress);
            if failed && fail_fast {
                not_attempted = total - k - 1;
                break;
            }
        }
        if let Some(previous) = writing.take()
            && let Ok(result) = written.recv()
        {
            frames_done.report(previous, result, progress);
        }
        // Ends the writer; the reader ends at its next frame.
        drop((write, reads));
    });
    RunReport {
        plan,
        outcomes,
        not_attempted,
    }
}

/// The outcomes so far, told to the caller as they are added.
struct Reports<'a> {
    outcomes: &'a mut Vec<FrameOutcome>,
    frames: &'a [(PathBuf, PathBuf)],
    total: usize,
}

impl Reports<'_> {
    /// Adds frame `k`'s outcome and tells the caller; returns whether it failed.
    fn report(
        &mut self,
        k: usize,
        result: Result<FrameStats>,
        progress: &mut dyn Progress,
    ) -> bool {
        let (input, output) = &self.frames[k];
        let outcome = FrameOutcome {
            input: input.clone(),
            output: output.clone(),
            frame: path_frame_number(input),
            result,
        };
        progress.frame_done(&outcome, k + 1, self.total);
        let failed = outcome.result.is_err();
        self.outcomes.push(outcome);
        failed
    }
}

/// A message of a frame made while the previous one is still being written.
enum Message {
    Spacing(PathBuf, f32),
    Warning(Option<PathBuf>, String),
}

impl Message {
    fn tell(self, progress: &mut dyn Progress) {
        match self {
            Message::Spacing(from, r) => progress.spacing_estimated(&from, r),
            Message::Warning(input, text) => progress.warning(input.as_deref(), &text),
        }
    }
}

/// The caller's progress, with the messages kept back while `held`.
struct Deferred<'a> {
    progress: &'a mut dyn Progress,
    held: bool,
    messages: Vec<Message>,
}

impl Progress for Deferred<'_> {
    fn started(&mut self, plan: &Plan) {
        self.progress.started(plan);
    }

    fn spacing_estimated(&mut self, from: &Path, spacing: f32) {
        if self.held {
            self.messages
                .push(Message::Spacing(from.to_path_buf(), spacing));
        } else {
            self.progress.spacing_estimated(from, spacing);
        }
    }

    fn warning(&mut self, input: Option<&Path>, message: &str) {
        if self.held {
            let input = input.map(Path::to_path_buf);
            self.messages
                .push(Message::Warning(input, message.to_string()));
        } else {
            self.progress.warning(input, message);
        }
    }

    fn frame_done(&mut self, outcome: &FrameOutcome, done: usize, total: usize) {
        self.progress.frame_done(outcome, done, total);
    }

    fn cancelled(&mut self) -> bool {
        self.progress.cancelled()
    }

    fn observer(&mut self) -> Box<dyn Observer> {
        self.progress.observer()
    }

    fn measured(&mut self, stats: &mut FrameStats) {
        self.progress.measured(stats);
    }
}

#[cfg(test)]
mod tests {
    use std::fs;

    use super::*;
    use crate::config::Config;
    use crate::frames::Output;
    use crate::io::MeshFormat;
    use crate::pipeline::Batch;
    use crate::tests::common::ball_frames;

    fn scratch(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("splash-overlap-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(dir.join("sim")).unwrap();
        dir
    }

    fn batch(inputs: &[PathBuf], out: &Path, format: MeshFormat, config: Config) -> Batch {
        Batch {
            inputs: inputs.to_vec(),
            input_format: None,
            output: Output::Directory(out.to_path_buf()),
            format,
            config,
            shard: None,
            skip_existing: false,
            fail_fast: false,
            iso: None,
        }
    }

    /// `batch` run frame after frame with [`run_plan`], as before the overlap.
    fn serial(batch: &Batch, progress: &mut dyn Progress) -> RunReport {
        let plan = batch.plan().unwrap();
        let mut pipeline =
            FramePipeline::new(None, batch.format, batch.config.clone(), None).unwrap();
        progress.started(&plan);
        pipeline.spacing_from(&batch.inputs[..plan.first.unwrap_or(0)], progress);
        let fail_fast = batch.fail_fast;
        run_plan(plan, fail_fast, progress, |input, output, progress| {
            pipeline.frame(input, output, progress)
        })
    }

    /// What a caller is told, in order, without the timings; cancels after frame `stop`.
    #[derive(Default)]
    struct Record {
        events: Vec<String>,
        done: usize,
        stop: Option<usize>,
    }

    impl Progress for Record {
        fn spacing_estimated(&mut self, from: &Path, spacing: f32) {
            let name = from.file_name().unwrap().to_string_lossy();
            self.events.push(format!("spacing {spacing} from {name}"));
        }

        fn warning(&mut self, input: Option<&Path>, message: &str) {
            self.events.push(format!("warning {input:?}: {message}"));
        }

        fn frame_done(&mut self, o: &FrameOutcome, done: usize, total: usize) {
            let result = match &o.result {
                Ok(s) => format!("{} triangles", s.triangles),
                Err(e) => e.to_string(),
            };
            self.events
                .push(format!("{done}/{total} {:?}: {result}", o.frame));
            self.done += 1;
        }

        fn cancelled(&mut self) -> bool {
            self.stop.is_some_and(|k| self.done >= k)
        }
    }

    fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
        let mut files: Vec<_> = fs::read_dir(dir)
            .map(|d| {
                d.map(|e| e.unwrap())
                    .filter(|e| e.file_type().unwrap().is_file())
                    .map(|e| {
                        (
                            e.file_name().to_string_lossy().into_owned(),
                            fs::read(e.path()).unwrap(),
                        )
                    })
                    .collect()
            })
            .unwrap_or_default();
        files.sort();
        files
    }

    /// Six frames, as OBJ and as PLY with velocities interpolated and turned Z-up: every mesh
    /// the overlapped run writes is the one its frame written alone writes.
    #[test]
    fn overlapped_runs_write_what_frames_alone_write() {
        let dir = scratch("same");
        let inputs = ball_frames(&dir.join("sim"), 6);
        let mut ply = Config {
            spacing: Some(0.1),
            ..Config::default()
        };
        ply.output.attributes = vec!["velocity".into()];
        ply.output.up_axis = Some(crate::io::UpAxis::Z);
        let obj = Config {
            spacing: Some(0.1),
            ..Config::default()
        };
        for (format, config) in [(MeshFormat::Obj, obj), (MeshFormat::PlyBinary, ply)] {
            let out = dir.join(format.extension());
            let report = batch(&inputs, &out, format, config.clone())
                .run(&mut Record::default())
                .unwrap();
            assert!(report.complete() && report.outcomes.len() == 6);
            let written = files(&out);
            assert_eq!(written.len(), 6);
            for (input, (name, bytes)) in inputs.iter().zip(&written) {
                let alone = dir.join(format!("alone.{}", format.extension()));
                FramePipeline::new(None, format, config.clone(), None)
                    .unwrap()
                    .frame(input, &alone, &mut Record::default())
                    .unwrap();
                assert!(fs::read(&alone).unwrap() == *bytes, "{name} as {format:?}");
            }
        }
        fs::remove_dir_all(&dir).unwrap();
    }

    /// Frame 3 cannot be read and frame 4's output is a directory (its write fails, on the
    /// writer's thread): those two fail, the others are written as if alone. With `fail_fast`,
    /// the run stops at the first failure, frames made meanwhile are not written.
    #[test]
    fn a_broken_frame_fails_alone() {
        let dir = scratch("broken");
        let inputs = ball_frames(&dir.join("sim"), 5);
        fs::write(&inputs[2], "x,y,z\n0,0,oops\n").unwrap();
        let config = Config {
            spacing: Some(0.1),
            ..Config::default()
        };
        let (out, reference) = (dir.join("out"), dir.join("reference"));
        fs::create_dir_all(out.join("f_0004.obj")).unwrap();
        fs::create_dir_all(reference.join("f_0004.obj")).unwrap();
        let mut overlapped = Record::default();
        let b = batch(&inputs, &out, MeshFormat::Obj, config.clone());
        let report = b.run(&mut overlapped).unwrap();
        let failed: Vec<usize> = report
            .outcomes
            .iter()
            .enumerate()
            .filter_map(|(k, o)| o.result.is_err().then_some(k + 1))
            .collect();
        assert_eq!(failed, [3, 4]);
        let mut one_by_one = Record::default();
        serial(
            &batch(&inputs, &reference, MeshFormat::Obj, config.clone()),
            &mut one_by_one,
        );
        assert_eq!(overlapped.events.len(), 5);
        assert_eq!(files(&out), files(&reference));
        assert_eq!(
            files(&out)
                .iter()
                .map(|(n, _)| n.as_str())
                .collect::<Vec<_>>(),
            ["f_0001.obj", "f_0002.obj", "f_0005.obj"]
        );

        // Stopped by the failing write of frame 2, while frame 3 was being made.
        let fast = dir.join("fast");
        fs::create_dir_all(fast.join("f_0002.obj")).unwrap();
        let b = Batch {
            fail_fast: true,
            ..batch(&inputs, &fast, MeshFormat::Obj, config)
        };
        let report = b.run(&mut Record::default()).unwrap();
        assert_eq!((report.outcomes.len(), report.not_attempted), (2, 3));
        assert!(report.outcomes[1].result.is_err());
        assert_eq!(
            files(&fast)
                .iter()
                .map(|(n, _)| n.as_str())
                .collect::<Vec<_>>(),
            ["f_0001.obj"]
        );
        fs::remove_dir_all(&dir).unwrap();
    }

    /// The caller hears what it hears frame after frame, in the same order: the spacing
    /// estimated and the spacing warning on frame 2 (frame 1 is empty, and is being written
    /// meanwhile) come after frame 1's end, a broken frame in its place; a run cancelled after
    /// frame 3 writes nothing more.
    #[test]
    fn callers_hear_of_frames_in_frame_order() {
        let dir = scratch("order");
        let inputs = ball_frames(&dir.join("sim"), 5);
        fs::write(&inputs[0], "x,y,z\n").unwrap();
        fs::write(&inputs[3], "not a table\n").unwrap();
        // Spacing estimated; then one 0.4x the particles' spacing, which is warned of.
        for spacing in [None, Some(0.04)] {
            for stop in [None, Some(3)] {
                let config = Config {
                    spacing,
                    ..Config::default()
                };
                let (out, reference) = (dir.join("out"), dir.join("reference"));
                let _ = (fs::remove_dir_all(&out), fs::remove_dir_all(&reference));
                let mut overlapped = Record {
                    stop,
                    ..Record::default()
                };
                let report = batch(&inputs, &out, MeshFormat::Obj, config.clone())
                    .run(&mut overlapped)
                    .unwrap();
                let mut one_by_one = Record {
                    stop,
                    ..Record::default()
                };
                let expected = serial(
                    &batch(&inputs, &reference, MeshFormat::Obj, config),
                    &mut one_by_one,
                );
                assert_eq!(overlapped.events, one_by_one.events, "{spacing:?} {stop:?}");
                assert!(
                    overlapped.events[1]
                        .starts_with(["spacing", "warning"][spacing.is_some() as usize])
                );
                assert_eq!(report.not_attempted, expected.not_attempted);
                assert_eq!(report.not_attempted, if stop.is_some() { 2 } else { 0 });
                assert_eq!(files(&out), files(&reference));
            }
        }
        fs::remove_dir_all(&dir).unwrap();
    }
}
