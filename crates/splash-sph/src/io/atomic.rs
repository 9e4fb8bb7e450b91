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
pub(crate) fn write_file(
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
/// (`.{name}.tmp-{pid}-{n}` whose process is gone): now that the file is complete, they are
/// garbage. Temporaries of live processes, this one included, are another write in progress
/// (a re-queued farm job writing the same frames) and must stay for its rename. Best effort.
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
        let file_name = entry.file_name();
        let Some(suffix) = file_name
            .to_string_lossy()
            .strip_prefix(&prefix)
            .map(str::to_owned)
        else {
            continue;
        };
        if path != ours && writer_is_dead(&suffix) {
            let _ = fs::remove_file(path);
        }
    }
}

/// Whether the writer of a temporary whose name ends in `{pid}-{n}` is known to be dead. A name
/// that does not parse, or a system without `/proc`, gives no proof: the temporary is kept.
fn writer_is_dead(suffix: &str) -> bool {
    let Some(pid) = suffix
        .split_once('-')
        .and_then(|(pid, _)| pid.parse::<u32>().ok())
    else {
        return false;
    };
    let proc = Path::new("/proc");
    pid != process::id() && proc.join("self").exists() && !proc.join(pid.to_string()).exists()
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

#[cfg(test)]
mod tests {
    use super::*;

    // Liveness is read from /proc.
    #[cfg(target_os = "linux")]
    #[test]
    fn only_temporaries_of_dead_writers_are_removed() {
        let dir = std::env::temp_dir().join(format!("splash-atomic-{}", process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        // A child that has been waited for is dead, and its pid is not reused this soon.
        let mut child = process::Command::new("true").spawn().unwrap();
        let dead = child.id();
        child.wait().unwrap();
        let mut live = process::Command::new("sleep").arg("60").spawn().unwrap();
        let names = [
            format!(".f.obj.tmp-{dead}-0"),
            format!(".f.obj.tmp-{}-0", live.id()),
            format!(".f.obj.tmp-{}-999", process::id()),
            ".f.obj.tmp-unknown".to_owned(),
        ];
        for name in &names {
            fs::write(dir.join(name), "partial").unwrap();
        }
        write_file(&dir.join("f.obj"), |f| io::Write::write_all(f, b"mesh")).unwrap();
        live.kill().unwrap();
        live.wait().unwrap();
        let mut left: Vec<String> = fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        let mut expected = vec!["f.obj".to_owned()];
        expected.extend(names[1..].iter().cloned());
        expected.sort();
        assert_eq!(left, expected);
        fs::remove_dir_all(&dir).unwrap();
    }
}
