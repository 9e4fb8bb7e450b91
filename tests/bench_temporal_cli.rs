//! `splash bench temporal` on real frames (dense-dambreak 120–124 from `../shared`, skipped
//! without it): a row per variant in the jitter table, and the carried figure split by part
//! (body, pieces, droplets) with shares of the vertices that add up to the whole.

mod common;

use std::process::Command;

use common::{finish, shared_data};

#[test]
fn bench_temporal_splits_the_carried_jitter_by_part() {
    let Some(dir) = shared_data("dense-dambreak") else {
        return;
    };
    let output = Command::new(env!("CARGO_BIN_EXE_splash"))
        .args(["bench", "temporal", dir.to_str().unwrap()])
        .args(["--frames", "120-124", "--spacing", "0.04", "--threads", "2"])
        .args(["--peer", "none"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    finish("splash bench temporal".into(), output).ok();
    let (jitter, parts) = stdout
        .split_once("Carried jitter by part")
        .unwrap_or_else(|| panic!("no table by part in:\n{stdout}"));
    let rows = |table: &str| -> Vec<Vec<String>> {
        table
            .lines()
            .filter(|l| l.starts_with("| ") && !l.starts_with("| mesh"))
            .map(|l| {
                l.trim_matches('|')
                    .split('|')
                    .map(|c| c.trim().to_string())
                    .collect()
            })
            .collect()
    };
    let names = |rows: &[Vec<String>]| rows.iter().map(|r| r[0].clone()).collect::<Vec<_>>();
    let (jitter, parts) = (rows(jitter), rows(parts));
    assert_eq!(names(&jitter), ["raw", "single-frame", "temporal"]);
    assert_eq!(names(&parts), names(&jitter));
    for row in &parts {
        // "0.0127 (84.5 %)": a finite RMS and a share; the shares make the whole.
        let mut total = 0.0;
        for cell in &row[1..] {
            let (rms, share) = cell.split_once(" (").expect(cell);
            let rms: f64 = rms.parse().expect(cell);
            assert!(rms.is_finite() && rms >= 0.0, "{cell}");
            total += share.trim_end_matches(" %)").parse::<f64>().expect(cell);
        }
        assert_eq!(row.len(), 4, "{row:?}");
        assert!(
            (total - 100.0).abs() < 0.2,
            "{row:?}: shares add up to {total} %"
        );
    }
}
