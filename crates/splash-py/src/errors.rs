//! The library's errors as Python exceptions, with the message the command line prints.

use std::io::ErrorKind;

use pyo3::PyErr;
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyPermissionError, PyValueError};
use splash_sph::Error;

/// `Error::Io` is an `OSError` (its subclass for a missing file or a refused permission);
/// everything else is about the data or the settings, a `ValueError`.
pub fn to_py(e: Error) -> PyErr {
    let message = e.to_string();
    match &e {
        Error::Io { io_error, .. } => match io_error.kind() {
            ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
            ErrorKind::PermissionDenied => PyPermissionError::new_err(message),
            _ => PyOSError::new_err(message),
        },
        _ => PyValueError::new_err(message),
    }
}
