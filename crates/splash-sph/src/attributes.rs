//! Particle quantities carried onto mesh vertices, for renderers and analysis: a velocity per
//! vertex lets renderers blur by motion; density, pressure or any other attribute can colour
//! the surface.
//!
//! A vertex gets the average of the particle values within the field's support, weighted by
//! the field's own kernel ([`RadialKernel`]: SSP07's (1 − s²)³ of eq. 5 of Solenthaler et al.
//! 2007, the density field's cubic spline, the blobbies' Gaussian, the metaballs' polynomial),
//! divided by the sum of the weights (Shepard normalisation), so a constant attribute is
//! reproduced exactly and a linear one closely away from the fluid's edge.

use crate::data::Attribute;
use crate::error::Result;
use crate::field::radial_kernel::RadialKernel;
use glam::Vec3;
use rayon::prelude::*;

#[cfg(target_arch = "x86_64")]
use crate::neighbours::box_filter::FRONT;
use crate::neighbours::handler_array::HandlerArray;
#[cfg(target_arch = "x86_64")]
use crate::neighbours::lane::F8;
use crate::neighbours::lane::Lane;
use crate::neighbours::lane_sums::{Lanes, lane_totals, lanes_path};
use crate::neighbours::neighbourhood::LANES;

/// Per-particle `attributes` (each one value per particle) interpolated onto `vertices` with
/// `kernel`, through one neighbour structure: each vertex gets the Shepard-normalised kernel
/// mean of the particles within the kernel's support, so a constant attribute stays that
/// constant. A vertex with no particle within the support (which the field's surface never
/// has) gets zero. `cell`: the vertices' spacing (the Marching Cubes cell, 0 when unknown),
/// which sizes the groups of vertices sharing one gather, and so the order of the sums (the
/// values' last bits, never their dependence on the thread count or the CPU).
pub fn interpolate(
    vertices: &[Vec3],
    particles: &[Vec3],
    attributes: &[&Attribute],
    kernel: &RadialKernel,
    cell: f32,
) -> Result<Vec<Attribute>> {
    let support = kernel.support();
    let widths: Vec<usize> = attributes
        .iter()
        .map(|a| match a {
            Attribute::Scalar(_) => 1,
            Attribute::Vector(_) => 3,
        })
        .collect();
    for a in attributes {
        let n = match a {
            Attribute::Scalar(s) => s.len(),
            Attribute::Vector(v) => v.len(),
        };
        if n != particles.len() {
            bail_input!("{} particles but {n} attribute values", particles.len());
        }
    }
    let k: usize = widths.iter().sum();
    let mut flat = vec![0.0f32; vertices.len() * k];
    if k > 0
        && !particles.is_empty()
        && support.partial_cmp(&0.0) == Some(std::cmp::Ordering::Greater)
    {
        // The coordinates and the values ride along the handler array's sort as channels,
        // one per component, so that gathers copy them eight at a time.
        let mut channels: Vec<Vec<f32>> = Vec::with_capacity(3 + k);
        channels.extend((0..3).map(|c| particles.iter().map(|p| p[c]).collect()));
        for a in attributes {
            match a {
                Attribute::Scalar(s) => channels.push(s.clone()),
                Attribute::Vector(v) => {
                    channels.extend((0..3).map(|c| v.iter().map(|v| v[c]).collect()))
                }
            }
        }
        let handlers = HandlerArray::with_channels(particles, support, channels)?;
        sweep(vertices, &handlers, k, &mut flat, cell, kernel);
    }
    let mut offset = 0;
    Ok(widths
        .iter()
        .map(|&w| {
            let column = |c: usize| flat.iter().skip(offset + c).step_by(k.max(1));
            let a = if w == 1 {
                Attribute::Scalar(column(0).copied().collect())
            } else {
                Attribute::Vector(
                    column(0)
                        .zip(column(1))
                        .zip(column(2))
                        .map(|((&x, &y), &z)| Vec3::new(x, y, z))
                        .collect(),
                )
            };
            offset += w;
            a
        })
        .collect())
}

