//! Atomic file replacement: readers of the destination see the old file or the new one, never
//! a partial write.

use std::ffi::OsString;
use std::fs::{self, File};
use std::io;
use std::path::Path;
use std::process;
use std::sync::atomic::{AtomicU64, Ordering};

use super::failure::IoFailure;

/// Distinguishes temporaries of concurrent writes from one process.
static NEXT_TEMPORARY: AtomicU64 = AtomicU64::new(0);

/// Writes `path` through `write` into `.{name}.tmp-{pid}-{n}` next to it, fsyncs and renames it
/// onto `path`; on any error removes the temporary. Creates missing parent directories.
pub(super) fn write_file(
    path: &Path,
    write: impl FnOnce(&mut File) -> io::Result<()>,
) -> crate::Result<()> {
    replace(path, write)
        .map_err(|e| e.into_error(path, format_args!("cannot write '{}'", path.display())))
}

fn replace(path: &Path, write: impl FnOnce(&mut File) -> io::Result<()>) -> Result<(), IoFailure> {
    let Some(name) = path.file_name() else {
        let message = "the path has no file name";
        return Err(IoFailure::of_kind(io::ErrorKind::InvalidInput, message));
    };
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    fs::create_dir_all(dir).map_err(|e| {
        IoFailure::new(
            format_args!("cannot create the directory '{}'", dir.display()),
            e,
        )
    })?;
    let mut temporary = OsString::from(".");
    temporary.push(name);
    temporary.push(format!(
        ".tmp-{}-{}",
        process::id(),
        NEXT_TEMPORARY.fetch_add(1, Ordering::Relaxed)
    ));
    let temporary = dir.join(temporary);
    let result = write_temporary(&temporary, path, write);
    if result.is_err() {
        // Best effort: the error being reported is the one that matters.
        let _ = fs::remove_file(&temporary);
    }
    result?;
    remove_leftovers(dir, name, &temporary);
    // Persists the rename itself; not every filesystem can sync a directory, hence best effort.
    if let Ok(dir) = File::open(dir) {
        let _ = dir.sync_all();
    }
    Ok(())
}

/// Removes the temporaries of earlier writes of `name` that were killed before their rename
/// (`.{name}.tmp-*` other than `ours`, already renamed): now that the file is complete, they are
/// garbage. Best effort.
fn remove_leftovers(dir: &Path, name: &std::ffi::OsStr, ours: &Path) {
    let mut prefix = OsString::from(".");
    prefix.push(name);
    prefix.push(".tmp-");
    let prefix = prefix.to_string_lossy().into_owned();
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if entry.file_name().to_string_lossy().starts_with(&prefix) && path != ours {
            let _ = fs::remove_file(path);
        }
    }
}

fn write_temporary(
    temporary: &Path,
    path: &Path,
    write: impl FnOnce(&mut File) -> io::Result<()>,
) -> Result<(), IoFailure> {
    let failed = |doing: &str, e| {
        let doing = format!(
            "cannot {doing} the temporary file '{}'",
            temporary.display()
        );
        IoFailure::new(doing, e)
    };
    let mut file = File::create(temporary).map_err(|e| failed("create", e))?;
    write(&mut file).map_err(|e| failed("write", e))?;
    file.sync_all().map_err(|e| failed("sync", e))?;
    drop(file);
    fs::rename(temporary, path).map_err(|e| {
        let doing = format!(
            "cannot rename the temporary file '{}' onto the target",
            temporary.display()
        );
        IoFailure::new(doing, e)
    })
}
