//! Rays against the metaball surface: front-to-back traversal of the hierarchy (Sec. 5.2) and,
//! in each leaf the ray crosses, the first root of the field on the ray's segment in its box.
//!
//! Root finding: the field along the ray is a sum of polynomials in t, one per metaball within
//! R of the ray (collected once per leaf). As in Sec. 3 it is sampled at the projections of
//! those centres (where each metaball peaks), plus the segment's ends and a grid of step the
//! lone-metaball radius (so that sparse droplets between projections are not stepped over);
//! the first outside→inside pair of samples brackets the root, which a bracketed Newton
//! iteration on the analytic derivative refines.

use glam::Vec3;

use super::fitted_bvh::{Aabb, FittedBvh, Node};

/// Where a ray meets the surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Distance along the (unit) ray direction.
    pub t: f32,
    /// Outward unit normal: the normalised gradient of the field.
    pub normal: Vec3,
}

/// The paper's Table 3 counts, summed over rays.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RayCounts {
    /// Rays traced (camera and shadow rays).
    pub rays: u64,
    /// Nodes visited.
    pub nodes: u64,
    /// Leaves whose segment was searched for a root ("intersection tests").
    pub leaves: u64,
    /// Entries of the lists of those leaves ("metaballs considered").
    pub metaballs: u64,
    /// Of those, the metaballs within R of the ray, whose polynomials were summed.
    pub along_ray: u64,
}

impl RayCounts {
    /// Adds `o`'s counts.
    pub fn add(&mut self, o: &RayCounts) {
        self.rays += o.rays;
        self.nodes += o.nodes;
        self.leaves += o.leaves;
        self.metaballs += o.metaballs;
        self.along_ray += o.along_ray;
    }
}

#[derive(Clone, Copy)]
struct Along {
    /// Projection of the centre on the ray.
    t: f32,
    /// 1 − δ²/R², δ the centre's distance from the ray.
    q: f32,
    index: u32,
}

/// Per-thread buffers, reused from ray to ray.
#[derive(Default)]
pub struct Scratch {
    stack: Vec<(u32, f32)>,
    along: Vec<Along>,
    samples: Vec<f32>,
}

/// Traces rays through a built hierarchy.
pub struct Tracer<'a> {
    bvh: &'a FittedBvh,
    step: f32,
    r2: f32,
    inv_r2: f32,
}

