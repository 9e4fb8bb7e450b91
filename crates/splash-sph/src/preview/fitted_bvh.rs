//! The Fitted BVH of Gourmel et al. 2010 (Sec. 4–5), and the plain "modified BVH" of their
//! Sec. 4 (Algorithm 1) to compare against.
//!
//! Every node holds its metaballs (those whose centre lies in it, each in exactly one leaf)
//! and its split metaballs (others whose bounding sphere reaches into its box), so that a leaf
//! computes the field anywhere in its box from its own list. The build is top-down:
//! - binned SAH (Sec. 5.1.1) with the measured cost of splash's leaf test, n + 16·k with
//!   k ≈ 3 ([`leaf_cost`]; the paper's n² and the linear n are ablations), n counting both kinds,
//!   along the longest axis of the centres; above [`TOP_LEVEL`] metaballs that axis is halved
//!   instead (the paper's conclusion); the metaballs are read in Z order, and each node's
//!   centre box comes from its parent's partition;
//! - FBVH children are the two halves of the parent's box at the split plane, each then
//!   intersected with the box of its metaballs' spheres of radius min(R, r_max(n)) (Sec. 5.1.2
//!   and 5.3.1), so siblings never overlap; split metaballs whose sphere misses the fitted box
//!   are dropped;
//! - at a leaf, split metaballs that cannot touch its surface are discarded (Sec. 5.3.2);
//! - a leaf has one metaball, or is cheaper than any split by the SAH's own cost (the same
//!   rule for both hierarchies, whose child boxes it estimates each its own way); subtrees
//!   with more than [`PARALLEL`] metaballs are built in parallel.
//!
//! Why every inside point is found in a leaf with the right sign: a point x with f(x) ≤ 0 lies
//! in one child's split box; every metaball reaching x reaches that box, so it is in that
//! child's list, and x lies within r_max(k) ≤ r_max(n) of one of them (k the number reaching
//! x), hence inside the fitted box. A leaf's list misses only metaballs that are zero in its
//! box or, discarded, zero wherever the field could be ≤ 0: its field has the true sign in its
//! box. Outside its box a leaf sums a subset, so it never calls an outside point inside.

use glam::Vec3;
use rayon::join;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

use super::metaballs::Metaballs;
pub use crate::config::preview::SplitRule;
use crate::error::Result;

/// Which hierarchy to build.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BvhKind {
    /// The Fitted BVH (Sec. 5): disjoint fitted boxes, tight r_max bounds, discarding.
    #[default]
    Fitted,
    /// The modified BVH of Sec. 4: each child's box bounds its metaballs' spheres, siblings
    /// overlap, same SAH.
    Plain,
}

impl BvhKind {
    /// `fitted` or `plain`.
    pub fn parse(text: &str) -> Result<BvhKind> {
        match text.trim().to_ascii_lowercase().as_str() {
            "fitted" | "fbvh" => Ok(BvhKind::Fitted),
            "plain" | "bvh" => Ok(BvhKind::Plain),
            _ => bail_config!("unknown BVH '{text}': expected fitted or plain"),
        }
    }

    /// `fitted` or `plain`.
    pub fn name(self) -> &'static str {
        match self {
            BvhKind::Fitted => "fitted",
            BvhKind::Plain => "plain",
        }
    }
}

/// The Fitted BVH's parts, each switchable to measure what it buys (the paper's Tables 4–5):
/// none changes a hit, only the hierarchy's shape and the work per ray.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BvhOptions {
    /// Cut each child's box down to its metaballs' spheres (Sec. 5.1.2).
    pub fit: bool,
    /// Spheres of radius min(R, r_max(n)) rather than R (Sec. 5.3.1).
    pub tight: bool,
    /// Drop split metaballs that cannot touch a leaf's surface (Sec. 5.3.2).
    pub discard: bool,
    /// The split cost.
    pub split: SplitRule,
}

impl Default for BvhOptions {
    fn default() -> Self {
        BvhOptions {
            fit: true,
            tight: true,
            discard: true,
            split: SplitRule::Measured,
        }
    }
}

