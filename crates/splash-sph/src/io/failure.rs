//! The readers' and writers' errors before the file's path is added: [`super::read_particles`],
//! [`super::read_mesh`] and [`super::write_mesh_file`] turn them into the library's [`Error`].

use std::fmt::Display;
use std::io;
use std::path::Path;

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
