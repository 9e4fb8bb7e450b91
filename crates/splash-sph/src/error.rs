//! The library's error: every failure names what was wrong (and the file, where there is one);
//! its variant says whose it is, so that callers can react (a Python binding raises `OSError`
//! for [`Error::Io`], `ValueError` for the others).

use std::path::PathBuf;

/// What went wrong.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be opened, read or written; `message` names the file and ends with
    /// the operating system's reason.
    #[error("{message}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What failed, naming the file, then why ("…: No such file or directory (os error 2)").
        message: String,
        /// The operating system's error, for its kind. Its text already ends `message`, so it
        /// is not also the error's `source()`: chains of causes print it once.
        io_error: std::io::Error,
    },
    /// A particle file whose content is not a valid frame of its format.
    #[error("cannot read particles from '{}': {message}", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong with it, with the line or byte where that helps.
        message: String,
    },
    /// A mesh file whose content is not a mesh of its format (see [`crate::io::read_mesh`]).
    #[error("cannot read a mesh from '{}': {message}", path.display())]
    MeshFormat {
        /// The file.
        path: PathBuf,
        /// What is wrong with it, with the line or byte where that helps.
        message: String,
    },
    /// A configuration that cannot be used: unknown keys or names, values out of range.
    #[error("{0}")]
    Config(String),
    /// Input data the reconstruction cannot use: non-finite coordinates, attributes whose
    /// length differs from the particles'.
    #[error("{0}")]
    Input(String),
    /// The work would exceed a limit: the memory limit, or a grid too large to index.
    #[error("{0}")]
    Limit(String),
}

/// `Result` with the library's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    pub(crate) fn config(message: impl Into<String>) -> Error {
        Error::Config(message.into())
    }

    pub(crate) fn input(message: impl Into<String>) -> Error {
        Error::Input(message.into())
    }

    pub(crate) fn limit(message: impl Into<String>) -> Error {
        Error::Limit(message.into())
    }

    /// Prefixes the message with `context` (`"{context}: {message}"`), keeping the variant.
    pub fn context(self, context: impl std::fmt::Display) -> Error {
        match self {
            Error::Io {
                path,
                message,
                io_error,
            } => Error::Io {
                path,
                message: format!("{context}: {message}"),
                io_error,
            },
            Error::Format { path, message } => Error::Format {
                path,
                message: format!("{context}: {message}"),
            },
            Error::MeshFormat { path, message } => Error::MeshFormat {
                path,
                message: format!("{context}: {message}"),
            },
            Error::Config(m) => Error::Config(format!("{context}: {m}")),
            Error::Input(m) => Error::Input(format!("{context}: {m}")),
            Error::Limit(m) => Error::Limit(format!("{context}: {m}")),
        }
    }
}

/// Every word of `message`, and every run of spaces, longer than 40 characters (a value or
/// name quoted from the input) cut to 40, with "…": an error message stays a few lines whatever
/// it quotes.
pub(crate) fn short_words(message: &str) -> String {
    const LONGEST: usize = 40;
    let mut out = String::with_capacity(message.len().min(1024));
    let (mut word, mut space) = (0, false);
    for c in message.chars() {
        let same = c.is_whitespace() == space && c != '\n';
        word = if same { word + 1 } else { 1 };
        space = c.is_whitespace();
        if word <= LONGEST {
            out.push(c);
        } else if word == LONGEST + 1 {
            out.push('…');
        }
    }
    out
}

/// Returns an [`Error::Config`] with a formatted message.
macro_rules! bail_config {
    ($($arg:tt)*) => {
        return Err($crate::error::Error::Config(format!($($arg)*)))
    };
}

/// Returns an [`Error::Input`] with a formatted message.
macro_rules! bail_input {
    ($($arg:tt)*) => {
        return Err($crate::error::Error::Input(format!($($arg)*)))
    };
}

/// Returns an [`Error::Limit`] with a formatted message.
macro_rules! bail_limit {
    ($($arg:tt)*) => {
        return Err($crate::error::Error::Limit(format!($($arg)*)))
    };
}

/// `x` for a message: plain for everyday magnitudes (0.014, 35.7), in scientific notation
/// outside them (1.4e-22, 1e30), where plain digits run to dozens of places.
pub(crate) fn figure(x: f32) -> String {
    if x == 0.0 || (1e-4..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}