/// Axis-aligned box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Aabb {
    pub(crate) const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// Grown by `r` on every side (the box of spheres of radius `r` around centres in it).
    fn grown(&self, r: f32) -> Aabb {
        Aabb {
            min: self.min - r,
            max: self.max + r,
        }
    }

    fn grow_sphere(&mut self, p: Vec3, r: f32) {
        self.min = self.min.min(p - r);
        self.max = self.max.max(p + r);
    }

    fn intersect(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: self.min.max(o.min),
            max: self.max.min(o.max),
        }
    }

    fn area(&self) -> f32 {
        let e = (self.max - self.min).max(Vec3::ZERO);
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// Whether the ball of radius `r` around `p` reaches the box (touching counts).
    pub(crate) fn touches_sphere(&self, p: Vec3, r: f32) -> bool {
        let q = p.clamp(self.min, self.max);
        (q - p).length_squared() <= r * r
    }
}

/// A node: interior nodes have their left child right after them and the right one at
/// `first`; leaves list `items[first .. first + count]`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Node {
    pub bounds: Aabb,
    pub first: u32,
    /// 0 for interior nodes.
    pub count: u32,
}

/// Where a subtree's own metaballs reach: the box of their spheres (radius R) and their range
/// in the reordered centres. The tracer collects with it exactly the metaballs along a piece of
/// ray, whatever the node boxes were fitted to.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Reach {
    pub bounds: Aabb,
    pub own: [u32; 2],
}

/// The built hierarchy over a frame's metaballs.
#[derive(Debug)]
pub struct FittedBvh {
    pub(crate) nodes: Vec<Node>,
    /// Per node, where its subtree's own metaballs reach.
    pub(crate) reach: Vec<Reach>,
    /// Leaf lists: indices into `points`, in particle order within each leaf (the order the
    /// field is summed in, so that every hierarchy sums it alike).
    pub(crate) items: Vec<u32>,
    /// The metaball centres, reordered so that each leaf's own metaballs are contiguous.
    pub(crate) points: Vec<Vec3>,
    /// The particle index of each of `points`.
    pub(crate) original: Vec<u32>,
    /// The box of all metaballs' spheres: the same for every hierarchy over these particles.
    pub(crate) scene: Aabb,
    pub(crate) field: Metaballs,
}

/// Counts of a built hierarchy.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BvhStats {
    /// Nodes, interior and leaves.
    pub nodes: usize,
    /// Leaves.
    pub leaves: usize,
    /// Entries of all leaf lists (metaballs and split metaballs).
    pub entries: usize,
    /// Deepest leaf (the root has depth 0).
    pub depth: usize,
    /// Bytes of the nodes, lists and reordered centres.
    pub bytes: usize,
}

impl BvhStats {
    /// Average metaballs (own and split) per leaf.
    pub fn per_leaf(&self) -> f64 {
        self.entries as f64 / self.leaves.max(1) as f64
    }
}

/// Nodes with more metaballs than this halve their longest axis instead of binning.
pub const TOP_LEVEL: usize = 1 << 16;
/// Subtrees with more metaballs than this are built in parallel.
pub const PARALLEL: usize = 4096;
/// The median rule, having no cost to weigh, splits nodes of more entries than this.
pub const MEDIAN_LEAF: usize = 96;
/// Split metaballs are tested for discarding in leaves of at most this many entries (the
/// test is quadratic; the paper suggests skipping it in crowded leaves).
const DISCARD_MAX: usize = 64;
const BINS: usize = 16;
/// Cost of a traversal step relative to testing one leaf entry against the ray.
const TRAVERSAL_COST: f32 = 4.0;
/// Cost of a metaball within R of the ray in a leaf test, in entry tests: splash's leaf test,
/// timed on the rays of cbd-small f40, costs about 9 cycles an entry and 150 such a metaball.
pub const LEAF_K_COST: f32 = 16.0;
/// Metaballs within R of the ray per leaf test, as measured (see [`leaf_cost`]).
const ALONG_PER_TEST: f32 = 3.0;

struct Ctx<'a> {
    points: &'a [Vec3],
    field: Metaballs,
    kind: BvhKind,
    options: BvhOptions,
    /// Entries of the node lists alive, checked against `budget`.
    entries: AtomicU64,
    budget: u64,
}

/// The hierarchy as built, flattened once at the end (merging flat arrays level by level
/// would copy every list once per level).
enum Tree {
    Leaf {
        bounds: Aabb,
        /// Own metaballs, then split metaballs (original indices).
        items: Vec<u32>,
        own: usize,
    },
    Inner {
        bounds: Aabb,
        children: Box<(Tree, Tree)>,
    },
}

