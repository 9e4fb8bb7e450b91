//! The helpers of the library's integration tests: those shared with its unit tests and the
//! command line's tests, and the readers' failure check.
#![allow(dead_code)]

use std::path::Path;

mod support;
pub use support::*;

/// Reads `path`, which must fail within a second (a huge allocation or a scan of a declared
/// count would take far longer) with a message naming the file and holding every `expected`.
pub fn assert_read_fails(
    path: &Path,
    format: Option<splash_sph::io::InputFormat>,
    expected: &[&str],
) {
    let start = std::time::Instant::now();
    let result = splash_sph::read_particles(path, format);
    let elapsed = start.elapsed();
    let message = match result {
        Ok(points) => panic!("{} read {} particles", path.display(), points.len()),
        Err(e) => e.to_string(),
    };
    let name = path.file_name().unwrap().to_string_lossy();
    assert!(message.contains(&*name), "no file name in: {message}");
    for want in expected {
        assert!(message.contains(want), "no '{want}' in: {message}");
    }
    assert!(
        elapsed < std::time::Duration::from_secs(1),
        "{message}: took {elapsed:?}"
    );
}
