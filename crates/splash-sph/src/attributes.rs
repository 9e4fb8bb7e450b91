//! Particle quantities carried onto mesh vertices, for renderers and analysis: a velocity per
//! vertex lets renderers blur by motion; density, pressure or any other attribute can colour
//! the surface.
//!
//! A vertex gets the average of the particle values within the field's support, weighted by
//! the field's own kernel ([`RadialKernel`]: SSP07's (1 − s²)³ of eq. 5 of Solenthaler et al.
//! 2007, the density field's cubic spline, the blobbies' Gaussian, the metaballs' polynomial),
//! divided by the sum of the weights (Shepard normalisation), so a constant attribute is
//! reproduced exactly and a linear one closely away from the fluid's edge.

use crate::error::Result;
use crate::field::radial_kernel::RadialKernel;
use crate::io::Attribute;
use glam::Vec3;
use rayon::prelude::*;

#[cfg(target_arch = "x86_64")]
use crate::neighbours::box_filter::FRONT;
use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::lane_sums::{Lanes, lanes_path};

/// Per-particle `attributes` (each one value per particle) interpolated onto `vertices` with
/// `kernel`, through one neighbour structure: each vertex gets the Shepard-normalised kernel
/// mean of the particles within the kernel's support, so a constant attribute stays that
/// constant. A vertex with no particle within the support (which the field's surface never
/// has) gets zero. `cell`: the vertices' spacing (the Marching Cubes cell, 0 when unknown),
/// which sizes the groups of vertices sharing one gather, never the values.
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
        // The values ride along the handler array's sort as channels, one per component.
        let mut channels: Vec<Vec<f32>> = Vec::with_capacity(k);
        for a in attributes {
            match a {
                Attribute::Scalar(s) => channels.push(s.clone()),
                Attribute::Vector(v) => {
                    channels.extend((0..3).map(|c| v.iter().map(|v| v[c]).collect()))
                }
            }
        }
        let handlers = HandlerArray::with_channels(particles, support, channels)?;
        match *kernel {
            // The kernel chosen once, outside the loops, so that they inline its weight.
            RadialKernel::Poly6 { .. } => sweep(vertices, &handlers, k, &mut flat, cell, |d2| {
                kernel.weight(d2)
            }),
            RadialKernel::CubicSpline { .. } => {
                sweep(vertices, &handlers, k, &mut flat, cell, |d2| {
                    kernel.weight(d2)
                })
            }
            RadialKernel::Blobby { .. } => sweep(vertices, &handlers, k, &mut flat, cell, |d2| {
                kernel.weight(d2)
            }),
            RadialKernel::Metaball { .. } => sweep(vertices, &handlers, k, &mut flat, cell, |d2| {
                kernel.weight(d2)
            }),
        }
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
/// smaller bins gather more often, larger ones give each vertex more candidates to test
/// (cbd-small frame 40, SSP07 at r/2, 1 thread: 83 ms against 162 ms for a gather per vertex,
/// the same bits).
const BIN: f32 = 0.5;
/// The bins' least edge in cells: with coarse cells (Blender's viewport: density at cell r,
/// support 2r) half a support held a vertex or two, and gathering took 4/5 of the time
/// (cbd-small, 11 frames, 1 thread: 0.184 -> 0.100 s; SSP07 at r/2 keeps half a support).
const BIN_CELLS: f32 = 4.0;

/// The candidates of a bin's vertices: the particles within the support of their box, in
/// handler order over the cells in (z, y, x) order, as coordinate and channel arrays.
#[derive(Default)]
struct Candidates {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    channels: Vec<f32>,
    /// Scratch: the candidates within the support of one vertex, and their squared distances.
    near: Vec<u32>,
    d2: Vec<f32>,
}

/// The Shepard means of the handler array's `k` channels at every vertex into `flat` (`k`
/// values per vertex), with the kernel `weight` of the squared distance (zero from the
/// support on). The vertices are binned in space (bins of `BIN` supports, at least
/// `BIN_CELLS` × `cell`), and each bin's share one list of candidate
/// particles; the particles within the support of a vertex are still visited in the order of
/// its own cells, so each vertex gets the same bits whatever its bin and however many threads
/// run.
fn sweep(
    vertices: &[Vec3],
    handlers: &HandlerArray,
    k: usize,
    flat: &mut [f32],
    cell: f32,
    weight: impl Fn(f32) -> f32 + Sync,
) {
    let support = handlers.cell_size();
    let bin = (BIN * support).max(BIN_CELLS * cell);
    let mut order: Vec<((i32, i32, i32), u32)> = vertices
        .par_iter()
        .enumerate()
        .map(|(i, v)| {
            let c = (*v / bin).floor().as_ivec3();
            ((c.z, c.y, c.x), i as u32)
        })
        .collect();
    order.par_sort_unstable();
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
                candidates.gather(handlers, lo, hi, k);
                let start = (run.as_ptr() as usize - block.as_ptr() as usize)
                    / std::mem::size_of_val(&run[0]);
                for (&(_, i), out) in run.iter().zip(out[start * k..].chunks_exact_mut(k)) {
                    candidates.mean_at(vertices[i as usize], support, k, &weight, out);
                }
            }
        });
    for (values, &(_, i)) in sorted.chunks_exact(k).zip(&order) {
        flat[i as usize * k..][..k].copy_from_slice(values);
    }
}

