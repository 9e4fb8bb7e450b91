//! The helpers of the command line's tests: the library's particle sets, fixtures and scratch
//! directories, and runs of the `splash` binary with their JSON log.
#![allow(dead_code)]

use std::process::Output;

#[path = "../../crates/splash-sph/tests/common/support.rs"]
mod support;
pub use support::*;

/// A finished run of the `splash` binary.
pub struct Run {
    pub command: String,
    pub success: bool,
    pub stderr: String,
}

impl Run {
    pub fn ok(self) -> Self {
        assert!(self.success, "{} failed:\n{}", self.command, self.stderr);
        self
    }

    pub fn failed(self) -> Self {
        assert!(
            !self.success,
            "{} succeeded:\n{}",
            self.command, self.stderr
        );
        self
    }

    pub fn has(self, text: &str) -> Self {
        assert!(
            self.stderr.contains(text),
            "{}: no '{text}' in:\n{}",
            self.command,
            self.stderr
        );
        self
    }

    /// The JSON log lines of one event kind (every line must be an object; serde_json writes
    /// them, so they are well-formed).
    pub fn events(&self, kind: &str) -> Vec<Event> {
        let tag = format!("{{\"event\":\"{kind}\"");
        self.stderr
            .lines()
            .inspect(|l| assert!(l.starts_with('{') && l.ends_with('}'), "not JSON: {l}"))
            .filter(|l| l.starts_with(&tag))
            .map(|l| Event(l.to_owned()))
            .collect()
    }

    /// Frame numbers of the `frame` events, in log order.
    pub fn frames(&self) -> Vec<u64> {
        self.events("frame")
            .iter()
            .map(|e| e.get("frame").parse().unwrap())
            .collect()
    }
}

/// One JSON log line. Parsing it with serde_json would add 15-20 s to this test's build on two
/// cores; splash writes flat objects whose top-level fields are found by name.
pub struct Event(pub String);

impl Event {
    /// The raw JSON text of top-level field `key`: `12`, `"3/4"`, `[…]`.
    pub fn get(&self, key: &str) -> &str {
        let text = &self.0;
        let start = text
            .find(&format!("\"{key}\":"))
            .unwrap_or_else(|| panic!("no {key} in {text}"))
            + key.len()
            + 3;
        let (mut depth, mut quoted, mut escaped) = (0, false, false);
        for (i, c) in text[start..].char_indices() {
            if std::mem::take(&mut escaped) {
                continue;
            }
            match c {
                '\\' if quoted => escaped = true,
                '"' => quoted = !quoted,
                '[' | '{' if !quoted => depth += 1,
                ']' | '}' if !quoted && depth > 0 => depth -= 1,
                ',' | '}' if !quoted && depth == 0 => return &text[start..start + i],
                _ => {}
            }
        }
        panic!("unterminated {key} in {text}")
    }
}

/// The run of `command` that gave `output`; it must not have panicked.
pub fn finish(command: String, output: Output) -> Run {
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(
        output.status.code().is_some() && !stderr.contains("panicked"),
        "{command}: {}\n{stderr}",
        output.status
    );
    Run {
        command,
        success: output.status.success(),
        stderr,
    }
}