/// Flat arrays of a [`Tree`].
#[derive(Default)]
struct Flat {
    nodes: Vec<Node>,
    items: Vec<u32>,
    /// Own metaballs in leaf order (original indices).
    order: Vec<u32>,
    /// Per node: for leaves, the range of their own metaballs in `order`.
    own: Vec<[u32; 2]>,
}

impl Flat {
    fn push(&mut self, tree: Tree) {
        // Iterative: a degenerate frame may give a deep tree.
        let mut stack = vec![(tree, None::<usize>)];
        while let Some((t, parent)) = stack.pop() {
            let at = self.nodes.len();
            if let Some(p) = parent {
                // This is the right child of `p`.
                self.nodes[p].first = at as u32;
            }
            match t {
                Tree::Leaf { bounds, items, own } => {
                    self.nodes.push(Node {
                        bounds,
                        first: self.items.len() as u32,
                        count: items.len() as u32,
                    });
                    let start = self.order.len() as u32;
                    self.own.push([start, start + own as u32]);
                    self.order.extend_from_slice(&items[..own]);
                    self.items.extend_from_slice(&items);
                }
                Tree::Inner { bounds, children } => {
                    self.nodes.push(Node {
                        bounds,
                        first: 0,
                        count: 0,
                    });
                    self.own.push([0, 0]);
                    let (l, r) = *children;
                    stack.push((r, Some(at)));
                    stack.push((l, None));
                }
            }
        }
    }
}

impl FittedBvh {
    /// Builds the hierarchy of `kind` over `points`; fails with [`Error::Limit`] when its lists
    /// would take more than `max_bytes`.
    ///
    /// [`Error::Limit`]: crate::Error::Limit
    #[cfg(test)]
    pub fn build(
        points: &[Vec3],
        field: Metaballs,
        kind: BvhKind,
        max_bytes: u64,
    ) -> Result<FittedBvh> {
        Self::build_with(points, field, kind, BvhOptions::default(), max_bytes)
    }

    /// [`build`](Self::build) with some of the Fitted BVH's parts switched off.
    pub fn build_with(
        points: &[Vec3],
        field: Metaballs,
        kind: BvhKind,
        options: BvhOptions,
        max_bytes: u64,
    ) -> Result<FittedBvh> {
        if points.len() >= u32::MAX as usize / 2 {
            bail_limit!("{} particles are too many for one preview", points.len());
        }
        // Centres (and their Z-ordered copy), particle indices (and the Z order), and per
        // metaball up to two nodes with their reach.
        let fixed = points.len() as u64 * (2 * 12 + 4 + 2 * 4 + 2 * (32 + 32));
        if fixed > max_bytes {
            bail_limit!(
                "the preview's hierarchy over {} particles needs at least {} MB, more than the \
                 memory limit of {} MB (max_memory)",
                points.len(),
                fixed >> 20,
                max_bytes >> 20
            );
        }
        if points.is_empty() {
            return Ok(FittedBvh {
                nodes: Vec::new(),
                reach: Vec::new(),
                items: Vec::new(),
                points: Vec::new(),
                original: Vec::new(),
                scene: Aabb::EMPTY,
                field,
            });
        }
        let mut centres = Aabb::EMPTY;
        for &p in points {
            centres.grow(p);
        }
        // The build reads the metaballs in Z order (its lists are particle indices again after).
        let z = z_order(points, &centres);
        let sorted: Vec<Vec3> = z.iter().map(|&i| points[i as usize]).collect();
        let ctx = Ctx {
            points: &sorted,
            field,
            kind,
            options,
            entries: AtomicU64::new(0),
            budget: (max_bytes - fixed) / 4,
        };
        let own: Vec<u32> = (0..points.len() as u32).collect();
        let reach = match kind {
            BvhKind::Fitted if options.tight => field.max_radius(points.len()),
            _ => field.cutoff,
        };
        let bounds = centres.grown(reach);
        ctx.charge(own.len())?;
        let mut tree = Flat::default();
        tree.push(build_node(&ctx, own, centres, Vec::new(), bounds)?);
        drop(sorted);
        for i in tree.items.iter_mut().chain(&mut tree.order) {
            *i = z[*i as usize];
        }
        drop(z);
        let Flat {
            nodes,
            mut items,
            order,
            own,
        } = tree;
        // The field is summed in particle order: sort each list by particle index, then
        // renumber the metaballs in leaf order, so that a leaf's list reads nearby memory.
        for n in &nodes {
            if n.count > 0 {
                items[n.first as usize..(n.first + n.count) as usize].sort_unstable();
            }
        }
        let mut new_index = vec![0u32; points.len()];
        for (k, &i) in order.iter().enumerate() {
            new_index[i as usize] = k as u32;
        }
        let reordered: Vec<Vec3> = order.iter().map(|&i| points[i as usize]).collect();
        for i in &mut items {
            *i = new_index[*i as usize];
        }
        let reach = reaches(&nodes, &own, &reordered, field.cutoff);
        let scene = reach[0].bounds;
        Ok(FittedBvh {
            nodes,
            reach,
            items,
            points: reordered,
            original: order,
            scene,
            field,
        })
    }

