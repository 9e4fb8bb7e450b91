//! Edge-collapse decimation by quadric error metrics (Garland & Heckbert 1997), with every new
//! vertex kept within a given exact distance of the undecimated surface.
//!
//! Each vertex carries the area-weighted quadric of the planes of its original faces; an edge
//! collapses to the point minimising the merged quadric. The collapses run in passes: every
//! edge is priced cheaply (the merged quadric's own minimum, which changes only when a collapse
//! moves an end), the cheapest are taken greedily as long as their stars share no triangle,
//! and those taken are checked in parallel against the mesh as the round found them; further
//! rounds of the same pass take the next cheapest around the refused collapses and the made
//! ones (but for the edges at a moved vertex, which wait for the next pass's prices). A refused
//! collapse stays refused until a collapse changes the star of an end. The result does not
//! depend on the thread count. A collapse is refused when
//! - the root-mean-square distance of the new point to the merged planes exceeds `max_error`;
//! - the new point, or the centroid of a triangle it makes, lies farther than `max_error` from
//!   the original triangles (exact point-to-triangle distance): the guarantee. The witness, an
//!   original triangle that close, is sought by walking the original mesh from the witnesses
//!   of the ends and of the moved triangles, towards ever closer triangles; a walk that stops
//!   short refuses, so a collapse may be refused that a farther triangle would allow, never
//!   the reverse. Checking the centroids too keeps the faces, not only their corners, on the
//!   surface: on cbd-small frame 40 at 0.1 r, vertices alone let centroids stray 0.23 r, for
//!   2 % fewer triangles;
//! - it breaks the link condition (the edge's ends share exactly the two opposite vertices),
//!   which keeps a closed manifold closed and manifold, the Euler characteristic and the
//!   components as they were (a collapse never joins two components);
//! - a surviving triangle around it turns by more than about 78° or degenerates, or gets a
//!   smaller quality than both `MIN_QUALITY` and the worst triangle it replaces.
//!
//! Vertices whose star is not a single closed fan (boundaries, non-manifold spots, degenerate
//! triangles) are never moved, so other meshes pass through with those parts untouched.

mod quadric;
mod witness;

use crate::error::{Error, Result};
use crate::mesh::TriMesh;
use crate::mesh::stars::{DEAD, Stars, area_weighted_normals, compact, validate};
use glam::{DVec3, Vec3};
use rayon::prelude::*;

use quadric::{Kept, Quadric, REGULARISATION};
use witness::Surface;

/// Most triangles a vertex may have around it to take part in a collapse, and the most a
/// collapse may leave around its new vertex: bounds the stack arrays of the checks and keeps
/// fans from growing into needles.
const MAX_STAR: usize = 16;

/// Collapses selected and checked in parallel before they are made: a share of a round, so that
/// the collapses waiting to be made stay few (all of a pass's at once held 32 MB on cbd-large
/// f23).
const CHECKED_AT_ONCE: usize = 1 << 14;

/// How many keys ahead the selection fetches a key's triangle.
const PREFETCH: usize = 16;

