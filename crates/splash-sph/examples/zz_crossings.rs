fn main() {
    for f in std::env::args().skip(1) {
        let m = splash_sph::io::read_mesh(std::path::Path::new(&f))
            .unwrap()
            .mesh;
        let mut best = f64::MAX;
        let mut n = 0;
        for _ in 0..7 {
            let t = std::time::Instant::now();
            let c = splash_sph::mesh::self_intersecting_faces(&m.vertices, &m.triangles);
            best = best.min(t.elapsed().as_secs_f64());
            n = c.len();
        }
        println!("{}\t{}\t{}\t{:.1} ms", f, m.triangles.len(), n, best * 1e3);
    }
}
