//! What a run tells its user: a progress bar on a terminal; one line per frame elsewhere (farm
//! logs), plain text or JSON; a summary of failed frames at the end. Everything goes to stderr.
//!
//! JSON lines (`--log-format json`) are one object per line, each with `"event"`:
//! - `"start"`: `selected`, `shard` (`"K/N"` or null), `assigned`, `skipped` (outputs found
//!   complete), `to_do`;
//! - `"spacing"`: `file`, `spacing`;
//! - `"warning"`: `time`, `file` (or null for the run), `message`;
//! - `"error"`: `message`: the run could not start (a bad flag, a missing input); the exit
//!   status is 2 for a usage error, else 1;
//! - `"frame"`: `time` (UTC, RFC 3339), `frame` (number or null), `input`, `output`, `status`
//!   (`"ok"` or `"error"`), and `particles`, `seconds` and the command's figures
//!   ([`FrameFigures::json`]: recon's `triangles`, `vertices`, `times` (seconds: `read`,
//!   `reconstruction`, of which `post`, and `write`; `post` is 0 under `--raw` alone); preview's `build_ms`,
//!   `render_ms`, `rays_per_second`, `hits`) or `error`;
//! - `"summary"`: `written`, `skipped`, `failed` (a list of `{frame, input, error}`),
//!   `not_attempted`, `ok` (true when every frame of the job has its output).
//!
//! `recon` and `preview` share it, and the flags that drive it ([`RunArgs`]).

use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;

use splash_sph::pipeline::{FrameOutcome, Plan, Progress, RunReport};
use splash_sph::{FrameStats, InputFormat};

/// The logging, input and report flags of a run over frames (`recon`, `preview`).
#[derive(Args)]
pub struct RunArgs {
    /// Log lines: plain, or json (one object per line).
    #[arg(long, value_name = "FORMAT", default_value = "plain")]
    pub log_format: String,

    /// Input format for every file: ply, csv, raw, vtk, vtu (or vtp), bgeo or xyz.
    #[arg(long)]
    pub input_format: Option<String>,

    /// Print figures per frame: recon's stage times and counts, preview's hierarchy and the
    /// paper's Table 3 counts per ray.
    #[arg(short, long)]
    pub verbose: bool,

    /// Print only errors.
    #[arg(short, long, conflicts_with = "verbose")]
    pub quiet: bool,

    /// Write per-frame figures to this file: recon's with their averages, machine, build and
    /// configuration (.json, .csv or .md), preview's (.json).
    #[arg(long)]
    pub report: Option<PathBuf>,
}

impl RunArgs {
    pub fn log_format(&self) -> anyhow::Result<LogFormat> {
        LogFormat::parse(&self.log_format)
    }

    pub fn input_format(&self) -> anyhow::Result<Option<InputFormat>> {
        Ok(self
            .input_format
            .as_deref()
            .map(InputFormat::parse)
            .transpose()?)
    }

    pub fn verbosity(&self) -> Verbosity {
        match (self.quiet, self.verbose) {
            (true, _) => Verbosity::Quiet,
            (_, true) => Verbosity::Verbose,
            _ => Verbosity::Normal,
        }
    }
}

/// What the log says of a frame done: recon's mesh figures, preview's image figures.
pub trait FrameFigures {
    /// Particles read.
    fn particles(&self) -> usize;
    /// Seconds the frame took.
    fn seconds(&self) -> f64;
    /// The plain line after the input's name, `output` the file written.
    fn line(&self, output: &Path, verbosity: Verbosity) -> String;
    /// The `frame` event's own fields.
    fn json(&self) -> serde_json::Map<String, serde_json::Value>;
}

impl FrameFigures for FrameStats {
    fn particles(&self) -> usize {
        self.particles
    }

    fn seconds(&self) -> f64 {
        let t = self.timings;
        // An isosurface's stages are its own, not the reconstruction's.
        let iso = self
            .iso
            .map_or(Duration::ZERO, |i| i.timings.grid_construction + i.total());
        (t.read + t.reconstruction() + iso + t.write).as_secs_f64()
    }

    fn line(&self, output: &Path, verbosity: Verbosity) -> String {
        let output = output.display();
        if verbosity == Verbosity::Verbose {
            format!(" -> {output}: {self}")
        } else if self.particles == 0 {
            format!(": no particles, wrote an empty mesh to {output}")
        } else {
            format!(
                " -> {output}: {} particles, {} triangles, {:.2} s",
                self.particles,
                self.triangles,
                self.seconds()
            )
        }
    }