/// Asks the processor to bring `t` into the cache: a hint, with no effect on what runs.
#[inline(always)]
fn prefetch<T>(t: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch reads nothing and faults on no address; SSE is in x86-64's baseline.
    unsafe {
        std::arch::x86_64::_mm_prefetch(
            (t as *const T).cast::<i8>(),
            std::arch::x86_64::_MM_HINT_T0,
        );
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = t;
}

/// Triangle quality `4 √3 area / Σ edge²` (1 for an equilateral triangle) under which a
/// collapse may not bring a triangle unless one as bad was there already: 0.3 is about a 10°
/// smallest angle.
const MIN_QUALITY: f64 = 0.3;

/// Cosine of the largest turn of a triangle's normal that a collapse may cause (about 78°):
/// refuses flips and near-flips, allows the folding of real curvature.
const MIN_NORMAL_COSINE: f64 = 0.2;

/// Decimates `mesh` by quadric-error edge collapses until no collapse is left that keeps every
/// vertex within `max_error` of the original surface (see the module documentation for the
/// checks). The result is as closed and manifold as the input, with the same components and
/// Euler characteristic per component; every vertex, and the centroid of every triangle, lies
/// within `max_error` of a triangle of `mesh` by exact point-to-triangle distance, and the
/// enclosed volume of each collapse's neighbourhood is kept. Normals, when `mesh`
/// has them, are the area-weighted normals of the new faces. The same mesh comes out whatever
/// the number of threads.
///
/// Errors: a `max_error` that is not a positive finite length, or a mesh that references
/// missing vertices, has non-finite vertices, or as many normals as neither 0 nor the vertices.
pub fn decimate(mesh: &TriMesh, max_error: f32) -> Result<TriMesh> {
    if !(max_error.is_finite() && max_error > 0.0) {
        return Err(Error::Config(format!(
            "decimation error must be a positive length, not {max_error}"
        )));
    }
    validate(mesh)?;
    if mesh.triangles.is_empty() {
        return Ok(mesh.clone());
    }
    let mut work = Decimation::new(mesh, f64::from(max_error));
    work.run();
    let live: Vec<[u32; 3]> = work
        .triangles
        .iter()
        .copied()
        .filter(|t| t[0] != DEAD)
        .collect();
    let mut out = compact(&work.positions, &[], &live);
    if !mesh.normals.is_empty() {
        out.normals = area_weighted_normals(&out.vertices, &out.triangles);
    }
    Ok(out)
}

/// `4 √3 area / Σ edge²`, from the doubled-area vector `n`.
fn quality(p: [DVec3; 3], n: DVec3) -> f64 {
    let squares = (p[1] - p[0]).length_squared()
        + (p[2] - p[1]).length_squared()
        + (p[0] - p[2]).length_squared();
    if squares == 0.0 {
        return 0.0;
    }
    2.0 * 3f64.sqrt() * n.length() / squares
}

fn corners(t: [u32; 3], positions: &[Vec3]) -> [DVec3; 3] {
    t.map(|v| positions[v as usize].as_dvec3())
}

fn doubled_area(p: [DVec3; 3]) -> DVec3 {
    (p[1] - p[0]).cross(p[2] - p[0])
}

/// The corner after `v` in `t`, counter-clockwise.
fn next_after(t: [u32; 3], v: u32) -> u32 {
    if t[0] == v {
        t[1]
    } else if t[1] == v {
        t[2]
    } else {
        t[0]
    }
}

/// Whether the triangles around `v` form one closed fan: their edges opposite `v` chain into a
/// single cycle through every neighbour once.
fn is_closed_fan(v: u32, star: &[u32], triangles: &[[u32; 3]]) -> bool {
    if star.len() < 3 || star.len() > MAX_STAR {
        return false;
    }
    let mut links = [(0u32, 0u32); MAX_STAR];
    for (link, &t) in links.iter_mut().zip(star) {
        let t = triangles[t as usize];
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            return false;
        }
        let next = next_after(t, v);
        *link = (next, next_after(t, next));
    }
    let links = &links[..star.len()];
    // Each neighbour starts exactly one link (so it ends exactly one), and walking the links
    // from the first comes back after visiting all of them.
    for (i, l) in links.iter().enumerate() {
        if links[..i].iter().any(|m| m.0 == l.0) {
            return false;
        }
    }
    let mut at = links[0].1;
    for _ in 1..links.len() {
        match links.iter().find(|l| l.0 == at) {
            Some(l) if at != links[0].0 => at = l.1,
            _ => return false,
        }
    }
    at == links[0].0
}

/// A collapse that passed every check: `b` goes into `a`, which moves to `point` with the
/// merged quadric; `opposite` are the corners of the edge's two triangles off the edge (whose
/// stars each lose one), `witness` is an original triangle within the error of `point`, and
/// `centres[..count]` the triangles the collapse moves, each with one within the error of its
/// new centroid.
struct Collapse {
    a: u32,
    b: u32,
    opposite: [u32; 2],
    quadric: Quadric,
    point: Vec3,
    witness: u32,
    centres: [(u32, u32); MAX_STAR],
    count: usize,
}

struct Decimation<'a> {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    /// Per vertex, its quadric kept at its position.
    quadrics: Vec<Kept>,
    /// Whether a vertex may move: its star was a closed fan in the input.
    movable: Vec<bool>,
    /// Per vertex, an original triangle within `max_error` of it: where the searches of the
    /// distance check start.
    witness: Vec<u32>,
    /// Per working triangle, an original triangle within `max_error` of its centroid.
    centre_witness: Vec<u32>,
    /// Quadrics live around this point, so that their `f64` sums keep the digits of the
    /// small distances they measure.
    origin: DVec3,
    max_error: f64,
    surface: Surface<'a>,
    stars: Stars,
}

