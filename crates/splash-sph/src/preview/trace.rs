//! Rays against the metaball surface: front-to-back traversal of the hierarchy (Sec. 5.2) and,
//! in each leaf the ray crosses, the field of the leaf's list along the ray (Sec. 3).
//!
//! The hierarchy only accelerates: the hit must not depend on it. So each ray has one set of
//! samples and one field, whatever the hierarchy:
//! - distances run from where the ray enters the box of all metaballs' spheres, and each
//!   metaball's polynomial along the ray (its projection t_i and q_i) is computed alike;
//! - the samples are the start, the multiples of a step (the lone-metaball radius, so that
//!   sparse droplets are not stepped over) and the projections t_i, where each metaball peaks;
//! - the field at a sample sums the metaballs in particle order.
//!
//! Pass 1 traverses the hierarchy for the first inside sample. At an inside point of its box a
//! leaf's list holds every metaball non-zero there, so its sum is the field's to the bit;
//! anywhere else it sums a subset in the same order, which rounding keeps below the field, so
//! it never calls an outside sample inside. Pass 2 collects exactly the metaballs along the
//! last step before that sample (boxes of their spheres, not the fitted boxes) and refines the
//! root between the previous sample and it: Newton steps on the analytic derivative (the sums
//! that give the field give it too) while they stay inside the bracket, bisection otherwise;
//! the paper narrows its interval with the secant method instead. A ray that starts inside
//! walks out with pass 2 first.

use glam::Vec3;

use super::fitted_bvh::{Aabb, FittedBvh, LEAF_K_COST};

/// Where a ray meets the surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Distance along the (unit) ray direction.
    pub t: f32,
    /// Outward unit normal: the normalised gradient of the field.
    pub normal: Vec3,
    /// The per-particle values of [`Tracer::with_values`] at the hit, weighted by the metaballs'
    /// t_i^α there (in particle order, so independent of the hierarchy); 0 without values.
    pub value: f32,
}

/// The paper's Table 3 counts, summed over rays: pass 1's, and pass 2's node visits.
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
    /// Σ n² over those leaves: the paper's model of their cost.
    pub metaballs_squared: u64,
    /// Of those, the metaballs within R of the ray, whose polynomials were summed.
    pub along_ray: u64,
    /// Terms of the field sums at pass 1's samples: the k metaballs along the ray times the
    /// samples tested, the leaf test's part that grows as k².
    pub terms: u64,
    /// Nodes visited by pass 2 (collecting the metaballs to refine a hit or walk out).
    pub refine_nodes: u64,
    /// Metaballs pass 2 tested against the ray.
    pub refine_metaballs: u64,
}

impl RayCounts {
    /// The leaf tests' cost in entry tests by the measured model n + 16·k, the one
    /// [`SplitRule::Measured`](super::SplitRule::Measured) builds for: the entries of the leaves'
    /// lists plus 16 per metaball within R of the ray ([`metaballs`](Self::metaballs) + 16 ·
    /// [`along_ray`](Self::along_ray)).
    pub fn leaf_test_cost(&self) -> f64 {
        self.metaballs as f64 + f64::from(LEAF_K_COST) * self.along_ray as f64
    }

    /// Adds `o`'s counts.
    pub(crate) fn add(&mut self, o: &RayCounts) {
        self.rays += o.rays;
        self.nodes += o.nodes;
        self.leaves += o.leaves;
        self.metaballs += o.metaballs;
        self.metaballs_squared += o.metaballs_squared;
        self.along_ray += o.along_ray;
        self.terms += o.terms;
        self.refine_nodes += o.refine_nodes;
        self.refine_metaballs += o.refine_metaballs;
    }
}

#[derive(Clone, Copy)]
struct Along {
    /// Projection of the centre on the ray.
    t: f32,
    /// 1 − δ²/R², δ the centre's distance from the ray.
    q: f32,
    /// Half the chord of the sphere of radius R on the ray.
    half: f32,
    /// Index into the hierarchy's centres.
    index: u32,
}

/// Per-thread buffers, reused from ray to ray.
#[derive(Default)]
pub struct Scratch {
    stack: Vec<(u32, f32)>,
    along: Vec<Along>,
    exact: Vec<(u32, Along)>,
    samples: Vec<f32>,
    /// A packet's rays (the index of their direction) and first inside samples.
    packet: Vec<(usize, Ray, f32)>,
    /// The packet's rays crossing a node, and where.
    crossing: Vec<(usize, f32, f32)>,
    /// The entries of a leaf near some ray of the packet.
    near: Vec<u32>,
}

