//! Counts the faces of meshes (any format splash reads: PLY, OBJ, VTK, …) that cross another
//! face of the same mesh, with the exact test of `splash_sph::mesh::self_intersecting_faces`,
//! and times it, the best of several runs: the CPU time on one thread (steady on a loaded
//! machine) and the wall time on two.
//!
//!   cargo run --release --example self_intersections -- [--runs N] MESH...
//!
//! Prints one row per mesh (faces, self-intersecting faces, ms) and the totals.

use std::time::Instant;

use splash_sph::io::read_mesh;
use splash_sph::mesh::self_intersecting_faces;

/// The process's CPU time, in ms.
fn cpu_ms() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid timespec to write to.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut t) };
    t.tv_sec as f64 * 1e3 + t.tv_nsec as f64 * 1e-6
}

fn main() -> Result<(), String> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut runs = 3;
    if args.first().is_some_and(|a| a == "--runs") {
        runs = args.get(1).and_then(|n| n.parse().ok()).ok_or("--runs N")?;
        args.drain(..2);
    }
    if args.is_empty() {
        return Err("usage: self_intersections [--runs N] MESH...".into());
    }
    let pools: Vec<rayon::ThreadPool> = [1, 2]
        .iter()
        .map(|&n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| e.to_string())
        })
        .collect::<Result<_, _>>()?;
    println!("mesh\tfaces\tself_intersecting_faces\tcpu_ms_1_thread\twall_ms_2_threads");
    let (mut faces, mut crossing, mut frames, mut ms) = (0, 0, 0, [0.0; 2]);
    for file in &args {
        let mesh = read_mesh(file.as_ref()).map_err(|e| e.to_string())?.mesh;
        let mut found = Vec::new();
        let times: Vec<f64> = pools
            .iter()
            .enumerate()
            .map(|(i, pool)| {
                (0..runs)
                    .map(|_| {
                        let (c, t) = (cpu_ms(), Instant::now());
                        found = pool
                            .install(|| self_intersecting_faces(&mesh.vertices, &mesh.triangles));
                        if i == 0 {
                            cpu_ms() - c
                        } else {
                            t.elapsed().as_secs_f64() * 1e3
                        }
                    })
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        println!(
            "{file}\t{}\t{}\t{:.1}\t{:.1}",
            mesh.triangles.len(),
            found.len(),
            times[0],
            times[1]
        );
        faces += mesh.triangles.len();
        crossing += found.len();
        frames += usize::from(!found.is_empty());
        ms[0] += times[0];
        ms[1] += times[1];
    }
    let n = args.len() as f64;
    println!(
        "total ({} meshes): {faces} faces, {crossing} self-intersecting in {frames} meshes; \
         {:.1} ms per mesh (CPU, 1 thread), {:.1} ms (wall, 2 threads)",
        args.len(),
        ms[0] / n,
        ms[1] / n
    );
    Ok(())
}