/// Vertices per parallel task.
const BLOCK: usize = 256;
/// Edge of the bins that group vertices around one list of candidate particles, in supports:
/// smaller bins gather more often, larger ones give each vertex more candidates to weigh
/// (cbd-small frame 40, SSP07 at r/2, 1 thread: 0.35 and 0.7 no faster).
const BIN: f32 = 0.5;
/// The bins' least edge in cells: with coarse cells (Blender's viewport: density at cell r,
/// support 2r) half a support held a vertex or two, and gathering took 4/5 of the time
/// (cbd-small, 11 frames, 1 thread: 0.184 -> 0.100 s with 4 cells). Since the means weigh
/// every candidate, 3 (cbd-small frame 40, 1 thread: density at cell r 9.5 ms against 9.7
/// with 4, the blobbies at r/2 50 against 55; SSP07 at r/2 keeps half a support).
const BIN_CELLS: f32 = 3.0;

/// The candidates of a bin's vertices: the particles within the support of their box, in
/// handler order over the cells in (z, y, x) order, as one array per channel (x, y, z, then
/// the attributes' components), padded to whole lanes with particles at infinity.
#[derive(Default)]
struct Candidates {
    channels: Vec<Vec<f32>>,
    /// The candidates in each channel, a whole number of lanes; past them, room for stores.
    len: usize,
    /// Scratch: the handler ranges of the box's cells, and each candidate's weight at a vertex.
    ranges: Vec<std::ops::Range<usize>>,
    weights: Vec<f32>,
}

/// The Shepard means of the handler array's attribute channels (those after x, y, z: `k`) at
/// every vertex into `flat` (`k` values per vertex), with `kernel`'s weights. The vertices are
/// binned in space (cubes of `BIN` supports, at least `BIN_CELLS` × `cell`, fixed by absolute
/// coordinates) and sorted by bin; the vertices of a bin within one block of `BLOCK` sorted
/// vertices share one list of candidate particles (those within the support of their bounding
/// box), which each of them weighs whole in `LANES` lanes (those beyond the support weigh 0).
/// A particle's lane is its place in that list, so a vertex's bits depend on which vertices
/// share its list (fixed by the vertices, the bin edge and the block size), never on the
/// thread count or the CPU's vector width.
fn sweep(
    vertices: &[Vec3],
    handlers: &HandlerArray,
    k: usize,
    flat: &mut [f32],
    cell: f32,
    kernel: &RadialKernel,
) {
    let support = handlers.cell_size();
    let bin = (BIN * support).max(BIN_CELLS * cell);
    // Chosen here: a test's forced path does not reach the worker threads.
    let path = lanes_path();
    // Bins keyed by 21 bits per axis: bins 2^21 apart share a key, and so a gather (slower,
    // never wrong).
    let mut order: Vec<(u64, u32)> = vertices
        .par_iter()
        .enumerate()
        .map(|(i, v)| {
            let c = (*v / bin).floor().as_ivec3().to_array();
            let key = c.map(|c| u64::from(c as u32 & ((1 << 21) - 1)));
            (key[2] << 42 | key[1] << 21 | key[0], i as u32)
        })
        .collect();
    // Stable: by bin, then by index.
    radsort::sort_by_key(&mut order, |o| o.0);
    let mut sorted = vec![0.0f32; flat.len()];
    sorted
        .par_chunks_mut(BLOCK * k)
        .zip(order.par_chunks(BLOCK))
        .for_each_init(Candidates::default, |candidates, (out, block)| {
            for run in block.chunk_by(|a, b| a.0 == b.0) {
                let first = vertices[run[0].1 as usize];
                let (lo, hi) = run.iter().fold((first, first), |(lo, hi), &(_, i)| {
                    (lo.min(vertices[i as usize]), hi.max(vertices[i as usize]))
                });
                candidates.gather(handlers, lo, hi, path);
                let start = (run.as_ptr() as usize - block.as_ptr() as usize)
                    / std::mem::size_of_val(&run[0]);
                for (&(_, i), out) in run.iter().zip(out[start * k..].chunks_exact_mut(k)) {
                    candidates.mean_at(vertices[i as usize], support, kernel, out, path);
                }
            }
        });
    for (values, &(_, i)) in sorted.chunks_exact(k).zip(&order) {
        flat[i as usize * k..][..k].copy_from_slice(values);
    }
}

