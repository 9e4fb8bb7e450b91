//! The memory limit (`max_memory`, `--max-memory`) of every engine: estimates of the heap a
//! frame will need, made from what is known before the big allocations (particles, surface
//! particles, band bricks, blocks, mesh counts), and allocations that turn a failure into
//! [`Error::Limit`] instead of aborting the process.
//!
//! Estimates saturate rather than overflow: a grid too large to count is refused like one
//! too large to hold.

use crate::bytes::human;
use crate::config::Params;
use crate::error::{Error, Result};

/// Heap bytes per particle of the handler array: sort pairs (16), positions (12), cell starts
/// (hash map, ~20).
pub const PER_PARTICLE: u64 = 48;

/// Heap bytes per brick of 8³ vertices once its values are sampled, at most: values (2048 when
/// all its vertices are in the band, packed to the band's vertices), mask (64),
/// coordinates (12), index entry (~24), the triangulation's edge table (~350) and the band's
/// build (~50, pairs grouped per brick).
pub const PER_BRICK: u64 = 2048 + 64 + 12 + 24 + 350 + 50;

/// Heap bytes the triangulation holds per mesh vertex at its peak: positions and normals (24),
/// the field normals' gradients (12), and two triangles per vertex (2 × 12).
pub const PER_MESH_VERTEX: u64 = 24 + 12 + 24;

/// Mesh vertices expected per surface particle at cell = r (scaled by (r / cell)²): about 1.6
/// on `fixtures/frame_0040.ply` at cells r and r/2; 2 leaves room for splashier frames.
const VERTICES_PER_SURFACE_PARTICLE: f64 = 2.0;

/// Surface particles expected per particle where they are not counted (full grid, slices), up
/// to [`SURFACE_SCALE`] particles: 0.35 on `fixtures/frame_0040.ply`, a splashy small frame.
const SURFACE_FRACTION: f64 = 0.4;
/// Beyond this many particles the surface is taken to grow as the particles^(2/3), as a
/// fluid's area grows with its volume: 148 k surface particles of 1.05 M in
/// `cbd-large/frame_0023` (the guess: 152 k). The triangulation checks the real mesh.
const SURFACE_SCALE: f64 = 50_000.0;

/// `a × b`, saturating.
pub fn mul(a: u64, b: u64) -> u64 {
    a.saturating_mul(b)
}

/// Mesh vertices expected of `surface` surface particles at `params`' cell.
pub fn mesh_vertices(params: &Params, surface: u64) -> u64 {
    let scale = f64::from(params.spacing / params.cell).powi(2);
    (surface as f64 * VERTICES_PER_SURFACE_PARTICLE * scale).min(u64::MAX as f64) as u64
}

/// Surface particles expected of `particles` particles, for the engines that do not find them.
pub fn surface_guess(particles: usize) -> u64 {
    let n = particles as f64;
    let scaled = if n <= SURFACE_SCALE {
        n
    } else {
        SURFACE_SCALE * (n / SURFACE_SCALE).powf(2.0 / 3.0)
    };
    (scaled * SURFACE_FRACTION).ceil() as u64
}

/// Heap of the triangulation of a mesh of about `vertices` vertices.
pub fn mesh_bytes(vertices: u64) -> u64 {
    mul(vertices, PER_MESH_VERTEX)
}

/// Refuses the frame when `need` bytes exceed the memory limit; `what` says what needs them
/// ("the band of 12 bricks…"). Returns `need`, for the report.
pub fn check(params: &Params, need: u64, what: impl FnOnce() -> String) -> Result<u64> {
    if need > params.max_memory {
        return Err(refusal(params, need, &what()));
    }
    Ok(need)
}

/// The error of a frame that needs `need` bytes for `what`.
pub fn refusal(params: &Params, need: u64, what: &str) -> Error {
    let need = if need == u64::MAX {
        "more bytes than can be counted".to_string()
    } else {
        format!("about {}", human(need))
    };
    Error::limit(format!(
        "the {} engine would need {need} for {what}, above the memory limit of {} \
         (--max-memory); use a larger cell (now {} = {}r) or raise --max-memory",
        params.engine.name(),
        human(params.max_memory),
        short(params.cell),
        short(params.cell / params.spacing),
    ))
}

/// A vector with room for `len` elements, or [`Error::Limit`] naming `what` when the system
/// refuses (or the size overflows) instead of an abort.
pub fn try_vec<T>(len: usize, what: impl FnOnce() -> String) -> Result<Vec<T>> {
    let mut v = Vec::new();
    try_reserve(&mut v, len, what)?;
    Ok(v)
}

