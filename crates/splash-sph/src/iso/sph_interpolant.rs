//! The SPH interpolant (Sec. I, III-A): A(x) = Σ_j V_j A_j W(x − x_j, s_j), with V_j = m_j/ρ_j,
//! the cubic spline of support s_j, its analytic gradient, and the sum of weights Σ_j V_j W
//! that trimming reads (Sec. III-D3). Sums run in f64 over the particles in handler order, so
//! a value does not depend on the thread that asks and the correction can reach 1e-5.

use glam::{DVec3, IVec3, Vec3};
use rayon::prelude::*;

use crate::neighbours::handler_array::HandlerArray;

/// Where the per-particle data live among the handler array's channels.
#[derive(Debug, Clone)]
pub(crate) struct Channels {
    /// Each particle's kernel support s_j (2h_j, scaled).
    pub support: usize,
    /// Each particle's volume m_j/ρ_j.
    pub volume: usize,
    /// The scalar A_j whose isosurface is extracted.
    pub value: usize,
    /// Further attributes carried onto the vertices: first channel and width (1 or 3).
    pub extras: Vec<(usize, usize)>,
}

/// A, ∇A and Σ V W at a point.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Sample {
    pub value: f64,
    pub gradient: DVec3,
    pub weight: f64,
}

/// The particles sorted into lookup cells of the largest support, with their channels.
pub(crate) struct Interpolant {
    pub handlers: HandlerArray,
    pub channels: Channels,
    pub shepard: bool,
}

/// The cubic spline of the density field (`field/density.rs`) with its normalisation
/// 8/(π s³), for support s, in f64: W and dW/dr / r at distance² `r2`.
#[inline]
pub(crate) fn spline(r2: f64, s: f64) -> (f64, f64) {
    let r = r2.sqrt();
    let q = r / s;
    let (a, b) = ((1.0 - q).max(0.0), (0.5 - q).max(0.0));
    let sigma = 8.0 / (std::f64::consts::PI * s * s * s);
    let w = sigma * (2.0 * a * a * a - 8.0 * b * b * b);
    // dW/dq = σ(24 b² − 6 a²); dW/dr / r = dW/dq / (s r), finite at r = 0 where it is unused.
    let slope = sigma * (24.0 * b * b - 6.0 * a * a) / (s * r.max(f64::MIN_POSITIVE));
    (w, slope)
}

impl Interpolant {
    /// Calls `f(j, d, W, dW/dr / r)` for every particle j whose kernel reaches `x`, with
    /// d = x − x_j, in handler order.
    #[inline]
    pub fn for_each_near(&self, x: Vec3, mut f: impl FnMut(usize, DVec3, f64, f64)) {
        let h = &self.handlers;
        let c = h.cell_of(x);
        let xd = x.as_dvec3();
        let supports = &h.channels[self.channels.support];
        h.for_each_in_cells(c - IVec3::ONE, c + IVec3::ONE, |range| {
            for j in range {
                let d = xd - h.positions[j].as_dvec3();
                let r2 = d.length_squared();
                let s = f64::from(supports[j]);
                if r2 < s * s {
                    let (w, slope) = spline(r2, s);
                    f(j, d, w, slope);
                }
            }
        });
    }

    /// At every particle i, in handler order: `finish` of what `add(sum, ∇W_ij, v_j − v_i, V_j)`
    /// sums over the particles j near it, v the velocity in channels `first..first + 3`. The
    /// difference form of the SPH velocity derivatives (vorticity, gradient), in parallel.
    pub(crate) fn velocity_sums<S: Default>(
        &self,
        first: usize,
        add: impl Fn(&mut S, DVec3, DVec3, f64) + Sync,
        finish: impl Fn(S) -> f32 + Sync,
    ) -> Vec<f32> {
        let h = &self.handlers;
        let (v, vol) = (
            &h.channels[first..first + 3],
            &h.channels[self.channels.volume],
        );
        let vel = |j: usize| DVec3::new(v[0][j].into(), v[1][j].into(), v[2][j].into());
        (0..h.positions.len())
            .into_par_iter()
            .map(|i| {
                let vi = vel(i);
                let mut sum = S::default();
                self.for_each_near(h.positions[i], |j, d, _, slope| {
                    add(&mut sum, d * slope, vel(j) - vi, f64::from(vol[j]));
                });
                finish(sum)
            })
            .collect()
    }

    /// The mean number of other particles whose kernel reaches a particle, over at most
    /// `samples` particles spread evenly through the handler order (a fixed choice, so the
    /// figure does not depend on threads).
    pub fn mean_neighbours(&self, samples: usize) -> f64 {
        let n = self.handlers.positions.len();
        if n == 0 {
            return 0.0;
        }
        let stride = n.div_ceil(samples.max(1));
        let (mut count, mut sampled) = (0u64, 0u64);
        for i in (0..n).step_by(stride) {
            let mut near = 0u64;
            self.for_each_near(self.handlers.positions[i], |_, _, _, _| near += 1);
            // The particle itself is near at distance 0.
            count += near - 1;
            sampled += 1;
        }
        count as f64 / sampled as f64
    }

    /// A, ∇A and Σ V W at `x` for channel `channel`.
    pub fn sample(&self, x: Vec3, channel: usize) -> Sample {
        let (volumes, values) = (
            &self.handlers.channels[self.channels.volume],
            &self.handlers.channels[channel],
        );
        let (mut n, mut gn, mut d0, mut gd) = (0.0, DVec3::ZERO, 0.0, DVec3::ZERO);
        self.for_each_near(x, |j, d, w, slope| {
            let v = f64::from(volumes[j]);
            let a = f64::from(values[j]);
            n += v * a * w;
            gn += d * (v * a * slope);
            d0 += v * w;
            gd += d * (v * slope);
        });
        if self.shepard {
            if d0 > 0.0 {
                Sample {
                    value: n / d0,
                    gradient: (gn * d0 - gd * n) / (d0 * d0),
                    weight: d0,
                }
            } else {
                Sample::default()
            }
        } else {
            Sample {
                value: n,
                gradient: gn,
                weight: d0,
            }
        }
    }

    /// The interpolated extra attributes at `x`, written into `out` (one value per channel).
    pub fn extras_at(&self, x: Vec3, out: &mut [f32]) {
        let ch = &self.handlers.channels;
        let volumes = &ch[self.channels.volume];
        let first = self.channels.extras.first().map_or(0, |e| e.0);
        let mut sums = [0.0f64; 32];
        let mut weight = 0.0;
        self.for_each_near(x, |j, _, w, _| {
            let vw = f64::from(volumes[j]) * w;
            weight += vw;
            for (k, s) in sums.iter_mut().take(out.len()).enumerate() {
                *s += vw * f64::from(ch[first + k][j]);
            }
        });
        let norm = if self.shepard && weight > 0.0 {
            1.0 / weight
        } else {
            1.0
        };
        for (o, s) in out.iter_mut().zip(sums) {
            *o = (s * norm) as f32;
        }
    }
}