impl Candidates {
    /// Holds the particles within `support` (the handlers' cell size) of the box `[lo, hi]`.
    fn gather(&mut self, handlers: &HandlerArray, lo: Vec3, hi: Vec3, path: Lanes) {
        let support = handlers.cell_size();
        let ranges = &mut self.ranges;
        ranges.clear();
        handlers.for_each_in_box(lo - support, hi + support, |range| {
            // Cells that follow each other in handler order as one range: fewer short tails.
            match ranges.last_mut() {
                Some(last) if last.end == range.start => last.end = range.end,
                _ => ranges.push(range),
            }
        });
        let most: usize = ranges.iter().map(|r| r.len()).sum();
        let channels = &mut self.channels;
        channels.resize_with(handlers.channels.len(), Vec::new);
        for c in channels.iter_mut() {
            // Room for the last lanes' stores past the candidates kept (what the last
            // gather left in it is overwritten).
            c.resize(c.len().max(most + LANES), 0.0);
        }
        let boxed = Boxed {
            lo,
            hi,
            reach: support * support,
        };
        let mut m = 0;
        for range in ranges.iter() {
            m = match path {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: the CPU has AVX2 (`lanes_path` checked); the outputs hold
                // `most + LANES` floats each, past all the ranges' particles.
                Lanes::Avx2 | Lanes::Avx512 => unsafe {
                    boxed.keep_avx2(&handlers.channels, range.clone(), m, channels)
                },
                _ => boxed.keep(&handlers.channels, range.clone(), m, channels),
            };
        }
        // Padding: far away (weight 0), and values 0.
        self.len = m.next_multiple_of(LANES);
        for (c, channel) in channels.iter_mut().enumerate() {
            channel[m..self.len].fill(if c < 3 { f32::INFINITY } else { 0.0 });
        }
    }

    /// The Shepard mean of the attribute channels at `v` into `out`: every candidate weighed
    /// (0 from `support` on), then the weighted sums in `LANES` lanes.
    fn mean_at(
        &mut self,
        v: Vec3,
        support: f32,
        kernel: &RadialKernel,
        out: &mut [f32],
        path: Lanes,
    ) {
        match path {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: the CPU has AVX2 (`lanes_path` checked).
            Lanes::Avx2 | Lanes::Avx512 => unsafe { self.mean_avx2(v, support, kernel, out) },
            _ => self.mean::<f32>(v, support, kernel, out),
        }
    }

    /// [`Candidates::mean_at`] eight lanes at a time.
    ///
    /// # Safety
    /// AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn mean_avx2(&mut self, v: Vec3, support: f32, kernel: &RadialKernel, out: &mut [f32]) {
        self.mean::<F8>(v, support, kernel, out)
    }

    /// [`Candidates::mean_at`] `L::WIDTH` lanes at a time.
    #[inline(always)]
    fn mean<L: Lane>(&mut self, v: Vec3, support: f32, kernel: &RadialKernel, out: &mut [f32]) {
        let n = self.len;
        let [x, y, z, values @ ..] = &self.channels[..] else {
            unreachable!("x, y and z come first");
        };
        let (x, y, z) = (&x[..n], &y[..n], &z[..n]);
        let weights = &mut self.weights;
        weights.resize(n, 0.0);
        let s2 = support * support;
        // One loop per kernel, each with its own weight inlined (the Gaussian and the
        // metaballs' are scalar code anyway).
        match kernel {
            RadialKernel::Poly6 { .. } => weigh::<L>([x, y, z], v, s2, *kernel, weights),
            RadialKernel::CubicSpline { .. } => weigh::<L>([x, y, z], v, s2, *kernel, weights),
            _ => weigh::<L>([x, y, z], v, s2, *kernel, weights),
        }
        let total = lane_dot(weights, None);
        if total > 0.0 {
            for (o, values) in out.iter_mut().zip(values) {
                *o = lane_dot(weights, Some(&values[..n])) / total;
            }
        }
    }
}

/// The box test of a gather: within √`reach` of `[lo, hi]`.
struct Boxed {
    lo: Vec3,
    hi: Vec3,
    reach: f32,
}