impl<'a> Decimation<'a> {
    fn new(mesh: &'a TriMesh, max_error: f64) -> Self {
        let (lo, hi) = mesh
            .vertices
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        let origin = ((lo + hi) * 0.5).as_dvec3();
        let mut original = Stars::default();
        original.rebuild(mesh.vertices.len(), &mesh.triangles);
        let local = |v: u32| mesh.vertices[v as usize].as_dvec3() - origin;
        let (quadrics, movable): (Vec<Kept>, Vec<bool>) = (0..mesh.vertices.len() as u32)
            .into_par_iter()
            .map(|v| {
                let mut q = Quadric::default();
                for &t in original.of(v) {
                    let p = mesh.triangles[t as usize].map(local);
                    let n = doubled_area(p);
                    let area2 = n.length();
                    if area2 > 0.0 {
                        let n = n / area2;
                        q = q.add(&Quadric::plane(n, -n.dot(p[0]), 0.5 * area2));
                    }
                }
                (
                    q.kept_at(local(v)),
                    is_closed_fan(v, original.of(v), &mesh.triangles),
                )
            })
            .unzip();
        // A vertex lies on the triangles around it (one without any never moves).
        let witness = (0..mesh.vertices.len() as u32)
            .map(|v| original.of(v).first().copied().unwrap_or(DEAD))
            .collect();
        Decimation {
            positions: mesh.vertices.clone(),
            triangles: mesh.triangles.clone(),
            quadrics,
            movable,
            witness,
            centre_witness: (0..mesh.triangles.len() as u32).collect(),
            origin,
            max_error,
            surface: Surface::new(mesh, original, max_error),
            stars: Stars::default(),
        }
    }

    /// Vertex `v`'s position around the origin.
    fn local(&self, v: u32) -> DVec3 {
        self.positions[v as usize].as_dvec3() - self.origin
    }

    /// The sum of the quadrics of `a` and `b`.
    fn merged(&self, a: u32, b: u32) -> Quadric {
        let kept = |v: u32| self.quadrics[v as usize].at(self.local(v));
        kept(a).add(&kept(b))
    }

    /// The order in which the edge `a b` is tried: the mean squared distance to the merged
    /// planes of the quadric's own minimiser (pulled towards the midpoint). It reads only the
    /// quadrics and positions of `a` and `b`, so it holds until a collapse moves one of them;
    /// infinite for an edge that cannot collapse (an end that may not move, or already too
    /// far from the planes without the volume constraint's further pull).
    fn price(&self, a: u32, b: u32) -> f32 {
        if !(self.movable[a as usize] && self.movable[b as usize]) {
            return f32::INFINITY;
        }
        let q = self.merged(a, b);
        if q.w <= 0.0 {
            return 0.0;
        }
        let mid = (self.local(a) + self.local(b)) * 0.5;
        let x = q.minimiser(mid, DVec3::ZERO, 0.0).unwrap_or(mid);
        let cost = (q.eval(x) / q.w).max(0.0);
        if cost > self.max_error * self.max_error {
            f32::INFINITY
        } else {
            // With the pull to the midpoint, the regularised quadric's minimum: among collapses
            // the planes leave free (flat and creased regions) the shorter goes first. Positive
            // zero too: the sign bit marks refusals.
            ((cost + REGULARISATION * (x - mid).length_squared()) as f32).abs()
        }
    }

    /// The merged quadric of the edge `a b` and the point it collapses to, rounded to `f32`:
    /// the minimiser of the quadric on the plane of points that keep the volume enclosed by
    /// the stars of `a` and `b` (the volume preservation of Lindstrom & Turk 1998), solved a
    /// second time around the first solution so that the pull to the midpoint only decides
    /// the directions the planes leave free.
    fn target(&self, a: u32, b: u32) -> (Quadric, Vec3) {
        let q = self.merged(a, b);
        let local = |v: u32| self.local(v);
        let mid = (local(a) + local(b)) * 0.5;
        // Volume with the origin of the triangles around the edge, before (h) and, as a
        // linear function g·x of the new point x, after.
        let (mut g, mut h) = (DVec3::ZERO, 0.0);
        for (&t, moved) in self
            .stars
            .of(a)
            .iter()
            .map(|t| (t, a))
            .chain(self.stars.of(b).iter().map(|t| (t, b)))
        {
            let tri = self.triangles[t as usize];
            let both = tri.contains(&a) && tri.contains(&b);
            if both && moved == b {
                continue;
            }
            let p = tri.map(local);
            h += p[0].dot(p[1].cross(p[2])) / 6.0;
            if !both {
                let v1 = next_after(tri, moved);
                let v2 = next_after(tri, v1);
                g += local(v1).cross(local(v2)) / 6.0;
            }
        }
        let x = q
            .minimiser(mid, g, h)
            .and_then(|x0| q.minimiser(x0, g, h))
            .unwrap_or(mid);
        (q, (x + self.origin).as_vec3())
    }