    fn json(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut fields = serde_json::Map::new();
        fields.insert("triangles".into(), self.triangles.into());
        fields.insert("vertices".into(), self.vertices.into());
        fields.insert(
            "particles_outside_box".into(),
            self.particles_outside_box.into(),
        );
        let t = self.timings;
        let ms = |d: std::time::Duration| (d.as_secs_f64() * 1e3).round() / 1e3;
        fields.insert(
            "times".into(),
            json!({
                "read": ms(t.read),
                "reconstruction": ms(t.reconstruction()),
                "post": ms(t.post),
                "write": ms(t.write),
            }),
        );
        if let Some(iso) = &self.iso {
            fields.insert("iso".into(), json!(iso));
        }
        fields
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LogFormat {
    Plain,
    Json,
}

impl LogFormat {
    pub fn parse(name: &str) -> anyhow::Result<Self> {
        match name.trim().to_ascii_lowercase().as_str() {
            "plain" | "text" => Ok(Self::Plain),
            "json" => Ok(Self::Json),
            _ => anyhow::bail!("unknown log format '{name}': expected plain or json"),
        }
    }
}

/// How much to say.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verbosity {
    /// Errors and the summary of failures only.
    Quiet,
    Normal,
    /// Stage times and counts per frame.
    Verbose,
}

pub struct Console {
    bar: Option<ProgressBar>,
    format: LogFormat,
    verbosity: Verbosity,
}

impl Console {
    /// `terminal`: stderr is a terminal, so a progress bar replaces the per-frame lines (plain
    /// format only; errors are still printed above the bar).
    pub fn new(format: LogFormat, verbosity: Verbosity, terminal: bool) -> Console {
        let bar = (terminal && format == LogFormat::Plain && verbosity != Verbosity::Quiet)
            .then(|| {
                let bar = ProgressBar::hidden();
                bar.set_style(
                    ProgressStyle::with_template(
                        "{bar:40} {pos}/{len} frames, {per_sec}, {elapsed} elapsed, ETA {eta} {msg}",
                    )
                    .expect("the template is valid"),
                );
                bar
            });
        Console {
            bar,
            format,
            verbosity,
        }
    }

    /// Something that makes the output suspect, about `input` or the run.
    pub fn warn(&self, input: Option<&Path>, message: &str) {
        match self.format {
            LogFormat::Json => eprintln!(
                "{}",
                json!({
                    "event": "warning",
                    "time": utc_now(),
                    "file": input.map(|p| p.display().to_string()),
                    "message": message,
                })
            ),
            LogFormat::Plain if self.verbosity != Verbosity::Quiet => match input {
                Some(input) => self.say(&format!("warning: {}: {message}", input.display())),
                None => self.say(&format!("warning: {message}")),
            },
            LogFormat::Plain => {}
        }
    }

    fn say(&self, line: &str) {
        match &self.bar {
            Some(bar) if !bar.is_hidden() => bar.println(line),
            _ => eprintln!("{line}"),
        }
    }

    /// Ends the bar and prints the summary; returns whether every frame has its output.
    pub fn finish<S>(&self, report: &RunReport<S>) -> bool {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
        let failed: Vec<&FrameOutcome<S>> = report.failed().collect();
        let written = report.outcomes.len() - failed.len();
        if self.format == LogFormat::Json {
            let failed: Vec<_> = failed
                .iter()
                .map(|o| {
                    json!({
                        "frame": o.frame,
                        "input": o.input.display().to_string(),
                        "error": o.result.as_ref().err().map(|e| format!("{e:#}")),
                    })
                })
                .collect();
            let line = json!({
                "event": "summary",
                "written": written,
                "skipped": report.plan.skipped.len(),
                "failed": failed,
                "not_attempted": report.not_attempted,
                "ok": report.complete(),
            });
            eprintln!("{line}");
            return report.complete();
        }
        if failed.is_empty() && report.not_attempted == 0 {
            if self.verbosity != Verbosity::Quiet {
                let skipped = match report.plan.skipped.len() {
                    0 => String::new(),
                    n => format!(", {n} found complete and skipped"),
                };
                eprintln!("done: {written} frames written{skipped}");
            }
            return true;
        }
        let attempted = report.outcomes.len() + report.not_attempted;
        eprintln!("{} of {attempted} frames failed:", failed.len());
        for o in &failed {
            if let Err(e) = &o.result {
                eprintln!("  {}: {e:#}", o.input.display());
            }
        }
        if report.not_attempted > 0 {
            eprintln!(
                "stopped at the first failure (--fail-fast): {} frames not attempted",
                report.not_attempted
            );
        }
        false
    }
}

impl Console {
    /// This job's share, before any frame.
    pub fn start(&self, plan: &Plan) {
        if self.format == LogFormat::Json {
            let line = json!({
                "event": "start",
                "selected": plan.selected,
                "shard": plan.shard.map(|s| s.to_string()),
                "assigned": plan.assigned,
                "skipped": plan.skipped.len(),
                "to_do": plan.to_do(),
            });
            eprintln!("{line}");
            return;
        }
        if let Some(bar) = &self.bar {
            bar.set_length(plan.to_do() as u64);
            bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
        }
        if self.verbosity == Verbosity::Quiet {
            return;
        }
        let mut parts = Vec::new();
        if let Some(shard) = plan.shard {
            parts.push(format!(
                "shard {shard}: {} of {} frames",
                plan.assigned, plan.selected
            ));
        }
        if !plan.skipped.is_empty() {
            parts.push(format!(
                "{} found complete and skipped, {} to do",
                plan.skipped.len(),
                plan.to_do()
            ));
        }
        if !parts.is_empty() {
            self.say(&parts.join("; "));
        }
    }

