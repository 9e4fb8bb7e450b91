//! Records the git revision, when the sources are a git checkout, for the reports' "build".

use std::process::Command;

fn main() {
    println!("cargo:rerun-if-changed=.git/HEAD");
    println!("cargo:rerun-if-changed=.git/refs/heads");
    let revision = Command::new("git")
        .args(["rev-parse", "--short=12", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok());
    if let Some(rev) = revision {
        println!("cargo:rustc-env=SPLASH_GIT_REVISION={}", rev.trim());
    }
}
