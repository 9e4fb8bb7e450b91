//! The readers' and writers' errors before the file's path is added: [`super::read_particles`],
//! [`super::read_mesh`] and [`super::write_mesh_file`] turn them into the library's [`Error`].
//! With the helpers every reader words them with (input opened, coordinates checked, file text
//! quoted short).

use std::fmt::Display;
use std::fs::File;
use std::io;
use std::path::Path;

use glam::Vec3;

use crate::error::Error;

/// An I/O error and what was being done when it happened.
pub(super) struct IoFailure {
    /// The whole message, ending with `source`'s text: "cannot open the file: No such file…".
    pub message: String,
    pub source: io::Error,
}

impl IoFailure {
    pub fn new(doing: impl Display, source: io::Error) -> Self {
        Self {
            message: format!("{doing}: {source}"),
            source,
        }
    }

    /// A failure without an underlying I/O error (a directory where a file should be).
    pub fn of_kind(kind: io::ErrorKind, message: &str) -> Self {
        Self {
            message: message.to_owned(),
            source: io::Error::new(kind, message),
        }
    }

    /// The library's error for `path`, its message prefixed with `what` ("cannot write '…'").
    pub fn into_error(self, path: &Path, what: impl Display) -> Error {
        Error::Io {
            path: path.to_path_buf(),
            message: format!("{what}: {}", self.message),
            io_error: self.source,
        }
    }
}

/// Why a particle or mesh file cannot be read.
pub(super) enum Failure {
    Io(IoFailure),
    /// The content is not a valid frame of its format.
    Format(String),
}

pub(super) type Result<T, E = Failure> = std::result::Result<T, E>;

impl From<IoFailure> for Failure {
    fn from(e: IoFailure) -> Self {
        Self::Io(e)
    }
}

impl Failure {
    pub fn io(doing: impl Display, source: io::Error) -> Self {
        Self::Io(IoFailure::new(doing, source))
    }

    pub fn into_error(self, path: &Path) -> Error {
        match self {
            Self::Io(e) => e.into_error(
                path,
                format_args!("cannot read particles from '{}'", path.display()),
            ),
            Self::Format(message) => Error::Format {
                path: path.to_path_buf(),
                message,
            },
        }
    }
}

impl Failure {
    /// As [`Failure::into_error`], for a mesh file: [`Error::MeshFormat`] for its content.
    pub fn into_mesh_error(self, path: &Path) -> Error {
        match self {
            Self::Io(e) => e.into_error(
                path,
                format_args!("cannot read a mesh from '{}'", path.display()),
            ),
            Self::Format(message) => Error::MeshFormat {
                path: path.to_path_buf(),
                message,
            },
        }
    }
}

/// A [`Failure::Format`] with a formatted message.
macro_rules! format_failure {
    ($($arg:tt)*) => {
        $crate::io::failure::Failure::Format(format!($($arg)*))
    };
}

/// Returns a [`Failure::Format`] with a formatted message.
macro_rules! bail_format {
    ($($arg:tt)*) => {
        return Err(format_failure!($($arg)*))
    };
}

/// Opens a particle file, returning it with its length in bytes.
pub(super) fn open_input(path: &Path) -> Result<(File, u64)> {
    let file = File::open(path).map_err(|e| Failure::io("cannot open the file", e))?;
    let metadata = file
        .metadata()
        .map_err(|e| Failure::io("cannot query the file's size", e))?;
    if metadata.is_dir() {
        // Reading it would fail with a less telling message, on some systems only later.
        let failure = IoFailure::of_kind(io::ErrorKind::IsADirectory, "it is a directory");
        return Err(failure.into());
    }
    Ok((file, metadata.len()))
}

/// A writer's refusal of data it cannot write (`InvalidInput`).
pub(super) fn invalid_input(message: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, message)
}

/// Passes finite points through; `at` says where a non-finite one was found.
#[inline]
pub(super) fn finite(p: Vec3, at: impl FnOnce() -> String) -> Result<Vec3> {
    if p.is_finite() {
        Ok(p)
    } else {
        Err(non_finite(p, &at()))
    }
}

#[cold]
pub(super) fn non_finite(p: Vec3, at: &str) -> Failure {
    format_failure!(
        "{at} has a non-finite coordinate: ({}, {}, {})",
        p.x,
        p.y,
        p.z
    )
}

/// At most this many characters of a file's text are quoted in an error message, and at
/// most this many names listed: a file with no line breaks must not become a megabyte of text.
const QUOTED_CHARS: usize = 40;
const LISTED_NAMES: usize = 12;
const LISTED_CHARS: usize = 120;

/// `text` as an error message quotes it: cut to [`QUOTED_CHARS`] characters, with "…".
pub(super) fn short(text: &str) -> String {
    match text.char_indices().nth(QUOTED_CHARS) {
        Some((end, _)) => format!("{}…", &text[..end]),
        None => text.to_string(),
    }
}

/// A message from elsewhere (a parser's) as an error message quotes it: cut to a few lines'
/// worth, with "…", since it may quote the file.
pub(super) fn short_message(text: &str) -> String {
    match text.char_indices().nth(4 * QUOTED_CHARS) {
        Some((end, _)) => format!("{}…", &text[..end]),
        None => text.to_string(),
    }
}

/// Names joined by commas for an error message: at most [`LISTED_NAMES`], each [`short`], and
/// no more than [`LISTED_CHARS`] characters of them.
pub(super) fn listed<'a>(names: impl IntoIterator<Item = &'a str>) -> String {
    let names: Vec<&str> = names.into_iter().collect();
    let mut out: Vec<String> = Vec::new();
    let mut chars = 0;
    for name in names.iter().take(LISTED_NAMES) {
        let name = short(name);
        chars += name.chars().count() + 2;
        if chars > LISTED_CHARS && !out.is_empty() {
            break;
        }
        out.push(name);
    }
    if names.len() > out.len() {
        out.push(format!("… {} more", names.len() - out.len()));
    }
    out.join(", ")
}