impl Candidates {
    /// Holds the particles within `support` (the handlers' cell size) of the box `[lo, hi]`.
    fn gather(&mut self, handlers: &HandlerArray, lo: Vec3, hi: Vec3, k: usize) {
        let support = handlers.cell_size();
        let (x, y, z, channels) = (&mut self.x, &mut self.y, &mut self.z, &mut self.channels);
        x.clear();
        y.clear();
        z.clear();
        channels.clear();
        let reach = support * support;
        handlers.for_each_in_box(lo - support, hi + support, |range| {
            for i in range {
                let p = handlers.positions[i];
                if (p - p.clamp(lo, hi)).length_squared() < reach {
                    x.push(p.x);
                    y.push(p.y);
                    z.push(p.z);
                    channels.extend((0..k).map(|c| handlers.channels[c][i]));
                }
            }
        });
    }

    /// The Shepard mean of the channels at `v` into `out`: the candidates within `support`
    /// found first (branch-free), then weighed in order.
    fn mean_at(
        &mut self,
        v: Vec3,
        support: f32,
        k: usize,
        weight: &impl Fn(f32) -> f32,
        out: &mut [f32],
    ) {
        let n = self.x.len();
        let (near, d2s) = (&mut self.near, &mut self.d2);
        // Room for the last lanes' stores past the candidates kept.
        near.resize(n + 8, 0);
        d2s.resize(n + 8, 0.0);
        let m = within([&self.x, &self.y, &self.z], v, support * support, near, d2s);
        let mut total = 0.0f32;
        for (&i, &d2) in near[..m].iter().zip(&d2s[..m]) {
            let w = weight(d2);
            if w > 0.0 {
                total += w;
                let values = &self.channels[i as usize * k..][..k];
                for (o, value) in out.iter_mut().zip(values) {
                    *o += w * value;
                }
            }
        }
        if total > 0.0 {
            out.iter_mut().for_each(|o| *o /= total);
        }
    }
}

/// Keeps the candidates (coordinate arrays `xyz`) closer to `v` than √`s2`: their indices to
/// the front of `near` and their squared distances to the front of `d2s` (both with room for 8
/// past the candidates), in order; returns how many. Eight at a time with AVX2 (a scalar loop
/// was half the interpolation's time at SSP07 r/2), the same IEEE operations either way.
fn within(xyz: [&[f32]; 3], v: Vec3, s2: f32, near: &mut [u32], d2s: &mut [f32]) -> usize {
    assert!(xyz.iter().all(|c| c.len() == xyz[0].len()));
    assert!(near.len() >= xyz[0].len() + 8 && d2s.len() >= xyz[0].len() + 8);
    match lanes_path() {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the CPU has AVX2 (`lanes_path` checked); the lengths are asserted above.
        Lanes::Avx2 | Lanes::Avx512 => unsafe { within_avx2(xyz, v, s2, near, d2s) },
        _ => within_scalar(xyz, v, s2, 0, 0, near, d2s),
    }
}

/// [`within`] from candidate `from` on, with `m` kept before it.
fn within_scalar(
    [x, y, z]: [&[f32]; 3],
    v: Vec3,
    s2: f32,
    from: usize,
    mut m: usize,
    near: &mut [u32],
    d2s: &mut [f32],
) -> usize {
    for i in from..x.len() {
        // As `(p - v).length_squared()`, term by term, so the bits match.
        let (dx, dy, dz) = (x[i] - v.x, y[i] - v.y, z[i] - v.z);
        let d2 = dx * dx + dy * dy + dz * dz;
        near[m] = i as u32;
        d2s[m] = d2;
        m += usize::from(d2 < s2);
    }
    m
}