    /// Node, leaf and list counts.
    pub fn stats(&self) -> BvhStats {
        let mut s = BvhStats {
            nodes: self.nodes.len(),
            entries: self.items.len(),
            bytes: self.nodes.len() * (size_of::<Node>() + size_of::<Reach>())
                + self.items.len() * 4
                + self.points.len() * 16,
            ..BvhStats::default()
        };
        let mut stack = vec![(0usize, 0usize)];
        while let Some((n, depth)) = stack.pop() {
            let Some(node) = self.nodes.get(n) else {
                break;
            };
            if node.count > 0 {
                s.leaves += 1;
                s.depth = s.depth.max(depth);
            } else {
                stack.push((n + 1, depth + 1));
                stack.push((node.first as usize, depth + 1));
            }
        }
        s
    }

    /// Every leaf as (box, centres of its list).
    #[cfg(test)]
    pub fn leaves(&self) -> impl Iterator<Item = (Aabb, Vec<Vec3>)> + '_ {
        self.nodes.iter().filter(|n| n.count > 0).map(|n| {
            let list = &self.items[n.first as usize..(n.first + n.count) as usize];
            (
                n.bounds,
                list.iter().map(|&i| self.points[i as usize]).collect(),
            )
        })
    }

    /// The field.
    pub fn field(&self) -> Metaballs {
        self.field
    }
}

/// Each node's [`Reach`], children before parents (they follow them in `nodes`). Leaves own
/// the ranges `own` of `points`; a subtree's leaves are consecutive, so are their ranges.
fn reaches(nodes: &[Node], own: &[[u32; 2]], points: &[Vec3], r: f32) -> Vec<Reach> {
    let mut reach = vec![
        Reach {
            bounds: Aabb::EMPTY,
            own: [0, 0],
        };
        nodes.len()
    ];
    for n in (0..nodes.len()).rev() {
        reach[n] = if nodes[n].count > 0 {
            let [a, b] = own[n];
            let mut bounds = Aabb::EMPTY;
            for &p in &points[a as usize..b as usize] {
                bounds.grow_sphere(p, r);
            }
            Reach {
                bounds,
                own: [a, b],
            }
        } else {
            let (l, rt) = (reach[n + 1], reach[nodes[n].first as usize]);
            Reach {
                bounds: Aabb {
                    min: l.bounds.min.min(rt.bounds.min),
                    max: l.bounds.max.max(rt.bounds.max),
                },
                own: [l.own[0], rt.own[1]],
            }
        };
    }
    reach
}

impl Ctx<'_> {
    fn charge(&self, n: usize) -> Result<()> {
        let total = self.entries.fetch_add(n as u64, Ordering::Relaxed) + n as u64;
        if total > self.budget {
            bail_limit!(
                "the preview's hierarchy would hold more than {} metaball entries ({} MB), above \
                 the memory limit (max_memory); is the spacing right?",
                self.budget,
                (self.budget * 4) >> 20
            );
        }
        Ok(())
    }

    fn release(&self, n: usize) {
        self.entries.fetch_sub(n as u64, Ordering::Relaxed);
    }

    fn p(&self, i: u32) -> Vec3 {
        self.points[i as usize]
    }
}

/// A split: axis and plane; own metaballs with centre < plane go left.
#[derive(Clone, Copy)]
struct Split {
    axis: usize,
    plane: f32,
    /// Own metaballs of centre bin < `bin` go left (bins of `origin` + k / `scale`), so that
    /// both sides have some whatever the rounding of `plane`.
    bin: usize,
    origin: f32,
    scale: f32,
}