impl Boxed {
    /// Copies the particles of `range` in reach of the box from the channels `from` (x, y, z
    /// first) to the end of the `m` kept in `to` (each with room for `LANES` past them), in
    /// order; returns how many are kept. Branch-free: each one is stored, and kept or not.
    fn keep(
        &self,
        from: &[Vec<f32>],
        range: std::ops::Range<usize>,
        mut m: usize,
        to: &mut [Vec<f32>],
    ) -> usize {
        for i in range {
            // The distance to the box per axis, as `keep_avx2` takes it (maxps gives its
            // second operand where either is NaN, as `f32::max` does where the first is).
            let d = |c: usize| {
                let p = from[c][i];
                (self.lo[c] - p).max(p - self.hi[c]).max(0.0)
            };
            let (dx, dy, dz) = (d(0), d(1), d(2));
            let d2 = dx * dx + dy * dy + dz * dz;
            for (to, from) in to.iter_mut().zip(from) {
                to[m] = from[i];
            }
            m += usize::from(d2 < self.reach);
        }
        m
    }

    /// [`Boxed::keep`] eight particles at a time: the kept lanes moved to the front by one
    /// permutation ([`FRONT`]) and stored at the end of those kept so far (a short tail with
    /// lanes before the range: a range was scalar 2/7 of the gathers' time).
    ///
    /// # Safety
    /// AVX2; every `to` at least `LANES` longer than `m` plus the range's particles.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn keep_avx2(
        &self,
        from: &[Vec<f32>],
        range: std::ops::Range<usize>,
        mut m: usize,
        to: &mut [Vec<f32>],
    ) -> usize {
        use std::arch::x86_64::*;
        let zero = _mm256_setzero_ps();
        let lo = self.lo.to_array().map(|c| _mm256_set1_ps(c));
        let hi = self.hi.to_array().map(|c| _mm256_set1_ps(c));
        let reach = _mm256_set1_ps(self.reach);
        let mut i = range.start;
        while i < range.end {
            // The last eight end with the range, the lanes before `i` left out (read, not
            // kept: the particles of other cells); scalar where the channels are shorter.
            let (j, valid) = match (range.end - i, range.end.checked_sub(8)) {
                (8.., _) => (i, 0xff),
                (_, Some(j)) => (j, 0xff << (i - j) & 0xff),
                (_, None) => break,
            };
            let d: [__m256; 3] = std::array::from_fn(|c| {
                // SAFETY: j + 8 ≤ the range's end, within every channel.
                let p = unsafe { _mm256_loadu_ps(from[c][j..j + 8].as_ptr()) };
                let out = _mm256_max_ps(_mm256_sub_ps(lo[c], p), _mm256_sub_ps(p, hi[c]));
                let d = _mm256_max_ps(out, zero);
                _mm256_mul_ps(d, d)
            });
            let d2 = _mm256_add_ps(_mm256_add_ps(d[0], d[1]), d[2]);
            let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(d2, reach)) as usize & valid;
            // SAFETY: FRONT's rows are 8 i32.
            let front = unsafe { _mm256_loadu_si256(FRONT[mask].as_ptr().cast()) };
            for (to, from) in to.iter_mut().zip(from) {
                let kept = &mut to[m..m + 8];
                // SAFETY: 8 floats from j in the channel, 8 to m in the output.
                unsafe {
                    let values = _mm256_loadu_ps(from[j..j + 8].as_ptr());
                    let front = _mm256_permutevar8x32_ps(values, front);
                    _mm256_storeu_ps(kept.as_mut_ptr(), front);
                }
            }
            m += mask.count_ones() as usize;
            i = j + 8;
        }
        self.keep(from, i..range.end, m, to)
    }
}

/// The weights of `kernel` at `v` of the candidates `xyz` into `weights`, `L::WIDTH` at a
/// time: the kernel's where the squared distance is below `s2`, else 0.
#[inline(always)]
fn weigh<L: Lane>(
    [x, y, z]: [&[f32]; 3],
    v: Vec3,
    s2: f32,
    kernel: RadialKernel,
    weights: &mut [f32],
) {
    let at = [L::splat(v.x), L::splat(v.y), L::splat(v.z)];
    let w = L::WIDTH;
    let lanes = x
        .chunks_exact(w)
        .zip(y.chunks_exact(w))
        .zip(z.chunks_exact(w));
    for (((x, y), z), out) in lanes.zip(weights.chunks_exact_mut(w)) {
        // As `(p - v).length_squared()`, term by term.
        let (dx, dy, dz) = (L::load(x) - at[0], L::load(y) - at[1], L::load(z) - at[2]);
        let d2 = dx * dx + dy * dy + dz * dz;
        // The support cut exactly, where a rounded square root leaves a trace beyond it.
        (kernel.weight(d2) * d2.between(-1.0, s2)).store(out);
    }
}