    /// The collapse of the edge `a b` (both ends movable), or `None` when one of the module's
    /// checks refuses it; the distance check, the dearest, last.
    fn check(&self, a: u32, b: u32) -> Option<Collapse> {
        let (sa, sb) = (self.stars.of(a), self.stars.of(b));
        let new_degree = (sa.len() + sb.len()).checked_sub(4)?;
        if !(3..=MAX_STAR).contains(&new_degree) || sa.len() > MAX_STAR || sb.len() > MAX_STAR {
            return None;
        }
        // Link condition: on closed fans, the ring of `a` is the corner after `a` in each of its
        // triangles, each neighbour once.
        let ring = |v: u32, star: &[u32]| {
            let mut out = [0u32; MAX_STAR];
            for (o, &t) in out.iter_mut().zip(star) {
                *o = next_after(self.triangles[t as usize], v);
            }
            out
        };
        let (ra, rb) = (ring(a, sa), ring(b, sb));
        let (ra, rb) = (&ra[..sa.len()], &rb[..sb.len()]);
        // The two shared neighbours are the corners opposite the edge.
        let mut shared = ra.iter().copied().filter(|&x| x != b && rb.contains(&x));
        let opposite = [shared.next()?, shared.next()?];
        if shared.next().is_some() {
            return None;
        }
        let (q, p) = self.target(a, b);
        let cost = if q.w > 0.0 {
            (q.eval(p.as_dvec3() - self.origin) / q.w).max(0.0)
        } else {
            0.0
        };
        if cost > self.max_error * self.max_error {
            return None;
        }
        let new = p.as_dvec3();
        let mut worst_before = f64::INFINITY;
        let mut worst_after = f64::INFINITY;
        for (_, tri, moved) in self.surviving(a, b) {
            let before = corners(tri, &self.positions);
            let n0 = doubled_area(before);
            let mut after = before;
            after[tri.iter().position(|&v| v == moved).unwrap()] = new;
            let n1 = doubled_area(after);
            if n1.dot(n0) <= MIN_NORMAL_COSINE * n0.length() * n1.length() {
                return None;
            }
            worst_before = worst_before.min(quality(before, n0));
            worst_after = worst_after.min(quality(after, n1));
        }
        if worst_after < worst_before.min(MIN_QUALITY) {
            return None;
        }
        // The guarantee: the new point and the centroids of the triangles it makes lie within
        // `max_error` of the original surface.
        let witness = self
            .surface
            .witness(new, [self.witness[a as usize], self.witness[b as usize]])?;
        let mut centres = [(0, 0); MAX_STAR];
        let mut count = 0;
        for (t, tri, moved) in self.surviving(a, b) {
            let mut after = corners(tri, &self.positions);
            after[tri.iter().position(|&v| v == moved).unwrap()] = new;
            // The centroid moves by a third of the corner's step: its last witness is close.
            let found = self.surface.witness(
                (after[0] + after[1] + after[2]) / 3.0,
                [self.centre_witness[t as usize], witness],
            )?;
            centres[count] = (t, found);
            count += 1;
        }
        Some(Collapse {
            a,
            b,
            opposite,
            quadric: q,
            point: p,
            witness,
            centres,
            count,
        })
    }