impl Split {
    fn goes_left(&self, x: f32) -> bool {
        let b = (((x - self.origin) * self.scale) as isize).clamp(0, BINS as isize - 1);
        (b as usize) < self.bin
    }
}

fn build_node(
    ctx: &Ctx,
    own: Vec<u32>,
    centres: Aabb,
    split: Vec<u32>,
    bounds: Aabb,
) -> Result<Tree> {
    let n = own.len() + split.len();
    let choice = if own.len() <= 1 {
        None
    } else {
        choose_split(ctx, &own, &centres, &split, &bounds)
    };
    let Some(s) = choice else {
        return Ok(leaf(ctx, own, split, &bounds));
    };
    let (axis, r) = (s.axis, ctx.field.cutoff);
    let left = own.iter().filter(|&&i| s.goes_left(ctx.p(i)[axis])).count();
    if left == 0 || left == own.len() {
        return Ok(leaf(ctx, own, split, &bounds));
    }
    let fitted = ctx.kind == BvhKind::Fitted;
    // Fitted halves meet at the plane: only the sibling's metaballs within R of it can reach
    // the other half (with slack against rounding; `gather` decides).
    let (near_lo, near_hi) = (s.plane - 1.01 * r, s.plane + 1.01 * r);
    let (mut own_l, mut own_r) = (
        Vec::with_capacity(left),
        Vec::with_capacity(own.len() - left),
    );
    let (mut near_l, mut near_r) = (Vec::new(), Vec::new());
    let (mut cl, mut cr) = (Aabb::EMPTY, Aabb::EMPTY);
    for &i in &own {
        let p = ctx.p(i);
        if s.goes_left(p[axis]) {
            own_l.push(i);
            cl.grow(p);
            if fitted && p[axis] >= near_lo {
                near_l.push(i);
            }
        } else {
            own_r.push(i);
            cr.grow(p);
            if fitted && p[axis] <= near_hi {
                near_r.push(i);
            }
        }
    }
    let ((lbox, lsplit), (rbox, rsplit)) = if fitted {
        let mut lbox = bounds;
        lbox.max[axis] = s.plane;
        let mut rbox = bounds;
        rbox.min[axis] = s.plane;
        (
            (lbox, gather(ctx, &lbox, &split, &near_r)),
            (rbox, gather(ctx, &rbox, &split, &near_l)),
        )
    } else {
        let (lbox, rbox) = (cl.grown(r), cr.grown(r));
        (
            (lbox, gather(ctx, &lbox, &split, &own_r)),
            (rbox, gather(ctx, &rbox, &split, &own_l)),
        )
    };
    drop((near_l, near_r));
    let (lbox, lsplit) = fit(ctx, lbox, &cl, own_l.len(), lsplit);
    let (rbox, rsplit) = fit(ctx, rbox, &cr, own_r.len(), rsplit);
    ctx.charge(own_l.len() + lsplit.len() + own_r.len() + rsplit.len())?;
    ctx.release(n);
    drop(own);
    drop(split);
    let (l, r) = if n > PARALLEL {
        join(
            || build_node(ctx, own_l, cl, lsplit, lbox),
            || build_node(ctx, own_r, cr, rsplit, rbox),
        )
    } else {
        (
            build_node(ctx, own_l, cl, lsplit, lbox),
            build_node(ctx, own_r, cr, rsplit, rbox),
        )
    };
    Ok(Tree::Inner {
        bounds,
        children: Box::new((l?, r?)),
    })
}

/// The split metaballs of a child with box `b`: those of `split` and of the sibling's own
/// whose bounding sphere reaches `b`, in the order given.
fn gather(ctx: &Ctx, b: &Aabb, split: &[u32], sibling: &[u32]) -> Vec<u32> {
    let r = ctx.field.cutoff;
    split
        .iter()
        .chain(sibling)
        .copied()
        .filter(|&i| b.touches_sphere(ctx.p(i), r))
        .collect()
}