    /// The spacing estimated once for the run.
    pub fn spacing(&self, from: &Path, spacing: f32) {
        match self.format {
            LogFormat::Json => eprintln!(
                "{}",
                json!({"event": "spacing", "file": from.display().to_string(), "spacing": spacing})
            ),
            LogFormat::Plain if self.verbosity != Verbosity::Quiet => self.say(&format!(
                "estimated particle spacing r = {spacing} from {} (from the local particle density); used for every frame",
                from.display()
            )),
            LogFormat::Plain => {}
        }
    }

    /// Frame `done` of `total` is done (or failed).
    pub fn frame<S: FrameFigures>(&self, outcome: &FrameOutcome<S>, done: usize, total: usize) {
        if self.format == LogFormat::Json {
            eprintln!("{}", frame_json(outcome));
            return;
        }
        let name = outcome.input.display();
        let time = utc_now();
        match &outcome.result {
            Err(e) => self.say(&format!("{time} [{done}/{total}] {name}: error: {e:#}")),
            Ok(stats) if self.verbosity != Verbosity::Quiet => {
                let figures = stats.line(&outcome.output, self.verbosity);
                self.say(&format!("{time} [{done}/{total}] {name}{figures}"));
            }
            Ok(_) => {}
        }
        if let Some(bar) = &self.bar {
            bar.set_position(done as u64);
        }
    }
}

impl<S: FrameFigures> Progress<S> for Console {
    fn started(&mut self, plan: &Plan) {
        self.start(plan);
    }

    fn spacing_estimated(&mut self, from: &Path, spacing: f32) {
        self.spacing(from, spacing);
    }

    fn warning(&mut self, input: Option<&Path>, message: &str) {
        self.warn(input, message);
    }

    fn frame_done(&mut self, outcome: &FrameOutcome<S>, done: usize, total: usize) {
        self.frame(outcome, done, total);
    }
}

/// An error that ends the run before or outside the frames, as `format` wants it.
pub fn print_error(format: LogFormat, message: &str) {
    match format {
        LogFormat::Json => eprintln!("{}", json!({"event": "error", "message": message})),
        LogFormat::Plain => eprintln!("error: {message}"),
    }
}

/// The log format asked for on the command line, found before the arguments are parsed, so
/// that argument errors come out in it too: `--log-format json` or `--log-format=json`.
pub fn format_in_args(args: &[std::ffi::OsString]) -> LogFormat {
    let mut found = LogFormat::Plain;
    let mut words = args.iter().map(|a| a.to_string_lossy());
    while let Some(word) = words.next() {
        if word == "--" {
            break;
        }
        let value = match word.strip_prefix("--log-format") {
            Some("") => words.next().map(|w| w.into_owned()),
            Some(rest) => rest.strip_prefix('=').map(str::to_string),
            None => None,
        };
        if let Some(format) = value.and_then(|v| LogFormat::parse(&v).ok()) {
            found = format;
        }
    }
    found
}

fn frame_json<S: FrameFigures>(outcome: &FrameOutcome<S>) -> serde_json::Value {
    let mut line = json!({
        "event": "frame",
        "time": utc_now(),
        "frame": outcome.frame,
        "input": outcome.input.display().to_string(),
        "output": outcome.output.display().to_string(),
    });
    let fields = match &outcome.result {
        Ok(stats) => {
            let mut fields = serde_json::Map::new();
            fields.insert("status".into(), "ok".into());
            fields.insert("particles".into(), stats.particles().into());
            fields.extend(stats.json());
            fields.insert(
                "seconds".into(),
                ((stats.seconds() * 1e3).round() / 1e3).into(),
            );
            fields
        }
        Err(e) => {
            let mut fields = serde_json::Map::new();
            fields.insert("status".into(), "error".into());
            fields.insert("error".into(), format!("{e:#}").into());
            fields
        }
    };
    if let Some(line) = line.as_object_mut() {
        line.extend(fields);
    }
    line
}

/// The current time as UTC RFC 3339 to the second: `2025-01-31T12:00:00Z`.
pub fn utc_now() -> String {
    let secs = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    utc(secs)
}

fn utc(secs: u64) -> String {
    let (days, rem) = (secs / 86_400, secs % 86_400);
    // Civil date from days since 1970-01-01 (H. Hinnant's algorithm).
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_dates() {
        assert_eq!(utc(0), "1970-01-01T00:00:00Z");
        assert_eq!(utc(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(utc(1_735_689_599), "2024-12-31T23:59:59Z");
    }
}