    /// The triangles around the edge `a b` that survive its collapse (index and corners), with
    /// the end they hold.
    fn surviving(&self, a: u32, b: u32) -> impl Iterator<Item = (u32, [u32; 3], u32)> + '_ {
        let (sa, sb) = (self.stars.of(a), self.stars.of(b));
        sa.iter()
            .map(move |&t| (t, a))
            .chain(sb.iter().map(move |&t| (t, b)))
            .map(|(t, moved)| (t, self.triangles[t as usize], moved))
            .filter(move |(_, tri, _)| !(tri.contains(&a) && tri.contains(&b)))
    }

    /// `visit(v)` for each vertex of the triangles around `a` and `b` (some more than once):
    /// what a collapse of the edge reads and changes.
    fn region(&self, a: u32, b: u32, mut visit: impl FnMut(usize)) {
        for &s in self.stars.of(a).iter().chain(self.stars.of(b)) {
            for v in self.triangles[s as usize] {
                visit(v as usize);
            }
        }
    }

    /// Marks with `stamp` every vertex of [`Self::region`] that does not carry `held` already.
    fn lock(&self, a: u32, b: u32, locked: &mut [u32], stamp: u32, held: u32) {
        self.region(a, b, |v| {
            if locked[v] != held {
                locked[v] = stamp;
            }
        });
    }

    /// The next share of a round's selection: from `keys[at.next..]` in order, the edges
    /// with neither end locked, their regions locked with the round's stamp, until
    /// [`CHECKED_AT_ONCE`] are taken or the keys end. Keys with an end locked by this round
    /// are kept for the next (moved down to `keys[..at.kept]`); those of dead edges or with an
    /// end held are dropped for the pass.
    fn select(
        &self,
        keys: &mut [u64],
        at: &mut Selection,
        locked: &mut [u32],
    ) -> Vec<(usize, u32, u32)> {
        let mut taken = Vec::new();
        while at.next < keys.len() && taken.len() < CHECKED_AT_ONCE {
            let i = at.next;
            at.next += 1;
            // The keys go by cost, so their triangles lie all over the mesh: each is fetched a
            // few keys ahead (cbd-large f23 at 0.1r, 19 M keys read in 881 rounds: the
            // selection 477 → 355 ms).
            if let Some(&ahead) = keys.get(i + PREFETCH) {
                prefetch(&self.triangles[ahead as u32 as usize / 3]);
            }
            let key = keys[i];
            let slot = key as u32 as usize;
            let t = self.triangles[slot / 3];
            if t[0] == DEAD {
                // The edge of a collapse made this pass.
                continue;
            }
            let (a, b) = (t[slot % 3], t[(slot + 1) % 3]);
            let (la, lb) = (locked[a as usize], locked[b as usize]);
            if la == at.held || lb == at.held {
                continue;
            }
            if la == at.stamp || lb == at.stamp {
                keys[at.kept] = key;
                at.kept += 1;
                continue;
            }
            self.lock(a, b, locked, at.stamp, at.held);
            taken.push((slot, a, b));
        }
        taken
    }

    fn run(&mut self) {
        let n = self.positions.len();
        // Per corner slot (triangle × 3 + corner: the edge from that corner to the next), the
        // edge's price, negated (sign bit set) while its checks refuse it. The price holds
        // until a collapse moves an end; the checks read only the stars of the ends, so a
        // refusal holds until a collapse changes one of them.
        let mut costs = vec![f32::INFINITY; 3 * self.triangles.len()];
        let mut keys: Vec<u64> = Vec::new();
        // The pass that last moved each vertex (the survivor of a collapse), and that last
        // changed its star (a vertex of the triangles around a collapse).
        let mut moved = vec![0u32; n];
        let mut changed = vec![0u32; n];
        // Vertices of the stars of the collapses chosen in a selection round carry its stamp.
        let mut locked = vec![0u32; n];
        let mut stamp = 0u32;
        let mut pass = 0u32;
        loop {
            pass += 1;
            // The dead triangles out, in order, so that the passes scan only the live mesh;
            // the order, and with it every tie and sum, stays as it was.
            let mut live = 0;
            for i in 0..self.triangles.len() {
                if self.triangles[i][0] != DEAD {
                    self.triangles[live] = self.triangles[i];
                    self.centre_witness[live] = self.centre_witness[i];
                    costs.copy_within(3 * i..3 * i + 3, 3 * live);
                    live += 1;
                }
            }
            self.triangles.truncate(live);
            self.centre_witness.truncate(live);
            costs.truncate(3 * live);
            self.stars.rebuild(n, &self.triangles);
            let this = &*self;
            const CHUNK: usize = 1 << 12;
            costs
                .par_chunks_mut(CHUNK)
                .enumerate()
                .for_each(|(c, costs)| {
                    for (j, cost) in costs.iter_mut().enumerate() {
                        let slot = c * CHUNK + j;
                        let t = this.triangles[slot / 3];
                        let (a, b) = (t[slot % 3], t[(slot + 1) % 3]);
                        // Each edge once, from the triangle that walks it upwards.
                        if a >= b {
                            *cost = f32::INFINITY;
                            continue;
                        }
                        let recent = |marks: &[u32]| {
                            marks[a as usize] == pass - 1 || marks[b as usize] == pass - 1
                        };
                        if pass == 1 || recent(&moved) {
                            *cost = this.price(a, b);
                        } else if recent(&changed) {
                            *cost = cost.abs();
                        }
                    }
                });
            // Collected serially into one reused array, counted first so that it is allocated
            // once at its size: no per-thread copies or growth copies on top of it.
            let candidate = |c: &f32| c.is_finite() && c.is_sign_positive();
            keys.clear();
            keys.reserve_exact(costs.iter().filter(|c| candidate(c)).count());
            keys.extend(
                costs
                    .iter()
                    .enumerate()
                    .filter(|(_, c)| candidate(c))
                    .map(|(slot, c)| (u64::from(c.to_bits()) << 32) | slot as u64),
            );
            // Costs are non-negative, so their bits sort as the costs do; the slot breaks ties.
            keys.par_sort_unstable();
            // Rounds: the cheapest edges whose stars share no triangle with each other, checked
            // in parallel against the mesh as the round found it; the stars of the refused ones
            // are free again for the next round. An accepted collapse is made at once: the
            // survivor's star, and those of the two corners that lose a triangle, are out of
            // date until the next pass rebuilds the stars, so the edges at those three wait for
            // it (as the survivor's, whose prices it changed, must); the others around it keep
            // their prices and stars (their triangles only name the survivor in place of the
            // other end) and may collapse in the next round. A round is selected, checked and
            // made a share at a time: a collapse changes only triangles whose corners the round
            // has locked already, so the keys read after it are taken or kept as before it.
            let mut accepted = 0;
            stamp += 1;
            let held = stamp;
            loop {
                stamp += 1;
                let mut at = Selection {
                    next: 0,
                    kept: 0,
                    stamp,
                    held,
                };
                let mut share = self.select(&mut keys, &mut at, &mut locked);
                if share.is_empty() {
                    break;
                }
                while !share.is_empty() {
                    // In the mesh's order, not the costs': checks and collapses next to each
                    // other then read the same memory (cbd-large f23 at 0.1r: 2.88 → 2.67 s).
                    // They touch disjoint stars, so the order changes nothing else.
                    share.sort_unstable_by_key(|&(slot, _, _)| slot);
                    let this = &*self;
                    // The next share is selected while this one is checked: the selection is
                    // serial, and it takes what it would take after these collapses (an edge
                    // they change has an end in a locked region: kept for the next round, where
                    // it is dropped as it would have been at once).
                    let (checked, next) = rayon::join(
                        || {
                            share
                                .par_iter()
                                .map(|&(_, a, b)| this.check(a, b))
                                .collect::<Vec<Option<Collapse>>>()
                        },
                        || this.select(&mut keys, &mut at, &mut locked),
                    );
                    for (&(slot, _, _), c) in share.iter().zip(checked) {
                        let Some(c) = c else {
                            costs[slot] = -costs[slot];
                            continue;
                        };
                        self.region(c.a, c.b, |v| changed[v] = pass);
                        moved[c.a as usize] = pass;
                        for v in [c.a, c.opposite[0], c.opposite[1]] {
                            locked[v as usize] = held;
                        }
                        self.collapse(&c);
                        accepted += 1;
                    }
                    share = next;
                }
                keys.truncate(at.kept);
            }
            if accepted == 0 {
                break;
            }
        }
    }

    /// Moves `a` to the collapse point, gives it `b`'s triangles and removes the two triangles
    /// of the edge.
    fn collapse(&mut self, c: &Collapse) {
        let (a, b) = (c.a, c.b);
        self.positions[a as usize] = c.point;
        self.quadrics[a as usize] = c.quadric.kept_at(self.local(a));
        self.witness[a as usize] = c.witness;
        for &(t, w) in &c.centres[..c.count] {
            self.centre_witness[t as usize] = w;
        }
        for &t in self.stars.of(b) {
            let tri = &mut self.triangles[t as usize];
            if tri.contains(&a) {
                *tri = [DEAD; 3];
            } else {
                for v in tri.iter_mut().filter(|v| **v == b) {
                    *v = a;
                }
            }
        }
    }
}

/// Where a round's selection stands: the next key to read, how many keys were kept for the
/// next round, the round's lock stamp, and the pass's mark of vertices whose edges wait for the
/// next pass.
struct Selection {
    next: usize,
    kept: usize,
    stamp: u32,
    held: u32,
}

#[cfg(test)]
mod tests;