/// FBVH: the child's box cut down to the spheres of radius min(R, r_max(n)) of its n
/// metaballs (Sec. 5.1.2, 5.3.1), then the split metaballs that miss it dropped. `centres`
/// bounds the child's own metaballs.
fn fit(ctx: &Ctx, b: Aabb, centres: &Aabb, own: usize, split: Vec<u32>) -> (Aabb, Vec<u32>) {
    if ctx.kind == BvhKind::Plain || !ctx.options.fit {
        return (b, split);
    }
    let reach = if ctx.options.tight {
        ctx.field
            .max_radius(own + split.len())
            .min(ctx.field.cutoff)
    } else {
        ctx.field.cutoff
    };
    let mut spheres = centres.grown(reach);
    for &i in &split {
        spheres.grow_sphere(ctx.p(i), reach);
    }
    let fitted = b.intersect(&spheres);
    let r = ctx.field.cutoff;
    let split = split
        .into_iter()
        .filter(|&i| fitted.touches_sphere(ctx.p(i), r))
        .collect();
    (fitted, split)
}

/// Binned SAH (Sec. 5.1.1); None when a leaf is cheaper than the best split.
fn choose_split(
    ctx: &Ctx,
    own: &[u32],
    centres: &Aabb,
    split: &[u32],
    bounds: &Aabb,
) -> Option<Split> {
    let (cmin, cmax) = (centres.min, centres.max);
    let extent = cmax - cmin;
    let n = own.len() + split.len();
    let median = ctx.options.split == SplitRule::Median;
    if median && n <= MEDIAN_LEAF {
        return None;
    }
    if own.len() > TOP_LEVEL || median {
        let axis = extent.max_position();
        if extent[axis] <= 0.0 {
            return None;
        }
        return Some(Split {
            axis,
            plane: cmin[axis] + 0.5 * extent[axis],
            bin: BINS / 2,
            origin: cmin[axis],
            scale: BINS as f32 / extent[axis],
        });
    }
    let r = ctx.field.cutoff;
    // A plain child's box is its centres' box grown by R: it reaches R past the plane, and
    // so does its list (an upper bound: its centres lie on their side of the plane).
    let overlap = if ctx.kind == BvhKind::Plain { r } else { 0.0 };
    let area = bounds.area().max(f32::MIN_POSITIVE);
    let mut best: Option<(f32, Split)> = None;
    // The longest axis only: metaballs fill space evenly, so the other two seldom win, and
    // binning is most of the build (on cbd-large f23 three axes took half as much CPU again
    // for the whole run, for 3 % fewer metaballs per ray).
    for axis in [extent.max_position()] {
        if extent[axis].is_nan() || extent[axis] <= 0.0 {
            continue;
        }
        let scale = BINS as f32 / extent[axis];
        let bin = |x: f32| (((x - cmin[axis]) * scale) as isize).clamp(0, BINS as isize - 1);
        // Planes j = 1..BINS at cmin + j·extent/BINS. Own centres of bin < j go left; a
        // sphere is in the left list when its low end lies below the plane, in the right one
        // when its high end lies above it.
        let mut centres = [0usize; BINS];
        let mut lows = [0usize; BINS + 1];
        let mut highs = [0usize; BINS + 1];
        for &i in own {
            centres[bin(ctx.p(i)[axis]) as usize] += 1;
        }
        for &i in own.iter().chain(split) {
            let x = ctx.p(i)[axis];
            // Low end below plane j ⇔ j > (x − R − cmin)·scale: j ≥ ⌊·⌋ + 1.
            lows[floor_plus_one((x - r - overlap - cmin[axis]) * scale)] += 1;
            // High end above plane j ⇔ j < (x + R − cmin)·scale: j ≤ ⌈·⌉ − 1.
            highs[ceil_minus_one((x + r + overlap - cmin[axis]) * scale)] += 1;
        }
        let mut own_left = 0;
        let mut left = lows[0];
        let mut right_suffix = [0usize; BINS + 2];
        for j in (0..=BINS).rev() {
            right_suffix[j] = right_suffix[j + 1] + highs[j];
        }
        for j in 1..BINS {
            own_left += centres[j - 1];
            left += lows[j];
            let right = right_suffix[j];
            if own_left == 0 || own_left == own.len() {
                continue;
            }
            let plane = cmin[axis] + j as f32 / scale;
            let mut lb = *bounds;
            lb.max[axis] = lb.max[axis].min(plane + overlap);
            let mut rb = *bounds;
            rb.min[axis] = rb.min[axis].max(plane - overlap);
            let cost = TRAVERSAL_COST
                + (lb.area() * leaf_cost(ctx, left) + rb.area() * leaf_cost(ctx, right)) / area;
            if best.is_none_or(|(c, _)| cost < c) {
                let split = Split {
                    axis,
                    plane,
                    bin: j,
                    origin: cmin[axis],
                    scale,
                };
                best = Some((cost, split));
            }
        }
    }
    let (cost, s) = best?;
    (cost < leaf_cost(ctx, n)).then_some(s)
}

