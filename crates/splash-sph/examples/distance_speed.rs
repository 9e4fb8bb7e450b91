//! How long `--temporal`'s distance queries take: binning one mesh's triangles
//! ([`SurfaceBins`], reach 3r as the following uses) and the signed distance to it from every
//! vertex of another ([`SignedDistance`]), on one thread, with the minimum and median over the
//! runs and a checksum of the distances' bits, so that two builds can be checked to give the
//! same values.
//!
//! `cargo run --release --example distance_speed -- MESH_T.obj MESH_T+1.obj SPACING [RUNS]`,
//! e.g. two consecutive meshes of `splash recon --temporal`. Frame t's vertices are queried where
//! they are, not carried by the fluid: most lie within r/4 of frame t+1's surface, a little
//! farther than the carried vertices that the following queries.

use std::path::Path;
use std::time::{Duration, Instant};

use splash_sph::io::read_mesh;
use splash_sph::mesh::{Cursor, SignedDistance, SurfaceBins};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "MESH_T MESH_T+1 SPACING [RUNS]";
    let (Some(from), Some(to), Some(spacing)) = (args.first(), args.get(1), args.get(2)) else {
        return Err(usage.into());
    };
    let from = read_mesh(Path::new(from))?.mesh;
    let to = read_mesh(Path::new(to))?.mesh;
    let reach = 3.0 * spacing.parse::<f32>()?;
    let runs: usize = args.get(3).map_or(Ok(20), |r| r.parse())?;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let (mut binning, mut queries) = (Vec::new(), Vec::new());
    let mut checksum = 0u64;
    for _ in 0..runs {
        let start = Instant::now();
        let bins = pool.install(|| SurfaceBins::new(&to.vertices, &to.triangles, reach));
        binning.push(start.elapsed());
        let surface = SignedDistance::with_bins(&to.vertices, &to.triangles, &bins);
        let start = Instant::now();
        let mut cursor = Cursor::default();
        checksum = from.vertices.iter().fold(0u64, |sum, &v| {
            let d = surface
                .at_from(v, &mut cursor)
                .map_or(u32::MAX, f32::to_bits);
            sum.rotate_left(5) ^ u64::from(d)
        });
        queries.push(start.elapsed());
    }
    let figures = |times: &mut Vec<Duration>| {
        times.sort();
        (times[0].as_secs_f64(), times[times.len() / 2].as_secs_f64())
    };
    let (bins_min, bins_median) = figures(&mut binning);
    let (query_min, query_median) = figures(&mut queries);
    let per_query = 1e9 / from.vertices.len() as f64;
    println!(
        "{} triangles binned: min {:.2} ms, median {:.2} ms",
        to.triangles.len(),
        bins_min * 1e3,
        bins_median * 1e3
    );
    println!(
        "{} queries: min {:.0} ns, median {:.0} ns a query; checksum {checksum:016x}",
        from.vertices.len(),
        query_min * per_query,
        query_median * per_query
    );
    Ok(())
}
