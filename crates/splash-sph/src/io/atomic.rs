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
    write: impl FnOnce(&mut Writeback) -> io::Result<()>,
) -> crate::error::Result<()> {
    replace(path, write)
        .map_err(|e| e.into_error(path, format_args!("cannot write '{}'", path.display())))
}

fn replace(
    path: &Path,
    write: impl FnOnce(&mut Writeback) -> io::Result<()>,
) -> Result<(), IoFailure> {
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
    write: impl FnOnce(&mut Writeback) -> io::Result<()>,
) -> Result<(), IoFailure> {
    let failed = |doing: &str, e| {
        let doing = format!(
            "cannot {doing} the temporary file '{}'",
            temporary.display()
        );
        IoFailure::new(doing, e)
    };
    let file = File::create(temporary).map_err(|e| failed("create", e))?;
    let mut out = Writeback {
        file,
        written: 0,
        started: 0,
    };
    write(&mut out).map_err(|e| failed("write", e))?;
    let file = out.file;
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

/// Bytes written between requests to start writing them to disk.
const WRITEBACK_BYTES: u64 = 4 << 20;

/// The temporary file, which asks the kernel every [`WRITEBACK_BYTES`] to start writing what
/// it has been given to disk, without waiting (Linux's `sync_file_range`): the disk then works
/// while the rest is encoded, and the final fsync finds most of the file written.
pub(crate) struct Writeback {
    file: File,
    written: u64,
    started: u64,
}

impl io::Write for Writeback {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.file.write(buf)?;
        self.written += n as u64;
        if self.written - self.started >= WRITEBACK_BYTES {
            start_writeback(&self.file, self.started, self.written - self.started);
            self.started = self.written;
        }
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.file.flush()
    }
}

/// Starts writing `len` bytes from `offset` to disk. Best effort: where it fails or the
/// system has no such call, the fsync writes them.
#[cfg(target_os = "linux")]
fn start_writeback(file: &File, offset: u64, len: u64) {
    use std::os::fd::AsRawFd;
    let (Ok(offset), Ok(len)) = (i64::try_from(offset), i64::try_from(len)) else {
        return;
    };
    // SAFETY: the descriptor is open for the call; the call reads no memory of ours.
    unsafe {
        libc::sync_file_range(file.as_raw_fd(), offset, len, libc::SYNC_FILE_RANGE_WRITE);
    }
}

#[cfg(not(target_os = "linux"))]
fn start_writeback(_: &File, _: u64, _: u64) {}

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

    #[test]
    fn files_larger_than_the_writeback_step_are_written_whole() {
        let dir = std::env::temp_dir().join(format!("splash-writeback-{}", process::id()));
        let _ = fs::remove_dir_all(&dir);
        let path = dir.join("big.ply");
        // Odd-sized writes, so that the writeback steps fall inside them.
        let bytes: Vec<u8> = (0..2 * WRITEBACK_BYTES + 12_345)
            .map(|i| (i * 7 % 251) as u8)
            .collect();
        write_file(&path, |f| {
            bytes
                .chunks(1_000_003)
                .try_for_each(|c| io::Write::write_all(f, c))
        })
        .unwrap();
        assert!(fs::read(&path).unwrap() == bytes);
        fs::remove_dir_all(&dir).unwrap();
    }
}
