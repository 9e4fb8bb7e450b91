//! How long the mesh writers take on one mesh, in memory and to a file (temporary, fsync,
//! rename), in every output format, each run timing every format in turn (so that they are
//! compared under the same load), with the minimum and median over the runs (the minimum
//! is the figure a shared machine disturbs least). The OBJ row is paired with the serial
//! `write!` loop the OBJ writer was before it formatted on all threads, run alternately in the
//! same process, and checked to give the same bytes.
//!
//! `cargo run --release --example write_speed -- MESH.ply [RUNS] [DIR]`
//! (threads: `RAYON_NUM_THREADS`; files go to DIR, default the system's temporary directory).
//! A mesh to time: `splash recon frame_0040.ply --spacing 0.014 --cell r/2 --raw -o f40.ply`.

use std::io::{self, BufWriter, Write};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use splash_sph::io::{read_mesh, write_mesh, write_mesh_file};
use splash_sph::{MeshFormat, TriMesh};

/// The OBJ writer as it was, one `write!` per line on one thread.
fn obj_serial(mesh: &TriMesh, out: &mut impl Write) -> io::Result<()> {
    let mut out = BufWriter::with_capacity(1 << 16, out);
    writeln!(
        out,
        "# splash mesh: {} vertices, {} triangles",
        mesh.vertices.len(),
        mesh.triangles.len()
    )?;
    for v in &mesh.vertices {
        writeln!(out, "v {} {} {}", v.x, v.y, v.z)?;
    }
    for n in &mesh.normals {
        writeln!(out, "vn {} {} {}", n.x, n.y, n.z)?;
    }
    let with_normals = !mesh.normals.is_empty();
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| u64::from(i) + 1);
        if with_normals {
            writeln!(out, "f {a}//{a} {b}//{b} {c}//{c}")?;
        } else {
            writeln!(out, "f {a} {b} {c}")?;
        }
    }
    out.flush()
}

fn ms(d: Duration) -> String {
    format!("{:.1}", d.as_secs_f64() * 1e3)
}

/// "min / median" of the times.
fn summary(mut times: Vec<Duration>) -> String {
    times.sort();
    format!("{} / {}", ms(times[0]), ms(times[times.len() / 2]))
}

fn time(f: &mut impl FnMut()) -> Duration {
    let start = Instant::now();
    f();
    start.elapsed()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = PathBuf::from(
        args.next()
            .ok_or("usage: write_speed MESH.ply [RUNS] [DIR]")?,
    );
    let runs: usize = args.next().map_or(Ok(15), |n| n.parse())?;
    let dir = args.next().map_or_else(std::env::temp_dir, PathBuf::from);
    let mesh = read_mesh(&path)?.mesh;
    println!(
        "{}: {} vertices, {} triangles, {} threads, {runs} runs; ms min / median",
        path.display(),
        mesh.vertices.len(),
        mesh.triangles.len(),
        rayon::current_num_threads()
    );
    println!(
        "| format | bytes | in memory | to a file | serial write! in memory | ratio of minima |"
    );
    println!("|---|---|---|---|---|---|");
    let formats = [
        ("obj", MeshFormat::Obj),
        ("pov", MeshFormat::Pov),
        ("ply-ascii", MeshFormat::PlyAscii),
        ("ply", MeshFormat::PlyBinary),
        ("vtk", MeshFormat::Vtk),
        ("vtu", MeshFormat::Vtu),
        ("usd", MeshFormat::Usd),
    ];
    // Each run times every format in turn, so that the formats are compared pair by pair
    // under the same load.
    let n = formats.len();
    let (mut memory, mut to_file) = (vec![Vec::new(); n], vec![Vec::new(); n]);
    let mut serial = Vec::new();
    let mut sizes = vec![0; n];
    let mut buffer = Vec::new();
    for run in 0..runs {
        for (k, &(_, format)) in formats.iter().enumerate() {
            let file = dir.join(format!(
                "write-speed-{}.{}",
                std::process::id(),
                format.extension()
            ));
            memory[k].push(time(&mut || {
                buffer.clear();
                write_mesh(&mesh, format, &mut buffer).unwrap();
            }));
            sizes[k] = buffer.len();
            let bytes = std::mem::take(&mut buffer);
            to_file[k].push(time(&mut || write_mesh_file(&file, &mesh, format).unwrap()));
            if format == MeshFormat::Obj {
                serial.push(time(&mut || {
                    buffer.clear();
                    obj_serial(&mesh, &mut buffer).unwrap();
                }));
                assert!(buffer == bytes, "the serial OBJ writer gives other bytes");
            }
            buffer = bytes;
            if run + 1 == runs {
                std::fs::remove_file(&file)?;
            }
        }
    }
    for (k, &(name, format)) in formats.iter().enumerate() {
        let (paired, ratio) = if format != MeshFormat::Obj {
            (String::new(), String::new())
        } else {
            let ratio = memory[k].iter().min().unwrap().as_secs_f64()
                / serial.iter().min().unwrap().as_secs_f64();
            (summary(serial.clone()), format!("{ratio:.2}"))
        };
        println!(
            "| {name} | {} | {} | {} | {paired} | {ratio} |",
            sizes[k],
            summary(memory[k].clone()),
            summary(to_file[k].clone())
        );
    }
    Ok(())
}
