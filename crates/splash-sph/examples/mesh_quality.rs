//! The render-quality table of issue 25 over a folder of PLY meshes (splash's, or any other
//! tool's), each against the particle frame of the same file name:
//!
//!   cargo run --release --example mesh_quality -- --spacing 0.014 PARTICLES_DIR MESH_DIR [SLIVER_FRAME]
//!
//! Prints one row per mesh (volume error V/(N·r³) − 1, bumpiness, slivers, faces,
//! closed/manifold, components of ≤ 20 faces, self-intersecting faces; see
//! `splash_sph::mesh::Quality`), then the summary row of the table: volume error
//! min … max (mean abs), mean bumpiness, slivers of SLIVER_FRAME (a file name; the first mesh
//! when absent), mean faces; and the self-intersecting faces of all meshes.

use std::path::{Path, PathBuf};

use splash_sph::io::read_mesh;
use splash_sph::mesh::{quality, volume_error};
use splash_sph::read_particles;

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: mesh_quality --spacing R PARTICLES_DIR MESH_DIR [SLIVER_FRAME]";
    let (spacing, rest) = match args.as_slice() {
        [flag, r, rest @ ..] if flag == "--spacing" => (
            r.parse::<f32>().map_err(|e| format!("--spacing: {e}"))?,
            rest,
        ),
        _ => return Err(usage.into()),
    };
    let [particles, meshes, sliver_frame @ ..] = rest else {
        return Err(usage.into());
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(meshes)
        .map_err(|e| format!("{meshes}: {e}"))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "ply"))
        .collect();
    files.sort();
    println!(
        "mesh\tvolume_error_%\tbumpiness_deg\tslivers_%\tfaces\tclosed_manifold\tcomponents\tsmall_components\tself_intersecting_faces"
    );
    let (mut errors, mut bumps, mut faces) = (Vec::new(), Vec::new(), Vec::new());
    let mut sliver_row = None;
    let (mut crossing, mut crossed) = (0, 0);
    for file in &files {
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        let frame = Path::new(particles).join(&name);
        let n = read_particles(&frame, None)
            .map_err(|e| e.to_string())?
            .positions
            .len();
        let q = quality(&read_mesh(file).map_err(|e| e.to_string())?.mesh);
        let error = volume_error(q.volume, n, spacing);
        println!(
            "{name}\t{:+.2}\t{:.3}\t{:.3}\t{}\t{}\t{}\t{}\t{}",
            100.0 * error,
            q.bumpiness,
            100.0 * q.slivers,
            q.faces,
            q.closed_manifold,
            q.components,
            q.small_components,
            q.self_intersecting_faces
        );
        crossing += q.self_intersecting_faces;
        crossed += usize::from(q.self_intersecting_faces > 0);
        if sliver_row.is_none() || sliver_frame.first() == Some(&name) {
            sliver_row = Some((name.clone(), q.slivers));
        }
        errors.push(error);
        bumps.push(q.bumpiness);
        faces.push(q.faces as f64);
    }
    if files.is_empty() {
        return Err(format!("{meshes}: no .ply files"));
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (lo, hi) = errors
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &e| {
            (a.min(e), b.max(e))
        });
    let abs: Vec<f64> = errors.iter().map(|e| e.abs()).collect();
    let (sliver_name, slivers) = sliver_row.unwrap();
    println!(
        "summary ({} meshes): volume error {:+.1} % … {:+.1} % ({:.1} %) | bumpiness {:.2}° | \
         slivers {:.2} % ({sliver_name}) | faces {:.0} k",
        files.len(),
        100.0 * lo,
        100.0 * hi,
        100.0 * mean(&abs),
        mean(&bumps),
        100.0 * slivers,
        mean(&faces) / 1000.0
    );
    println!(
        "self-intersecting faces: {crossing} in {crossed} of {} meshes",
        files.len()
    );
    Ok(())
}
