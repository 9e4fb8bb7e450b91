//! `splash config show` and `--field`: what a render-farm job records is what runs.

use std::process::Command;

fn splash(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_splash"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn shown_configuration_reproduces_the_same_mesh() {
    let dir = std::env::temp_dir().join(format!("splash-config-show-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let frame = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/frame_0010.ply");
    let shown = splash(&[
        "config",
        "show",
        "--field",
        "density",
        "--spacing",
        "0.014",
        "--cell",
        "r",
    ]);
    assert!(shown.status.success());
    let text = String::from_utf8(shown.stdout).unwrap();
    assert!(
        text.contains("kind = \"density\"") && text.contains("iso = 0.6"),
        "{text}"
    );
    let file = dir.join("shown.toml");
    std::fs::write(&file, &text).unwrap();
    let (a, b) = (dir.join("a.ply"), dir.join("b.ply"));
    let from_flags = splash(&[
        "recon",
        frame,
        "--field",
        "density",
        "--spacing",
        "0.014",
        "--cell",
        "r",
        "-o",
        a.to_str().unwrap(),
    ]);
    let from_file = splash(&[
        "recon",
        frame,
        "--config",
        file.to_str().unwrap(),
        "-o",
        b.to_str().unwrap(),
    ]);
    assert!(from_flags.status.success() && from_file.status.success());
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn flags_override_the_file_and_typos_are_errors() {
    let preset = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/zb05.toml");
    let out = splash(&[
        "config",
        "show",
        "--config",
        preset,
        "--cell",
        "r/2",
        "--normals",
        "grid",
    ]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("cell = \"r/2\"")
            && text.contains("kind = \"zb05\"")
            && text.contains("normals = \"grid\""),
        "{text}"
    );
    let dir = std::env::temp_dir().join(format!("splash-config-typo-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("typo.toml");
    std::fs::write(&bad, "[field]\nkind = \"density\"\nios = 0.5\n").unwrap();
    let out = splash(&["config", "show", "--config", bad.to_str().unwrap()]);
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(!out.status.success());
    // At the key's line, not at [field]'s (line 1).
    assert!(
        err.contains("typo.toml: TOML parse error at line 3, column 1")
            && err.contains("3 | ios = 0.5")
            && err.contains("unknown field `ios`"),
        "{err}"
    );
    std::fs::write(&bad, "[field]\nkind = \"ssp07\"\nt_low = 4.0\n").unwrap();
    let out = splash(&["config", "show", "--config", bad.to_str().unwrap()]);
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        err.contains("typo.toml: invalid configuration at line 3, column 9")
            && err.contains("3 | t_low = 4.0")
            && err.contains("field.t_low (4) must be below field.t_high (3.5)"),
        "{err}"
    );
    let out = splash(&["config", "show", "--field", "splat"]);
    assert!(
        String::from_utf8(out.stderr)
            .unwrap()
            .contains("unknown field 'splat'")
    );
    let out = splash(&["config", "show", "--volume-scope", "droplet"]);
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        !out.status.success()
            && err.contains(
                "--volume-scope: unknown volume scope 'droplet': expected frame or component"
            ),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn normals_flag_chooses_what_the_obj_carries() {
    let dir = std::env::temp_dir().join(format!("splash-normals-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let frame = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/frame_0010.ply");
    let mut counts = Vec::new();
    for normals in ["field", "grid", "none"] {
        let out = dir.join(format!("{normals}.obj"));
        let run = splash(&[
            "recon",
            frame,
            "--spacing",
            "0.014",
            "--cell",
            "r",
            "--normals",
            normals,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(run.status.success(), "{run:?}");
        let text = std::fs::read_to_string(&out).unwrap();
        let count = |p: &str| text.lines().filter(|l| l.starts_with(p)).count();
        counts.push((normals, count("v "), count("vn "), count("f ")));
    }
    let [(_, v, vn_field, f), (_, _, vn_grid, _), (_, _, vn_none, _)] = counts[..] else {
        unreachable!()
    };
    assert!(v > 0 && f > 0);
    assert_eq!((vn_field, vn_grid, vn_none), (v, v, 0), "{counts:?}");
    assert!(counts.iter().all(|c| c.1 == v && c.3 == f), "{counts:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn shown_configuration_records_the_whole_run() {
    let dir = std::env::temp_dir().join(format!("splash-config-run-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let frame = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/frame_0010.ply");
    let run = [
        "--spacing",
        "0.014",
        "--cell",
        "r",
        "--engine",
        "slices",
        "--threads",
        "1",
        "--max-memory",
        "2G",
        "--format",
        "ply",
        "--up-axis",
        "z",
        "--attributes",
        "velocity",
        "--volume-scope",
        "component",
    ];
    let shown = splash(&[&["config", "show"][..], &run].concat());
    assert!(shown.status.success(), "{shown:?}");
    let text = String::from_utf8(shown.stdout).unwrap();
    for line in [
        "engine = \"slices\"",
        "threads = 1",
        "max_memory = \"2G\"",
        "format = \"ply\"",
        "up_axis = \"z\"",
        "attributes = [\"velocity\"]",
        "volume_scope = \"component\"",
    ] {
        assert!(text.contains(line), "no '{line}' in\n{text}");
    }
    // The shown file alone runs the same job: same bytes as the flags.
    let file = dir.join("run.toml");
    std::fs::write(&file, &text).unwrap();
    let (a, b) = (dir.join("a.ply"), dir.join("b.ply"));
    let from_flags = splash(&[&["recon", frame, "-o", a.to_str().unwrap()][..], &run].concat());
    let config = file.to_str().unwrap();
    let from_file = splash(&[
        "recon",
        frame,
        "--config",
        config,
        "-o",
        b.to_str().unwrap(),
    ]);
    assert!(from_flags.status.success(), "{from_flags:?}");
    assert!(from_file.status.success(), "{from_file:?}");
    let bytes = std::fs::read(&b).unwrap();
    assert_eq!(std::fs::read(&a).unwrap(), bytes);
    let header = String::from_utf8_lossy(&bytes[..400.min(bytes.len())]).into_owned();
    assert!(header.contains("property float vx"), "{header}");
    // A bad value in the file is refused, naming the file and the key.
    std::fs::write(
        &file,
        text.replace("engine = \"slices\"", "engine = \"fast\""),
    )
    .unwrap();
    let bad = splash(&["config", "show", "--config", config]);
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        !bad.status.success() && err.contains("run.toml") && err.contains("engine"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn cell_r_over_n_is_a_length_like_its_decimal() {
    let show = |cell: &str| {
        let out = splash(&["config", "show", "--spacing", "0.014", "--cell", cell]);
        assert!(out.status.success(), "--cell {cell}: {out:?}");
        String::from_utf8(out.stdout).unwrap()
    };
    let quarter = show("r/4");
    assert!(quarter.contains("cell = \"0.25r\""), "{quarter}");
    assert_eq!(quarter, show("0.25r"));
    assert_eq!(show("3r/2"), show("1.5r"));
}