/// Reserves room for `additional` more elements of `v`, or [`Error::Limit`] naming `what`.
pub fn try_reserve<T>(
    v: &mut Vec<T>,
    additional: usize,
    what: impl FnOnce() -> String,
) -> Result<()> {
    v.try_reserve_exact(additional)
        .map_err(|_| refused::<T>(additional, what))
}

/// The error of an allocation of `len` elements of `T` for `what` that the system refused.
fn refused<T>(len: usize, what: impl FnOnce() -> String) -> Error {
    let bytes = (len as u128 * size_of::<T>() as u128).min(u128::from(u64::MAX));
    Error::limit(format!(
        "cannot allocate {} for {}: the system refused the memory; use a larger cell or a \
         smaller --max-memory (the limit is checked before allocating)",
        human(bytes as u64),
        what()
    ))
}

/// `len` zeros, as [`try_filled`] gives them, in memory the system hands out zeroed: a large
/// block comes as fresh pages, so that nothing is written here and the threads that fill the
/// array touch its pages (a serial fill of the mesh and the band's values held the other
/// threads up).
pub fn try_zeroed<T: bytemuck::Zeroable + Clone>(
    len: usize,
    what: impl FnOnce() -> String,
) -> Result<Vec<T>> {
    if len == 0 || size_of::<T>() == 0 {
        return try_filled(len, T::zeroed(), what);
    }
    let Ok(layout) = std::alloc::Layout::array::<T>(len) else {
        return Err(refused::<T>(len, what));
    };
    // SAFETY: the layout is not zero-sized (checked above).
    let ptr = unsafe { std::alloc::alloc_zeroed(layout) }.cast::<T>();
    if ptr.is_null() {
        return Err(refused::<T>(len, what));
    }
    // SAFETY: `ptr` holds `len` zeroed `T`s, a valid value of a `Zeroable` type, allocated by
    // the global allocator with `T`'s array layout, as `Vec` expects.
    Ok(unsafe { Vec::from_raw_parts(ptr, len, len) })
}

/// `len` copies of `value` in a vector allocated with [`try_vec`].
pub fn try_filled<T: Clone>(len: usize, value: T, what: impl FnOnce() -> String) -> Result<Vec<T>> {
    let mut v = try_vec(len, what)?;
    v.resize(len, value);
    Ok(v)
}

/// `x` to four significant digits, in exponent notation when very large or small.
fn short(x: f32) -> String {
    if (1e-3..1e5).contains(&x.abs()) {
        format!("{}", (x * 1e4).round() / 1e4)
    } else {
        format!("{x:.3e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;

    #[test]
    fn a_refused_allocation_is_a_limit_error_not_an_abort() {
        // More bytes than the address space: try_reserve fails without asking the system.
        let e = try_vec::<[f32; 512]>(usize::MAX / 1024, || "the field values".into()).unwrap_err();
        assert!(matches!(e, Error::Limit(_)), "{e:?}");
        assert!(e.to_string().contains("for the field values"), "{e}");
        let v = try_filled(3, 7u8, || "x".into()).unwrap();
        let z: Vec<glam::Vec3> = try_zeroed(1 << 20, || "x".into()).unwrap();
        assert!(z.len() == 1 << 20 && z.iter().all(|&p| p == glam::Vec3::ZERO));
        assert!(try_zeroed::<[u32; 3]>(usize::MAX / 4, || "x".into()).is_err());
        assert_eq!(v, [7, 7, 7]);
    }

    #[test]
    fn a_need_above_the_limit_names_the_figures_and_the_remedies() {
        let config = Config {
            spacing: Some(0.014),
            max_memory: Some(crate::bytes::Bytes(50 << 20)),
            ..Config::default()
        };
        let params = Params::resolve(&config, 0.014);
        assert_eq!(check(&params, 1000, || unreachable!()).unwrap(), 1000);
        let e = check(&params, 3 << 30, || "the band of 5 bricks".into()).unwrap_err();
        let text = e.to_string();
        assert!(matches!(e, Error::Limit(_)));
        for part in [
            "narrow-band engine would need about 3.22 GB for the band of 5 bricks",
            "limit of 52.4 MB (--max-memory)",
            "larger cell (now 0.007 = 0.5r)",
            "raise --max-memory",
        ] {
            assert!(text.contains(part), "{part}: {text}");
        }
        let e = check(&params, u64::MAX, || "a grid".into()).unwrap_err();
        assert!(
            e.to_string().contains("more bytes than can be counted"),
            "{e}"
        );
    }
}