/// The cost of testing a ray against a leaf of `n` entries, in entry tests. splash's leaf
/// test (`Tracer::leaf_inside`) tests each entry's distance from the ray, then samples the
/// field of the k metaballs within R of it until a sample is inside. Timed on the rays of
/// cbd-small f40 (1.1 M leaf tests of five hierarchies, n from 1 to 3500) it costs about 9
/// cycles an entry and 150 a metaball along the ray, no k² part showing; k stayed 2.6–3.6 per
/// test on FBVHs whose leaves hold 18 to 134 entries (R is a few particle spacings whatever
/// the leaf), hence n + 16·3.
fn leaf_cost(ctx: &Ctx, n: usize) -> f32 {
    let n = n as f32;
    match ctx.options.split {
        SplitRule::Measured => n + LEAF_K_COST * ALONG_PER_TEST,
        SplitRule::N2 => n * n,
        SplitRule::Sah | SplitRule::Median => n,
    }
}

/// The particles' indices in Morton (Z-curve) order of their position in `centres` (10 bits
/// an axis), ties by index: nearby metaballs, nearby in memory while building.
fn z_order(points: &[Vec3], centres: &Aabb) -> Vec<u32> {
    let scale = 1023.0
        / (centres.max - centres.min)
            .max_element()
            .max(f32::MIN_POSITIVE);
    let mut keyed: Vec<(u32, u32)> = points
        .par_iter()
        .enumerate()
        .map(|(i, &p)| {
            let q = ((p - centres.min) * scale)
                .min(Vec3::splat(1023.0))
                .as_uvec3();
            (spread(q.x) | spread(q.y) << 1 | spread(q.z) << 2, i as u32)
        })
        .collect();
    keyed.par_sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

/// The 10 low bits of `x` spread to every third bit.
fn spread(x: u32) -> u32 {
    let mut x = x & 0x3ff;
    x = (x | x << 16) & 0x0300_00ff;
    x = (x | x << 8) & 0x0300_f00f;
    x = (x | x << 4) & 0x030c_30c3;
    (x | x << 2) & 0x0924_9249
}

/// ⌊v⌋ + 1 clamped to 0..=BINS, in integers (f32 floor is a libm call on baseline x86-64).
fn floor_plus_one(v: f32) -> usize {
    if v < 0.0 {
        0
    } else {
        (v.min(BINS as f32) as usize + 1).min(BINS)
    }
}

/// ⌈v⌉ − 1 clamped to 0..=BINS, in integers.
fn ceil_minus_one(v: f32) -> usize {
    if v <= 0.0 {
        return 0;
    }
    let v = v.min(BINS as f32 + 1.0);
    let floor = v as usize;
    let ceil = if (floor as f32) < v { floor + 1 } else { floor };
    (ceil - 1).min(BINS)
}

fn leaf(ctx: &Ctx, own: Vec<u32>, mut split: Vec<u32>, bounds: &Aabb) -> Tree {
    let n = own.len() + split.len();
    if ctx.kind == BvhKind::Fitted && ctx.options.discard && n <= DISCARD_MAX && !split.is_empty() {
        // Sec. 5.3.2: a split metaball whose r_max ball misses the box and whose sphere stays
        // r_max away from every other centre of the list is zero wherever the field can be ≤ 0.
        let r = ctx.field.cutoff;
        let rmax = ctx.field.max_radius(n).min(r);
        let all: Vec<Vec3> = own.iter().chain(&split).map(|&i| ctx.p(i)).collect();
        let far = (r + rmax) * (r + rmax);
        split.retain(|&i| {
            let p = ctx.p(i);
            bounds.touches_sphere(p, rmax)
                || all
                    .iter()
                    .any(|&q| q != p && (q - p).length_squared() < far)
        });
    }
    let own_count = own.len();
    let mut items = own;
    items.extend_from_slice(&split);
    // The lists stay: only the discarded entries are given back.
    ctx.release(n - items.len());
    Tree::Leaf {
        bounds: *bounds,
        items,
        own: own_count,
    }
}