/// Traces rays through a built hierarchy.
pub struct Tracer<'a> {
    bvh: &'a FittedBvh,
    values: Option<&'a [f32]>,
    step: f32,
    r2: f32,
    inv_r2: f32,
    /// Slack of box and interval tests against rounding: they may only err towards keeping.
    margin: f32,
}

/// A ray with its origin of distances `base` = o + tb·d, where it enters the scene's box.
#[derive(Clone, Copy)]
struct Ray {
    o: Vec3,
    d: Vec3,
    inv: Vec3,
    tb: f32,
    base: Vec3,
    /// Where it leaves the scene's box (or tmax), from `base`.
    end: f32,
}

impl<'a> Tracer<'a> {
    /// A tracer over `bvh`.
    pub fn new(bvh: &'a FittedBvh) -> Tracer<'a> {
        let f = bvh.field;
        Tracer {
            bvh,
            values: None,
            step: f.lone_radius().max(f.cutoff * 1e-3),
            r2: f.cutoff * f.cutoff,
            inv_r2: f.inv_r2(),
            margin: f.cutoff * 1e-3,
        }
    }

    /// The same tracer interpolating `values` (one per particle, in the particles' order) at
    /// its hits.
    pub fn with_values(mut self, values: &'a [f32]) -> Tracer<'a> {
        self.values = Some(values);
        self
    }

    fn ray(&self, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> Option<Ray> {
        let inv = d.recip();
        let (t0, t1) = slab(&self.bvh.scene, o, inv, tmin, tmax, 0.0)?;
        Some(Ray {
            o,
            d,
            inv,
            tb: t0,
            base: o + t0 * d,
            end: t1 - t0,
        })
    }

    /// The first surface point on `o + t·d` (|d| = 1) with t in [`tmin`, `tmax`], entering the
    /// fluid from outside (a ray that starts inside passes its own way out and looks for the
    /// next surface it enters).
    pub fn first_hit(
        &self,
        o: Vec3,
        d: Vec3,
        tmin: f32,
        tmax: f32,
        scratch: &mut Scratch,
        counts: &mut RayCounts,
    ) -> Option<Hit> {
        counts.rays += 1;
        let ray = self.ray(o, d, tmin, tmax)?;
        let first = self.first_inside(&ray, 0.0, false, scratch, counts);
        self.hit_from(&ray, first, scratch, counts)
    }

    /// The hit of `ray` whose first inside sample from its start is `first`.
    fn hit_from(
        &self,
        ray: &Ray,
        first: Option<f32>,
        scratch: &mut Scratch,
        counts: &mut RayCounts,
    ) -> Option<Hit> {
        let (mut start, mut s) = (0.0, first?);
        loop {
            if s > start {
                return Some(self.refine_hit(ray, start, s, scratch, counts));
            }
            start = self.exit(ray, start, scratch, counts)?;
            s = self.first_inside(ray, start, false, scratch, counts)?;
        }
    }

    /// [`first_hit`](Self::first_hit) of the rays from `o` along each of `dirs` over all
    /// distances, into `hits`: the samples of a pixel, whose directions differ by little. They
    /// traverse the hierarchy together, and a leaf's entries too far from all of them for any
    /// to pass within R are dropped once for all; each ray then meets the same entries, in the
    /// same order, as alone, so each hit is [`first_hit`](Self::first_hit)'s to the bit.
    pub fn first_hits(
        &self,
        o: Vec3,
        dirs: &[Vec3],
        hits: &mut Vec<Option<Hit>>,
        scratch: &mut Scratch,
        counts: &mut RayCounts,
    ) {
        hits.clear();
        if dirs.len() == 1 {
            hits.push(self.first_hit(o, dirs[0], 0.0, f32::INFINITY, scratch, counts));
            return;
        }
        counts.rays += dirs.len() as u64;
        let mut packet = std::mem::take(&mut scratch.packet);
        packet.clear();
        packet.extend(
            (dirs.iter().enumerate()).filter_map(|(i, &d)| {
                Some((i, self.ray(o, d, 0.0, f32::INFINITY)?, f32::INFINITY))
            }),
        );
        self.first_inside_packet(&mut packet, scratch, counts);
        hits.resize(dirs.len(), None);
        for &(i, ray, best) in &packet {
            hits[i] = self.hit_from(&ray, best.is_finite().then_some(best), scratch, counts);
        }
        scratch.packet = packet;
    }

    /// Whether [`first_hit`](Self::first_hit) would find a surface; stops at the first inside
    /// sample found (shadow rays).
    pub fn occluded(
        &self,
        o: Vec3,
        d: Vec3,
        tmin: f32,
        tmax: f32,
        scratch: &mut Scratch,
        counts: &mut RayCounts,
    ) -> bool {
        counts.rays += 1;
        let Some(ray) = self.ray(o, d, tmin, tmax) else {
            return false;
        };
        // Pass 1 from the start finds an inside sample whenever the start is inside (its
        // leaf sums the exact field there): none, and the ray is free without pass 2.
        if self
            .first_inside(&ray, 0.0, true, scratch, counts)
            .is_none()
        {
            return false;
        }
        self.collect_exact(&ray, 0.0, 0.0, scratch, counts);
        if self.excess(scratch.exact.iter().map(|e| &e.1), 0.0) < 0.0 {
            return true;
        }
        match self.exit(&ray, 0.0, scratch, counts) {
            Some(s) => self.first_inside(&ray, s, true, scratch, counts).is_some(),
            None => false,
        }
    }

    /// Pass 1: the first sample at or after `start` inside the fluid (with `any`, some such
    /// sample), from `ray.base`.
    fn first_inside(
        &self,
        ray: &Ray,
        start: f32,
        any: bool,
        scratch: &mut Scratch,
        counts: &mut RayCounts,
    ) -> Option<f32> {
        let nodes = &self.bvh.nodes;
        let m = self.margin;
        let lo = ray.tb + start;
        let mut best = f32::INFINITY;
        let limit = |best: f32| ray.tb + best.min(ray.end);
        let mut stack = std::mem::take(&mut scratch.stack);
        stack.clear();
        if let Some((t0, _)) = nodes
            .first()
            .and_then(|n| slab(&n.bounds, ray.o, ray.inv, lo, limit(best), m))
        {
            stack.push((0, t0));
        }
        while let Some((n, entry)) = stack.pop() {
            if entry > limit(best) {
                continue;
            }
            counts.nodes += 1;
            let node = &nodes[n as usize];
            if node.count > 0 {
                let Some((t0, t1)) = slab(&node.bounds, ray.o, ray.inv, lo, limit(best), m) else {
                    continue;
                };
                let (u0, u1) = (t0 - ray.tb, (t1 - ray.tb).min(best));
                let list = &self.bvh.items[node.first as usize..(node.first + node.count) as usize];
                counts.leaves += 1;
                counts.metaballs += list.len() as u64;
                counts.metaballs_squared += (list.len() * list.len()) as u64;
                if let Some(s) = self.leaf_inside(list, ray, start, u0, u1, scratch, counts)
                    && s < best
                {
                    best = s;
                    if any {
                        break;
                    }
                }
                continue;
            }
            let (l, r) = (n + 1, node.first);
            let sl = slab(
                &nodes[l as usize].bounds,
                ray.o,
                ray.inv,
                lo,
                limit(best),
                m,
            );
            let sr = slab(
                &nodes[r as usize].bounds,
                ray.o,
                ray.inv,
                lo,
                limit(best),
                m,
            );
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
        best.is_finite().then_some(best)
    }

    /// The projection t and distance² from the ray of centre `index`, from `ray.base`.
    #[inline]
    fn along(&self, ray: &Ray, index: u32) -> Option<Along> {
        let v = self.bvh.points[index as usize] - ray.base;
        let dist2 = v.cross(ray.d).length_squared();
        (dist2 < self.r2).then(|| Along {
            t: v.dot(ray.d),
            q: 1.0 - dist2 * self.inv_r2,
            half: (self.r2 - dist2).sqrt() + self.margin,
            index,
        })
    }

    /// Pass 1 for a packet of rays from one origin, each `(_, ray, best)` from its start:
    /// `best` becomes its first inside sample (the minimum over the leaves it crosses, as
    /// alone, whatever order they are visited in).
    fn first_inside_packet(
        &self,
        packet: &mut [(usize, Ray, f32)],
        scratch: &mut Scratch,
        counts: &mut RayCounts,
    ) {
        let (nodes, m) = (&self.bvh.nodes, self.margin);
        let Some((_, first, _)) = packet.first() else {
            return;
        };
        let (o, d0) = (first.o, first.d);
        let spread = packet
            .iter()
            .map(|(_, r, _)| (r.d - d0).length())
            .fold(0.0, f32::max);
        let mut stack = std::mem::take(&mut scratch.stack);
        let mut crossing = std::mem::take(&mut scratch.crossing);
        let mut near = std::mem::take(&mut scratch.near);
        stack.clear();
        if !nodes.is_empty() {
            stack.push((0, 0.0));
        }
        while let Some((n, _)) = stack.pop() {
            let node = &nodes[n as usize];
            crossing.clear();
            for (k, (_, ray, best)) in packet.iter().enumerate() {
                let limit = ray.tb + best.min(ray.end);
                if let Some((t0, t1)) = slab(&node.bounds, ray.o, ray.inv, ray.tb, limit, m) {
                    crossing.push((k, t0, t1));
                }
            }
            counts.nodes += crossing.len() as u64;
            if crossing.is_empty() {
                continue;
            }
            if node.count == 0 {
                // Nearer child (by its centre along the first ray) popped first.
                let (l, r) = (n + 1, node.first);
                let depth = |c: u32| {
                    let b = &nodes[c as usize].bounds;
                    (0.5 * (b.min + b.max) - o).dot(d0)
                };
                if depth(l) <= depth(r) {
                    stack.push((r, 0.0));
                    stack.push((l, 0.0));
                } else {
                    stack.push((l, 0.0));
                    stack.push((r, 0.0));
                }
                continue;
            }
            let list = &self.bvh.items[node.first as usize..(node.first + node.count) as usize];
            counts.leaves += crossing.len() as u64;
            counts.metaballs_squared += (list.len() * list.len()) as u64 * crossing.len() as u64;
            let list = if crossing.len() > 1 {
                // A centre p is at least |(p − o) × d0| − |p − o|·spread from every ray: keep
                // those that may be within R of one (with slack for rounding), in list order.
                let b = node.bounds;
                let far = (b.min - o).abs().max((b.max - o).abs()).length() + self.bvh.field.cutoff;
                let reach = self.bvh.field.cutoff + far * (spread + 1e-5) + m;
                let reach2 = reach * reach;
                near.clear();
                near.extend(list.iter().copied().filter(|&i| {
                    (self.bvh.points[i as usize] - o).cross(d0).length_squared() <= reach2
                }));
                counts.metaballs += list.len() as u64;
                &near[..]
            } else {
                list
            };
            for &(k, t0, t1) in &crossing {
                let (_, ray, best) = &mut packet[k];
                let (u0, u1) = (t0 - ray.tb, (t1 - ray.tb).min(*best));
                counts.metaballs += list.len() as u64;
                if let Some(s) = self.leaf_inside(list, ray, 0.0, u0, u1, scratch, counts)
                    && s < *best
                {
                    *best = s;
                }
            }
        }
        scratch.stack = stack;
        scratch.crossing = crossing;
        scratch.near = near;
    }

    /// The first sample in [`u0`, `u1`] (and after `start`) inside by a leaf's `list` (or
    /// the part of it that may be within R of the ray).
    #[allow(clippy::too_many_arguments)]
    fn leaf_inside(
        &self,
        list: &[u32],
        ray: &Ray,
        start: f32,
        u0: f32,
        u1: f32,
        scratch: &mut Scratch,
        counts: &mut RayCounts,
    ) -> Option<f32> {
        let along = &mut scratch.along;
        along.clear();
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for &index in list {
            let Some(a) = self.along(ray, index) else {
                continue;
            };
            if a.t + a.half < u0 || a.t - a.half > u1 {
                continue;
            }
            lo = lo.min(a.t - a.half);
            hi = hi.max(a.t + a.half);
            along.push(a);
        }
        counts.along_ray += along.len() as u64;
        // The field is zero (outside) beyond the reach of the metaballs along the ray.
        let (a0, b0) = (lo.max(u0).max(start), hi.min(u1));
        if a0 > b0 {
            return None;
        }
        let samples = &mut scratch.samples;
        samples.clear();
        if start >= a0 {
            samples.push(start);
        }
        samples.extend(along.iter().map(|m| m.t).filter(|&t| t >= a0 && t <= b0));
        self.grid(a0, b0, samples);
        samples.sort_unstable_by(f32::total_cmp);
        let mut tested = 0;
        let found = samples.iter().copied().find(|&s| {
            tested += 1;
            self.excess(along.iter(), s) >= 0.0
        });
        counts.terms += tested * along.len() as u64;
        found
    }

    /// The multiples of the step in [`a`, `b`].
    fn grid(&self, a: f32, b: f32, samples: &mut Vec<f32>) {
        // One multiple more each side: the division rounds, the test on k·step decides.
        let first = (a / self.step).ceil() - 1.0;
        let last = (b / self.step).floor() + 1.0;
        if !(last >= first && last - first < 65536.0) {
            return;
        }
        let mut k = first;
        while k <= last {
            let s = k * self.step;
            if s >= a && s <= b {
                samples.push(s);
            }
            k += 1.0;
        }
    }

    /// Pass 2: every metaball whose sphere meets the ray between `u0` and `u1`, in particle
    /// order, into `scratch.exact`, found through the boxes of the nodes' spheres.
    fn collect_exact(
        &self,
        ray: &Ray,
        u0: f32,
        u1: f32,
        scratch: &mut Scratch,
        counts: &mut RayCounts,
    ) {
        let (nodes, reach) = (&self.bvh.nodes, &self.bvh.reach);
        let exact = &mut scratch.exact;
        exact.clear();
        let stack = &mut scratch.stack;
        stack.clear();
        if !nodes.is_empty() {
            stack.push((0, 0.0));
        }
        let (t0, t1) = (ray.tb + u0, ray.tb + u1);
        while let Some((n, _)) = stack.pop() {
            let n = n as usize;
            counts.refine_nodes += 1;
            if slab(&reach[n].bounds, ray.o, ray.inv, t0, t1, self.margin).is_none() {
                continue;
            }
            if nodes[n].count == 0 {
                stack.push((nodes[n].first, 0.0));
                stack.push((n as u32 + 1, 0.0));
                continue;
            }
            let [a, b] = reach[n].own;
            counts.refine_metaballs += (b - a) as u64;
            for index in a..b {
                if let Some(m) = self.along(ray, index)
                    && m.t + m.half >= u0
                    && m.t - m.half <= u1
                {
                    exact.push((self.bvh.original[index as usize], m));
                }
            }
        }
        exact.sort_unstable_by_key(|e| e.0);
    }

    /// The first sample after `start` outside the fluid, walking on with pass 2.
    fn exit(
        &self,
        ray: &Ray,
        start: f32,
        scratch: &mut Scratch,
        counts: &mut RayCounts,
    ) -> Option<f32> {
        let mut u = start;
        while u <= ray.end {
            let next = u + 4.0 * self.step;
            self.collect_exact(ray, u, next, scratch, counts);
            let samples = &mut scratch.samples;
            samples.clear();
            let exact = &scratch.exact;
            samples.extend(exact.iter().map(|e| e.1.t).filter(|&t| t > u && t <= next));
            self.grid(u, next, samples);
            samples.retain(|&s| s > u);
            samples.sort_unstable_by(f32::total_cmp);
            if let Some(s) = samples
                .iter()
                .copied()
                .find(|&s| self.excess(exact.iter().map(|e| &e.1), s) < 0.0)
            {
                return Some(s);
            }
            u = next;
        }
        None
    }

    /// The hit between the sample before `s` (outside) and `s` (the first inside one).
    fn refine_hit(
        &self,
        ray: &Ray,
        start: f32,
        s: f32,
        scratch: &mut Scratch,
        counts: &mut RayCounts,
    ) -> Hit {
        // The largest multiple of the step below s, or the start.
        let mut k = (s / self.step).floor() + 1.0;
        while k * self.step >= s {
            k -= 1.0;
        }
        let w0 = (k * self.step).max(start);
        self.collect_exact(ray, w0, s, scratch, counts);
        let exact = &scratch.exact;
        let a = exact
            .iter()
            .map(|e| e.1.t)
            .filter(|&t| t > w0 && t < s)
            .fold(w0, f32::max);
        let u = self.refine(exact, a, s);
        let x = ray.base + u * ray.d;
        Hit {
            t: ray.tb + u,
            normal: self.normal(exact, x, ray.d),
            value: self.values.map_or(0.0, |v| self.value(exact, x, v)),
        }
    }

    /// Σ t_i^α − T/c along the ray at `t`: ≥ 0 inside.
    fn excess<'b>(&self, along: impl Iterator<Item = &'b Along>, t: f32) -> f32 {
        let alpha = self.bvh.field.exponent;
        let mut sum = 0.0;
        for m in along {
            let dt = t - m.t;
            let k = m.q - dt * dt * self.inv_r2;
            if k > 0.0 {
                sum += powi(k, alpha);
            }
        }
        sum - self.bvh.field.level
    }

    /// [`excess`](Self::excess) and its derivative in t.
    fn excess_slope(&self, along: &[(u32, Along)], t: f32) -> (f32, f32) {
        let alpha = self.bvh.field.exponent;
        let (mut sum, mut slope) = (0.0, 0.0);
        for (_, m) in along {
            let dt = t - m.t;
            let k = m.q - dt * dt * self.inv_r2;
            if k > 0.0 {
                let p = powi(k, alpha - 1);
                sum += p * k;
                slope += alpha as f32 * p * (-2.0 * dt * self.inv_r2);
            }
        }
        (sum - self.bvh.field.level, slope)
    }

    /// The root in [a, b] (outside at a, inside at b): Newton steps on the analytic derivative
    /// while they stay inside the bracket, bisection otherwise.
    fn refine(&self, along: &[(u32, Along)], mut a: f32, mut b: f32) -> f32 {
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

    /// Σ w_i v_i / Σ w_i at `x` with the metaballs' weights w_i = t_i^α (the nearest metaball's
    /// value where all weights vanish, as rounding can leave at the surface's edge).
    fn value(&self, along: &[(u32, Along)], x: Vec3, values: &[f32]) -> f32 {
        let alpha = self.bvh.field.exponent;
        let (mut sum, mut weights) = (0.0f32, 0.0f32);
        let mut nearest = (f32::INFINITY, 0.0);
        for (original, m) in along {
            let d2 = (x - self.bvh.points[m.index as usize]).length_squared();
            let v = values[*original as usize];
            let k = 1.0 - d2 * self.inv_r2;
            if k > 0.0 {
                let w = powi(k, alpha);
                sum += w * v;
                weights += w;
            }
            if d2 < nearest.0 {
                nearest = (d2, v);
            }
        }
        if weights > 0.0 {
            sum / weights
        } else {
            nearest.1
        }
    }

    /// The outward unit normal at `x`: ∇f ∝ Σ t_i^(α−1)(x − p_i).
    fn normal(&self, along: &[(u32, Along)], x: Vec3, d: Vec3) -> Vec3 {
        let alpha = self.bvh.field.exponent;
        let mut g = Vec3::ZERO;
        for (_, m) in along {
            let v = x - self.bvh.points[m.index as usize];
            let k = 1.0 - v.length_squared() * self.inv_r2;
            if k > 0.0 {
                g += powi(k, alpha - 1) * v;
            }
        }
        g.try_normalize().unwrap_or(-d)
    }
}

/// The part of [`tmin`, `tmax`] where the ray is in the box, widened by `slack` each way.
#[inline]
fn slab(b: &Aabb, o: Vec3, inv: Vec3, tmin: f32, tmax: f32, slack: f32) -> Option<(f32, f32)> {
    let t1 = (b.min - o) * inv;
    let t2 = (b.max - o) * inv;
    let near = t1.min(t2).max_element().max(tmin) - slack;
    let far = t1.max(t2).min_element().min(tmax) + slack;
    (near <= far).then_some((near, far))
}

/// x^n for n ≥ 0 by the square-and-multiply of `f32::powi`'s runtime routine (libgcc's and
/// compiler-rt's `__powisf2`), inlined: the same products in the same order, so the same bits,
/// without the call.
#[inline]
fn powi(mut x: f32, n: i32) -> f32 {
    debug_assert!(n >= 0);
    let mut n = n as u32;
    let mut y = if n & 1 == 1 { x } else { 1.0 };
    loop {
        n >>= 1;
        if n == 0 {
            return y;
        }
        x *= x;
        if n & 1 == 1 {
            y *= x;
        }
    }
}