/// [`within`] eight candidates at a time: the kept lanes moved to the front by one
/// permutation ([`FRONT`]) and stored at the end of those kept so far; the rest scalar.
///
/// # Safety
/// AVX2; `near` and `d2s` at least 8 longer than the coordinate arrays, which are all as long.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn within_avx2(
    xyz: [&[f32]; 3],
    v: Vec3,
    s2: f32,
    near: &mut [u32],
    d2s: &mut [f32],
) -> usize {
    use std::arch::x86_64::*;
    let n = xyz[0].len() / 8 * 8;
    let at = v.to_array().map(|c| _mm256_set1_ps(c));
    let limit = _mm256_set1_ps(s2);
    let mut index = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    let mut m = 0;
    for i in (0..n).step_by(8) {
        // SAFETY: i + 8 ≤ n, within every coordinate array.
        let d: [__m256; 3] = std::array::from_fn(|k| {
            let d = _mm256_sub_ps(unsafe { _mm256_loadu_ps(xyz[k].as_ptr().add(i)) }, at[k]);
            _mm256_mul_ps(d, d)
        });
        let d2 = _mm256_add_ps(_mm256_add_ps(d[0], d[1]), d[2]);
        let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(d2, limit)) as usize;
        // SAFETY: FRONT's rows are 8 i32; m ≤ i, so m + 8 ≤ n + 8 ≤ the outputs' lengths.
        unsafe {
            let front = _mm256_loadu_si256(FRONT[mask].as_ptr().cast());
            _mm256_storeu_ps(d2s.as_mut_ptr().add(m), _mm256_permutevar8x32_ps(d2, front));
            let kept = _mm256_permutevar8x32_epi32(index, front);
            _mm256_storeu_si256(near.as_mut_ptr().add(m).cast(), kept);
        }
        m += mask.count_ones() as usize;
        index = _mm256_add_epi32(index, _mm256_set1_epi32(8));
    }
    within_scalar(xyz, v, s2, n, m, near, d2s)
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
    fn the_candidates_within_reach_are_the_same_on_every_path() {
        use crate::neighbours::lane_sums::tests::FORCED;
        let mut next = crate::tests::common::uniform(7);
        // First one at the reach exactly (left out), one just inside, one not a number.
        let mut points = vec![[0.5, 0.0, 0.0], [0.0, -0.4999, 0.0], [f32::NAN; 3]];
        points.extend(
            (0..203)
                .map(|_| (crate::tests::common::uniform_point(&mut next) * 2.0 - 1.0).to_array()),
        );
        let mut coords = [Vec::new(), Vec::new(), Vec::new()];
        for p in points {
            coords.iter_mut().zip(p).for_each(|(c, x)| c.push(x));
        }
        let xyz = [&coords[0][..], &coords[1][..], &coords[2][..]];
        let run = |scalar: bool, v: Vec3| {
            let (mut near, mut d2s) = (vec![0; 214], vec![0.0f32; 214]);
            FORCED.set(scalar.then_some(Lanes::Scalar));
            let m = within(xyz, v, 0.25, &mut near, &mut d2s);
            FORCED.set(None);
            let d2s: Vec<u32> = d2s[..m].iter().map(|d| d.to_bits()).collect();
            (near[..m].to_vec(), d2s)
        };
        for v in [Vec3::ZERO, Vec3::new(0.3, -0.2, 0.1)] {
            let scalar = run(true, v);
            assert!(
                scalar.0.len() > 5 && scalar.0.len() < 100,
                "{}",
                scalar.0.len()
            );
            assert_eq!(run(false, v), scalar, "at {v}");
        }
        assert_eq!(
            run(true, Vec3::ZERO).0[0],
            1,
            "only the one inside the reach"
        );
    }

    #[test]
    fn the_bins_never_change_the_bits() {
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
        let kernel = RadialKernel::CubicSpline { support: 2.0 * r };
        let bits = |cell: f32| match interpolate(&vertices, &particles, &[&velocity], &kernel, cell)
            .unwrap()
            .remove(0)
        {
            Attribute::Vector(v) => v.iter().map(|v| v.to_array().map(f32::to_bits)).collect(),
            Attribute::Scalar(_) => Vec::new(),
        };
        let want: Vec<[u32; 3]> = bits(0.0);
        assert!(want.iter().any(|v| v[0] != 0));
        // Bins of half a support, then of one, two and four supports.
        for cell in [r / 2.0, r, 2.0 * r] {
            assert_eq!(bits(cell), want, "cell {cell}");
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
            // A particle just beyond the support adds nothing; one just inside does.
            let centre = Vec3::splat(side / 2.0);
            for (reach, felt) in [(1.001, false), (0.98, true)] {
                let mut with_probe = particles.clone();
                with_probe.push(centre + Vec3::new(reach * support, 0.0, 0.0));
                let mut probe = vec![0.0; particles.len()];
                probe.push(1.0);
                let Attribute::Scalar(v) = interpolate(
                    &[centre],
                    &with_probe,
                    &[&Attribute::Scalar(probe)],
                    &kernel,
                    0.0,
                )
                .unwrap()
                .remove(0) else {
                    panic!()
                };
                assert_eq!(
                    v[0] > 0.0,
                    felt,
                    "{kind}: probe at {reach} support: {}",
                    v[0]
                );
            }
        }
    }
}