/// Σ weight × value (Σ weight without values) over whole lanes, in `LANES` lanes added in
/// lane order (the compiler vectorises the lanes, which keeps the bits); a value where the
/// weight is 0 adds nothing, even when it is not a number.
#[inline(always)]
fn lane_dot(weights: &[f32], values: Option<&[f32]>) -> f32 {
    let mut acc = [0.0f32; LANES];
    match values {
        None => {
            for w in weights.chunks_exact(LANES) {
                for l in 0..LANES {
                    acc[l] += w[l];
                }
            }
        }
        Some(values) => {
            for (w, v) in weights.chunks_exact(LANES).zip(values.chunks_exact(LANES)) {
                for l in 0..LANES {
                    let product = w[l] * v[l];
                    acc[l] += if w[l] > 0.0 { product } else { 0.0 };
                }
            }
        }
    }
    lane_totals(&[acc])[0]
}

/// Velocities of `vertices`, interpolated from the particles' with support `support`: see
/// [`interpolate`].
#[cfg(test)]
fn interpolate_velocities(
    vertices: &[Vec3],
    particles: &[Vec3],
    velocities: &[Vec3],
    support: f32,
) -> Result<Vec<Vec3>> {
    if particles.len() != velocities.len() {
        bail_input!(
            "{} particles but {} velocities",
            particles.len(),
            velocities.len()
        );
    }
    let velocities = Attribute::Vector(velocities.to_vec());
    let kernel = RadialKernel::Poly6 { support };
    match interpolate(vertices, particles, &[&velocities], &kernel, 0.0)?.pop() {
        Some(Attribute::Vector(v)) => Ok(v),
        _ => unreachable!("one vector in, one vector out"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_uniform_or_linear_velocity_is_reproduced() {
        let mut particles = Vec::new();
        for z in 0..12 {
            for y in 0..12 {
                for x in 0..12 {
                    particles.push(Vec3::new(x as f32, y as f32, z as f32) * 0.1);
                }
            }
        }
        let vertices = [Vec3::splat(0.55), Vec3::new(0.3, 0.62, 0.48)];
        let uniform = vec![Vec3::new(1.0, -2.0, 0.5); particles.len()];
        for v in interpolate_velocities(&vertices, &particles, &uniform, 0.4).unwrap() {
            assert!((v - uniform[0]).length() < 1e-5, "{v}");
        }
        // A symmetric kernel reproduces a linear field away from the boundary.
        let linear: Vec<Vec3> = particles
            .iter()
            .map(|p| Vec3::new(p.y, 2.0, -p.x))
            .collect();
        for (x, v) in vertices
            .iter()
            .zip(interpolate_velocities(&vertices, &particles, &linear, 0.25).unwrap())
        {
            let lattice_centre_bias = 0.02;
            assert!(
                (v - Vec3::new(x.y, 2.0, -x.x)).length() < lattice_centre_bias,
                "{x}: {v}"
            );
        }
        let far = interpolate_velocities(&[Vec3::splat(9.0)], &particles, &uniform, 0.4).unwrap();
        assert_eq!(far, [Vec3::ZERO]);
    }

    /// Particles jittered off a lattice, so that no symmetry helps.
    fn jittered(n: i32, spacing: f32) -> Vec<Vec3> {
        let mut seed = 12345u32;
        let mut rand = move || {
            seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
            (seed >> 8) as f32 / (1u32 << 24) as f32 - 0.5
        };
        let mut out = Vec::new();
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let jitter = Vec3::new(rand(), rand(), rand()) * 0.3 * spacing;
                    out.push(Vec3::new(x as f32, y as f32, z as f32) * spacing + jitter);
                }
            }
        }
        out
    }

    #[test]
    fn constants_stay_constant_and_linear_fields_stay_close_to_linear() {
        let h = 0.1;
        let particles = jittered(14, h);
        let support = 2.0 * h;
        let kernel = RadialKernel::Poly6 { support };
        // Vertices anywhere a particle reaches, edge included, and in the interior.
        let vertices: Vec<Vec3> = (0..200)
            .map(|i| {
                let t = i as f32 / 200.0;
                Vec3::new(t * 1.3, (t * 7.0).fract() * 1.3, (t * 13.0).fract() * 1.3)
            })
            .collect();
        let density = Attribute::Scalar(vec![998.25; particles.len()]);
        let velocity = Attribute::Vector(vec![Vec3::new(0.5, -3.0, 1e-3); particles.len()]);
        let out = interpolate(&vertices, &particles, &[&density, &velocity], &kernel, 0.0).unwrap();
        let (Attribute::Scalar(d), Attribute::Vector(v)) = (&out[0], &out[1]) else {
            panic!("kinds changed: {out:?}");
        };
        // Shepard: the weights sum to one up to rounding, wherever a particle is in reach.
        for (x, d) in vertices.iter().zip(d) {
            assert!(
                (d - 998.25).abs() <= 998.25 * 4.0 * f32::EPSILON,
                "{x}: {d}"
            );
        }
        for v in v {
            assert!(
                (*v - Vec3::new(0.5, -3.0, 1e-3)).abs().max_element() < 4e-6,
                "{v}"
            );
        }
        // A linear field: at an interior vertex (a support away from the edge) the Shepard mean
        // is exactly the field at the kernel-weighted centroid of the particles in reach. With
        // only ~30 particles in reach, their discrete placement (lattice offset from the vertex
        // plus jitter of up to 0.15 h) moves that centroid off the vertex by a fraction of the
        // spacing: the error is at most |gradient| × 0.2 h (the bias of the lattice test above,
        // 0.02 at h = 0.1), while the field varies by |gradient| × 2 h across the support.
        let grad = Vec3::new(2.0, -1.0, 0.5);
        let linear = Attribute::Scalar(particles.iter().map(|p| grad.dot(*p)).collect());
        let interior: Vec<Vec3> = vertices
            .iter()
            .copied()
            .filter(|x| x.min_element() > support && x.max_element() < 1.3 - support)
            .collect();
        assert!(interior.len() > 20);
        let Attribute::Scalar(l) = interpolate(&interior, &particles, &[&linear], &kernel, 0.0)
            .unwrap()
            .remove(0)
        else {
            panic!()
        };
        let mut worst = 0.0f32;
        for (x, l) in interior.iter().zip(l) {
            worst = worst.max((l - grad.dot(*x)).abs() / (grad.length() * h));
        }
        assert!(worst < 0.2, "error {worst} h × |gradient|");
        // And it is no exact copy of a value at a particle: the mean did something.
        assert!(worst > 0.0);
        // Nothing to interpolate, or no particles: zeros of the right kinds.
        assert!(
            interpolate(&vertices, &particles, &[], &kernel, 0.0)
                .unwrap()
                .is_empty()
        );
        let none =
            interpolate(&vertices, &[], &[&Attribute::Scalar(vec![])], &kernel, 0.0).unwrap();
        assert_eq!(none, [Attribute::Scalar(vec![0.0; vertices.len()])]);
        assert!(
            interpolate(
                &vertices,
                &particles,
                &[&Attribute::Scalar(vec![1.0])],
                &kernel,
                0.0
            )
            .is_err()
        );
    }

    /// Every field's kernel at spacing r, with the support the field itself reports.
    fn field_kernels(r: f32) -> Vec<(&'static str, RadialKernel)> {
        crate::field::FieldConfig::KINDS
            .iter()
            .map(|&kind| {
                let field = crate::field::FieldConfig::named(kind).unwrap().build(r);
                let kernel = field.radial_kernel();
                assert_eq!(kernel.support(), field.support(), "{kind}");
                (kind, kernel)
            })
            .collect()
    }

    #[test]
    fn the_candidates_in_reach_of_a_box_are_the_same_on_every_path() {
        let mut next = crate::tests::common::uniform(7);
        // First one at the reach exactly (left out), one just inside, one not a number, one
        // at infinity; then a value channel.
        let mut points = vec![
            [1.0, 0.0, 0.0],
            [0.0, -0.8999, 0.0],
            [f32::NAN; 3],
            [f32::INFINITY, 0.0, 0.0],
        ];
        points.extend(
            (0..203)
                .map(|_| (crate::tests::common::uniform_point(&mut next) * 2.5 - 1.25).to_array()),
        );
        let mut from = vec![Vec::new(); 4];
        for (i, p) in points.iter().enumerate() {
            from.iter_mut().zip(p).for_each(|(c, &x)| c.push(x));
            from[3].push(i as f32);
        }
        let boxed = Boxed {
            lo: Vec3::new(-0.5, -0.4, -0.1),
            hi: Vec3::new(0.5, 0.5, 0.1),
            reach: 0.25,
        };
        let run = |scalar: bool, ranges: &[std::ops::Range<usize>]| {
            let mut to = vec![vec![0.0f32; points.len() + LANES]; 4];
            let mut m = 0;
            for r in ranges {
                m = match scalar {
                    true => boxed.keep(&from, r.clone(), m, &mut to),
                    #[cfg(target_arch = "x86_64")]
                    // SAFETY: the CPU has AVX2, checked below before this runs.
                    false => unsafe { boxed.keep_avx2(&from, r.clone(), m, &mut to) },
                    #[cfg(not(target_arch = "x86_64"))]
                    false => boxed.keep(&from, r.clone(), m, &mut to),
                };
            }
            to.iter()
                .map(|c| c[..m].iter().map(|v| v.to_bits()).collect())
                .collect::<Vec<Vec<u32>>>()
        };
        // Whole, and in ranges with tails of every length.
        let ranges = [
            0..points.len(),
            0..13,
            13..14,
            14..14,
            14..35,
            35..points.len(),
        ];
        let scalar = run(true, &ranges[..1]);
        assert_eq!(run(true, &ranges[1..]), scalar);
        let kept: Vec<u32> = scalar[3]
            .iter()
            .map(|&i| f32::from_bits(i) as u32)
            .collect();
        assert!(kept.len() > 20 && kept.len() < 150, "{}", kept.len());
        assert_eq!(kept[0], 1, "only the one inside the reach");
        assert!(!kept.contains(&3), "the one at infinity is out of reach");
        #[cfg(target_arch = "x86_64")]
        if lanes_path() != Lanes::Scalar {
            assert_eq!(run(false, &ranges[..1]), scalar);
            assert_eq!(run(false, &ranges[1..]), scalar);
            return;
        }
        eprintln!("no AVX2 on this CPU: only the scalar gathers were checked");
    }

    #[test]
    fn the_bits_are_the_same_on_every_path_and_thread_count_and_the_bins_round_alike() {
        use crate::neighbours::lane_sums::tests::on_every_path;
        let r = 0.1;
        let particles = jittered(14, r);
        let velocity = Attribute::Vector(
            particles
                .iter()
                .map(|p| Vec3::new(p.y.sin(), p.z * p.x, 1.0 / (1.0 + p.x)))
                .collect(),
        );
        let vertices: Vec<Vec3> = (0..2000)
            .map(|i| {
                let t = i as f32 / 2000.0;
                Vec3::new(t, (t * 7.0).fract(), (t * 13.0).fract()) * 1.4
            })
            .collect();
        let interpolated = |kernel: &RadialKernel, cell: f32| match interpolate(
            &vertices,
            &particles,
            &[&velocity],
            kernel,
            cell,
        )
        .unwrap()
        .remove(0)
        {
            Attribute::Vector(v) => v,
            Attribute::Scalar(_) => Vec::new(),
        };
        let bits = |v: Vec<Vec3>| -> Vec<[u32; 3]> {
            v.iter().map(|v| v.to_array().map(f32::to_bits)).collect()
        };
        for (kind, kernel) in field_kernels(r) {
            let paths = on_every_path(|| bits(interpolated(&kernel, r / 2.0)));
            let want = &paths[0].1;
            assert!(want.iter().any(|v| v[0] != 0), "{kind}");
            for (path, got) in &paths {
                assert_eq!(got, want, "{kind} {path:?}");
            }
            for threads in [1, 3] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let got = pool.install(|| bits(interpolated(&kernel, r / 2.0)));
                assert_eq!(&got, want, "{kind}, {threads} threads");
            }
        }
        // Bins of half a support, then of ¾, 1½ and 3: the same sums in other lanes.
        let kernel = RadialKernel::CubicSpline { support: 2.0 * r };
        let want = interpolated(&kernel, 0.0);
        for cell in [r / 2.0, r, 2.0 * r] {
            let got = interpolated(&kernel, cell);
            let worst = want
                .iter()
                .zip(&got)
                .map(|(a, b)| ((*a - *b).abs() / a.abs().max(Vec3::splat(0.1))).max_element())
                .fold(0.0f32, f32::max);
            assert!(worst < 1e-5, "cell {cell}: {worst}");
        }
    }

    #[test]
    fn every_fields_kernel_keeps_constants_reproduces_linear_fields_and_its_support() {
        let r = 0.1;
        let (n, side) = (16, 1.5);
        let particles = jittered(n, r);
        let vertices: Vec<Vec3> = (0..300)
            .map(|i| {
                let t = i as f32 / 300.0;
                Vec3::new(t, (t * 7.0).fract(), (t * 13.0).fract()) * side
            })
            .collect();
        let grad = Vec3::new(2.0, -1.0, 0.5);
        let constant = Attribute::Scalar(vec![-7.25; particles.len()]);
        let linear = Attribute::Scalar(particles.iter().map(|p| grad.dot(*p)).collect());
        for (kind, kernel) in field_kernels(r) {
            let support = kernel.support();
            let out =
                interpolate(&vertices, &particles, &[&constant, &linear], &kernel, 0.0).unwrap();
            let (Attribute::Scalar(c), Attribute::Scalar(l)) = (&out[0], &out[1]) else {
                panic!("kinds changed");
            };
            // Shepard up to the rounding of f32 sums over up to ~300 particles in reach.
            for (x, c) in vertices.iter().zip(c) {
                assert!((c + 7.25).abs() <= 7.25 * 1e-5, "{kind} {x}: {c}");
            }
            // Interior: a support (and a spacing) away from the cloud's edge. The error is the
            // offset of the kernel-weighted centroid of the particles in reach from the vertex,
            // a fraction of the spacing (see the test above), larger the fewer particles are
            // in reach.
            let mut worst = 0.0f32;
            let mut interior = 0;
            for (x, l) in vertices.iter().zip(l) {
                if x.min_element() > support + r && x.max_element() < side - support - r {
                    interior += 1;
                    worst = worst.max((l - grad.dot(*x)).abs() / (grad.length() * r));
                }
            }
            assert!(interior > 20, "{kind}: {interior}");
            // Measured: 0.03 for the wide kernels (4 r), up to 0.21 for the blobbies' (1.6 r,
            // about 15 particles in reach), against |gradient| × 2 × support across the kernel.
            assert!(worst < 0.3, "{kind}: error {worst} r × |gradient|");
            // A particle just beyond the support adds nothing, even not a number; one just
            // inside does.
            let centre = Vec3::splat(side / 2.0);
            for (reach, value, felt) in [
                (1.001, 1.0, false),
                (1.001, f32::NAN, false),
                (0.98, 1.0, true),
            ] {
                let mut with_probe = particles.clone();
                with_probe.push(centre + Vec3::new(reach * support, 0.0, 0.0));
                let mut probe = vec![0.0; particles.len()];
                probe.push(value);
                // With a second vertex out of the probe's reach but in the same bin (of four
                // supports), whose candidates the probe is then among.
                let second = centre + Vec3::new(0.1, 0.5, 0.0) * support;
                let Attribute::Scalar(v) = interpolate(
                    &[centre, second],
                    &with_probe,
                    &[&Attribute::Scalar(probe)],
                    &kernel,
                    support,
                )
                .unwrap()
                .remove(0) else {
                    panic!()
                };
                assert_eq!(
                    v[0] > 0.0,
                    felt,
                    "{kind}: probe {value} at {reach} support: {}",
                    v[0]
                );
                assert_eq!(v[0], if felt { v[0] } else { 0.0 }, "{kind}");
            }
        }
    }
}