impl<'a> Tracer<'a> {
    /// A tracer over `bvh`.
    pub fn new(bvh: &'a FittedBvh) -> Tracer<'a> {
        let f = bvh.field;
        Tracer {
            bvh,
            step: f.lone_radius().max(f.cutoff * 1e-3),
            r2: f.cutoff * f.cutoff,
            inv_r2: f.inv_r2(),
        }
    }

    /// The first surface point on `o + t·d` (|d| = 1) with t in [`tmin`, `tmax`], entering the
    /// fluid from outside (a ray that starts inside passes its own way out and looks for the
    /// next surface it enters). With `any`, stops at the first hit found (shadow rays).
    #[allow(clippy::too_many_arguments)]
    pub fn first_hit(
        &self,
        o: Vec3,
        d: Vec3,
        tmin: f32,
        tmax: f32,
        any: bool,
        scratch: &mut Scratch,
        counts: &mut RayCounts,
    ) -> Option<Hit> {
        counts.rays += 1;
        let nodes = &self.bvh.nodes;
        let inv = d.recip();
        let mut best = tmax;
        let mut hit = None;
        let mut stack = std::mem::take(&mut scratch.stack);
        stack.clear();
        if let Some((t0, _)) = nodes
            .first()
            .and_then(|n| slab(&n.bounds, o, inv, tmin, best))
        {
            stack.push((0, t0));
        }
        while let Some((n, entry)) = stack.pop() {
            if entry > best {
                continue;
            }
            counts.nodes += 1;
            let node = &nodes[n as usize];
            if node.count > 0 {
                let Some((t0, t1)) = slab(&node.bounds, o, inv, tmin, best) else {
                    continue;
                };
                if let Some(h) = self.leaf_hit(node, o, d, t0, t1, scratch, counts)
                    && h.t < best
                {
                    best = h.t;
                    hit = Some(h);
                    if any {
                        break;
                    }
                }
                continue;
            }
            let (l, r) = (n + 1, node.first);
            let sl = slab(&nodes[l as usize].bounds, o, inv, tmin, best);
            let sr = slab(&nodes[r as usize].bounds, o, inv, tmin, best);
            match (sl, sr) {
                (Some((tl, _)), Some((tr, _))) => {
                    // Far child first on the stack, so that the near one is popped first.
                    if tl <= tr {
                        stack.push((r, tr));
                        stack.push((l, tl));
                    } else {
                        stack.push((l, tl));
                        stack.push((r, tr));
                    }
                }
                (Some((tl, _)), None) => stack.push((l, tl)),
                (None, Some((tr, _))) => stack.push((r, tr)),
                (None, None) => {}
            }
        }
        scratch.stack = stack;
        hit
    }

    /// The first outside→inside root on [`t0`, `t1`] of the field of `node`'s list.
    #[allow(clippy::too_many_arguments)]
    fn leaf_hit(
        &self,
        node: &Node,
        o: Vec3,
        d: Vec3,
        t0: f32,
        t1: f32,
        scratch: &mut Scratch,
        counts: &mut RayCounts,
    ) -> Option<Hit> {
        let list = &self.bvh.items[node.first as usize..(node.first + node.count) as usize];
        counts.leaves += 1;
        counts.metaballs += list.len() as u64;
        // Distances are measured from the segment's start, so that f32 keeps its precision
        // for cameras far from the fluid.
        let base = o + t0 * d;
        let span = t1 - t0;
        let along = &mut scratch.along;
        along.clear();
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for &index in list {
            let v = self.bvh.points[index as usize] - base;
            let t = v.dot(d);
            let dist2 = v.cross(d).length_squared();
            if dist2 >= self.r2 {
                continue;
            }
            let half = (self.r2 - dist2).sqrt();
            if t + half <= 0.0 || t - half >= span {
                continue;
            }
            lo = lo.min(t - half);
            hi = hi.max(t + half);
            along.push(Along {
                t,
                q: 1.0 - dist2 * self.inv_r2,
                index,
            });
        }
        counts.along_ray += along.len() as u64;
        if along.is_empty() {
            return None;
        }
        // The field is zero (outside) beyond the reach of the metaballs along the ray.
        let (a0, b0) = (lo.max(0.0), hi.min(span));
        if a0 > b0 {
            return None;
        }
        let samples = &mut scratch.samples;
        samples.clear();
        samples.extend([a0, b0]);
        samples.extend(along.iter().map(|m| m.t).filter(|&t| t > a0 && t < b0));
        // The grid is fixed along the ray (multiples of the step from its origin).
        let first = ((t0 + a0) / self.step).floor() + 1.0;
        let last = ((t0 + b0) / self.step).ceil() - 1.0;
        if last >= first && last - first < 65536.0 {
            let mut k = first;
            while k <= last {
                let s = k * self.step - t0;
                if s > a0 && s < b0 {
                    samples.push(s);
                }
                k += 1.0;
            }
        }
        samples.sort_unstable_by(f32::total_cmp);
        let mut outside: Option<f32> = None;
        for &s in samples.iter() {
            if self.excess(along, s) < 0.0 {
                outside = Some(s);
            } else if let Some(a) = outside {
                let s = self.refine(along, a, s);
                let normal = self.normal(along, base + s * d, d);
                return Some(Hit { t: t0 + s, normal });
            }
        }
        None
    }

    /// Σ t_i^α − T/c along the ray at `t`: ≥ 0 inside.
    fn excess(&self, along: &[Along], t: f32) -> f32 {
        let alpha = self.bvh.field.exponent;
        let mut sum = 0.0;
        for m in along {
            let dt = t - m.t;
            let k = m.q - dt * dt * self.inv_r2;
            if k > 0.0 {
                sum += k.powi(alpha);
            }
        }
        sum - self.bvh.field.level
    }

    /// [`excess`](Self::excess) and its derivative in t.
    fn excess_slope(&self, along: &[Along], t: f32) -> (f32, f32) {
        let alpha = self.bvh.field.exponent;
        let (mut sum, mut slope) = (0.0, 0.0);
        for m in along {
            let dt = t - m.t;
            let k = m.q - dt * dt * self.inv_r2;
            if k > 0.0 {
                let p = k.powi(alpha - 1);
                sum += p * k;
                slope += alpha as f32 * p * (-2.0 * dt * self.inv_r2);
            }
        }
        (sum - self.bvh.field.level, slope)
    }

    /// The root in [a, b] (outside at a, inside at b): Newton steps on the analytic derivative
    /// while they stay inside the bracket, bisection otherwise.
    fn refine(&self, along: &[Along], mut a: f32, mut b: f32) -> f32 {
        let tol = (self.bvh.field.cutoff * 1e-5).max(b.abs() * 4.0 * f32::EPSILON);
        let mut t = 0.5 * (a + b);
        for _ in 0..64 {
            let (g, dg) = self.excess_slope(along, t);
            if g >= 0.0 {
                b = t;
            } else {
                a = t;
            }
            if b - a <= tol {
                return 0.5 * (a + b);
            }
            let newton = t - g / dg;
            if dg != 0.0 && newton > a && newton < b {
                if (newton - t).abs() <= 0.25 * tol {
                    return newton;
                }
                t = newton;
            } else {
                t = 0.5 * (a + b);
            }
        }
        0.5 * (a + b)
    }

    /// The outward unit normal at `x`: ∇f ∝ Σ t_i^(α−1)(x − p_i).
    fn normal(&self, along: &[Along], x: Vec3, d: Vec3) -> Vec3 {
        let alpha = self.bvh.field.exponent;
        let mut g = Vec3::ZERO;
        for m in along {
            let v = x - self.bvh.points[m.index as usize];
            let k = 1.0 - v.length_squared() * self.inv_r2;
            if k > 0.0 {
                g += k.powi(alpha - 1) * v;
            }
        }
        g.try_normalize().unwrap_or(-d)
    }
}

/// The part of [`tmin`, `tmax`] where the ray is in the box.
#[inline]
fn slab(b: &Aabb, o: Vec3, inv: Vec3, tmin: f32, tmax: f32) -> Option<(f32, f32)> {
    let t1 = (b.min - o) * inv;
    let t2 = (b.max - o) * inv;
    let near = t1.min(t2).max_element().max(tmin);
    let far = t1.max(t2).min_element().min(tmax);
    (near <= far).then_some((near, far))
}
