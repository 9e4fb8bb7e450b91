//! Signed distance from points to a closed, consistently wound mesh, within a reach: the
//! nearest point of the nearest triangle (Ericson 2005, *Real-Time Collision Detection*,
//! §5.1.5), signed by the angle-weighted pseudonormal of the feature it lies on — face, edge or
//! vertex (Bærentzen & Aanæs 2005, *Signed distance computation using the angle weighted
//! pseudonormal*), which is exact for any closed manifold mesh. Negative inside. The triangles
//! are binned in cells about a triangle and a half wide, searched shell by shell around the
//! query until no farther cell can hold a nearer triangle, so that a point near the surface
//! visits a few dozen triangles. The cells are grouped in bricks of 4³ that a hash map finds,
//! so that the structure grows with the surface, not the volume it encloses, and a run of
//! nearby queries ([`Cursor`]) hashes a brick once.

use std::borrow::Cow;

use glam::{IVec3, Vec3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

use super::unit_normal;
use crate::neighbours::{CellKeys, cell_of};

/// A mesh prepared for signed-distance queries up to `reach` away: its [`SurfaceBins`], built
/// here or kept by the caller (a sequence keeps a frame's for both frames beside it).
#[derive(Debug)]
pub struct SignedDistance<'a> {
    vertices: &'a [Vec3],
    triangles: &'a [[u32; 3]],
    bins: Cow<'a, SurfaceBins>,
}

/// The triangles of a mesh binned for [`SignedDistance`], without the mesh itself.
#[derive(Debug, Clone)]
pub struct SurfaceBins {
    reach: f32,
    /// The bins' edge, and how many shells of bins cover the reach.
    cell: f32,
    shells: i32,
    /// The bricks' numbering ([`CellKeys`] of the bricks, 4³ bins each), and each occupied
    /// brick's place in `starts`: a query hashes a brick once for the bins around it.
    bricks: CellKeys,
    places: FxHashMap<u32, u32>,
    /// Per occupied brick, where each of its bins' triangles start in `binned` (the bin after
    /// it, or the next brick's first, says where they end).
    starts: Vec<u32>,
    binned: Vec<u32>,
}

/// The gap between `p` and the box around triangle `tri`: no point of the triangle lies
/// nearer, so a query passes a triangle by on six comparisons of the corners it reads anyway
/// (a sphere around it, made from the same corners with four square roots, took a third more
/// of the queries' time on dense-dambreak's `--temporal`; kept per triangle it would add 16
/// bytes a triangle to the three frames a sequence holds).
fn box_gap(p: Vec3, tri: [u32; 3], vertices: &[Vec3]) -> f32 {
    let [a, b, c] = tri.map(|i| vertices[i as usize]);
    let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
    (lo - p).max(p - hi).max(Vec3::ZERO).length_squared()
}

/// Which part of a triangle a point is nearest to.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Feature {
    Face,
    Edge,
    Vertex(u32),
}

/// The nearest triangles so far: the squared distance, the nearest point, and every triangle
/// that reaches that point (the faces of an edge or a vertex all do: ties within a hair of the
/// distance) with the feature it reaches it by, whose pseudonormals [`signed`] sums.
#[derive(Debug, Clone, Copy)]
struct Nearest {
    d2: f32,
    point: Vec3,
    /// The triangles tied (a triangle binned in several cells is met again), in the order met.
    faces: [(u32, Feature); 16],
    count: usize,
}

impl Nearest {
    /// None yet: every triangle is nearer.
    const NONE: Nearest = Nearest {
        d2: f32::INFINITY,
        point: Vec3::ZERO,
        faces: [(0, Feature::Face); 16],
        count: 0,
    };
}

impl<'a> SignedDistance<'a> {
    /// Bins `triangles` (of `vertices`) for queries within `reach` (a positive length).
    pub fn new(vertices: &'a [Vec3], triangles: &'a [[u32; 3]], reach: f32) -> Self {
        let bins = Cow::Owned(SurfaceBins::new(vertices, triangles, reach));
        SignedDistance {
            vertices,
            triangles,
            bins,
        }
    }

    /// Queries on `vertices` and `triangles` with the `bins` made of them.
    pub fn with_bins(
        vertices: &'a [Vec3],
        triangles: &'a [[u32; 3]],
        bins: &'a SurfaceBins,
    ) -> Self {
        SignedDistance {
            vertices,
            triangles,
            bins: Cow::Borrowed(bins),
        }
    }
}

impl SurfaceBins {
    /// Bins `triangles` (of `vertices`) for queries within `reach` (a positive length).
    pub fn new(vertices: &[Vec3], triangles: &[[u32; 3]], reach: f32) -> Self {
        // Bins about a triangle wide: a point near the surface then visits a few dozen.
        let edges: f64 = triangles
            .par_iter()
            .map(|t| f64::from(vertices[t[0] as usize].distance(vertices[t[1] as usize])))
            .sum();
        let mean_edge = (edges / triangles.len().max(1) as f64) as f32;
        let cell = (1.5 * mean_edge).clamp(reach / 8.0, reach);
        let cell = if cell.is_finite() && cell > 0.0 {
            cell
        } else {
            reach
        };
        let bounds = vertices
            .iter()
            .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        let (bricks, cell) = CellKeys::fitting_bricks(bounds, cell);
        let shells = (reach / cell).ceil() as i32 + 1;
        // Per chunk of triangles, `bin key << 32 | triangle` for every bin a triangle's box
        // meets, in triangle order, and the bricks they lie in (a run of one brick told once:
        // neighbouring triangles mostly share theirs).
        let chunks: Vec<(Vec<u64>, Vec<u32>)> = triangles
            .par_chunks(CHUNK)
            .enumerate()
            .map(|(chunk, tris)| {
                let mut entries = Vec::with_capacity(4 * tris.len());
                let mut occupied: Vec<u32> = Vec::new();
                for (k, tri) in tris.iter().enumerate() {
                    let [a, b, c] = tri.map(|i| vertices[i as usize]);
                    let (lo, hi) = (
                        cell_of(a.min(b).min(c), cell),
                        cell_of(a.max(b).max(c), cell),
                    );
                    let t = (chunk * CHUNK + k) as u64;
                    for z in lo.z..=hi.z {
                        for y in lo.y..=hi.y {
                            for x in lo.x..=hi.x {
                                let key = bin_key(&bricks, IVec3::new(x, y, z));
                                entries.push(u64::from(key) << 32 | t);
                                if occupied.last() != Some(&(key >> 6)) {
                                    occupied.push(key >> 6);
                                }
                            }
                        }
                    }
                }
                (entries, occupied)
            })
            .collect();
        // The occupied bricks in key order, numbered in that order.
        let mut occupied: Vec<u32> = chunks.iter().flat_map(|(_, o)| o).copied().collect();
        radsort::sort(&mut occupied);
        occupied.dedup();
        let places: FxHashMap<u32, u32> = occupied.iter().zip(0..).map(|(&k, i)| (k, i)).collect();
        // A counting sort of the entries by bin, stable: each bin lists its triangles in order
        // (a radix sort of the entries took twice as long on dense-dambreak's meshes, and
        // `counting_sort::sort_by_bucket`, which needs them in one buffer, made `--temporal`
        // 1.07x slower).
        let mut last = (u32::MAX, 0);
        let mut bin = |key: u32| {
            if key >> 6 != last.0 {
                last = (key >> 6, places[&(key >> 6)] as usize * BRICK_BINS);
            }
            last.1 + (key & 63) as usize
        };
        let entries = || chunks.iter().flat_map(|(entries, _)| entries);
        let mut starts = vec![0u32; occupied.len() * BRICK_BINS + 1];
        for &e in entries() {
            starts[bin((e >> 32) as u32) + 1] += 1;
        }
        for i in 1..starts.len() {
            starts[i] += starts[i - 1];
        }
        let mut next = starts.clone();
        let mut binned = vec![0u32; starts[starts.len() - 1] as usize];
        for &e in entries() {
            let at = &mut next[bin((e >> 32) as u32)];
            binned[*at as usize] = e as u32;
            *at += 1;
        }
        drop(chunks);
        SurfaceBins {
            reach,
            cell,
            shells,
            bricks,
            places,
            starts,
            binned,
        }
    }

    /// The triangles binned at bin `c`, the brick of the last bin asked for kept in `last`
    /// (the bins a query visits mostly share one).
    #[inline]
    fn in_bin(&self, c: IVec3, last: &mut Option<(IVec3, Option<u32>)>) -> &[u32] {
        let brick = c >> 2;
        let place = match *last {
            Some((b, place)) if b == brick => place,
            _ => {
                let place = self
                    .bricks
                    .key(brick)
                    .and_then(|k| self.places.get(&k).copied());
                *last = Some((brick, place));
                place
            }
        };
        let Some(place) = place else { return &[] };
        let i = place as usize * BRICK_BINS + local_bin(c);
        &self.binned[self.starts[i] as usize..self.starts[i + 1] as usize]
    }
}

/// Where a run of queries ([`SignedDistance::at_from`]) last looked: a brick of bins.
#[derive(Debug, Clone, Copy, Default)]
pub struct Cursor {
    last: Option<(IVec3, Option<u32>)>,
}

/// Bins to a brick: 4³.
const BRICK_BINS: usize = 64;

/// Bin `c`'s place in its brick.
fn local_bin(c: IVec3) -> usize {
    let l = c & 3;
    (l.x | l.y << 2 | l.z << 4) as usize
}

/// Bin `c`'s key: its brick's, then its place in it, so that sorting by key groups each
/// brick's bins.
fn bin_key(bricks: &CellKeys, c: IVec3) -> u32 {
    bricks.packed(c >> 2) << 6 | local_bin(c) as u32
}

/// Triangles a task bins at once: their entries take about 1 MiB, which glibc maps for them
/// and returns when freed (at 8192 the allocator's arenas kept them: dense-dambreak's
/// `--temporal` peaked 5 MiB higher).
const CHUNK: usize = 32768;

impl SignedDistance<'_> {
    /// The signed distance from `p` to the mesh (negative inside), or None when no triangle
    /// lies within the reach. The triangles are visited in a fixed order, so that the answer
    /// does not depend on the thread.
    pub fn at(&self, p: Vec3) -> Option<f32> {
        self.at_from(p, &mut Cursor::default())
    }

    /// [`at`](Self::at) for a run of nearby points: `cursor` keeps the brick of bins the last
    /// query ended in.
    pub fn at_from(&self, p: Vec3, cursor: &mut Cursor) -> Option<f32> {
        let bins = &*self.bins;
        let home = cell_of(p, bins.cell);
        // How far p lies inside its home cell: the searched cells reach this much beyond
        // their shells, so that a point near its cell's middle stops after the cell itself.
        let corner = home.as_vec3() * bins.cell;
        let inside = (p - corner)
            .min(corner + Vec3::splat(bins.cell) - p)
            .min_element()
            .max(0.0);
        let mut best = Nearest::NONE;
        for shell in 0..=bins.shells {
            for dz in -shell..=shell {
                for dy in -shell..=shell {
                    // Inside the shell's faces in z and y, only its two cells in x.
                    let side = dz.abs().max(dy.abs()) == shell;
                    let step = if side || shell == 0 {
                        1
                    } else {
                        2 * shell as usize
                    };
                    for dx in (-shell..=shell).step_by(step) {
                        let key = home + IVec3::new(dx, dy, dz);
                        // A cell whose box is farther than the nearest triangle holds no nearer one.
                        let lo = key.as_vec3() * bins.cell;
                        let gap = (lo - p).max(p - (lo + bins.cell)).max(Vec3::ZERO);
                        if gap.length_squared() > best.d2 * (1.0 + TIE) {
                            continue;
                        }
                        for &t in bins.in_bin(key, &mut cursor.last) {
                            let tri = self.triangles[t as usize];
                            let near = best.d2 * (1.0 + TIE) + f32::MIN_POSITIVE;
                            if box_gap(p, tri, self.vertices) > near {
                                continue;
                            }
                            let t = std::iter::once(t);
                            nearest_in(p, t, self.vertices, self.triangles, &mut best);
                        }
                    }
                }
            }
            // Cells beyond this shell lie at least `shell` cells and `inside` away: past the
            // reach, or past the nearest triangle, none can give an answer.
            let bound = shell as f32 * bins.cell + inside;
            if bound > bins.reach || best.d2 * (1.0 + TIE) < bound * bound {
                break;
            }
        }
        (best.count > 0 && best.d2.sqrt() <= bins.reach)
            .then(|| signed(p, &best, self.vertices, self.triangles))
    }
}

/// The signed distance from `p` to the nearest of `candidates` (triangles of `triangles`),
/// signed as [`SignedDistance::at`] signs it: for a caller that knows the triangles near `p`,
/// which must include every triangle that touches the nearest point.
pub fn signed_distance_among(
    p: Vec3,
    candidates: impl IntoIterator<Item = u32>,
    vertices: &[Vec3],
    triangles: &[[u32; 3]],
) -> Option<f32> {
    let mut best = Nearest::NONE;
    nearest_in(p, candidates, vertices, triangles, &mut best);
    (best.count > 0).then(|| signed(p, &best, vertices, triangles))
}

/// The unsigned distance from `p` to the triangle `tri` of `vertices`.
pub fn triangle_distance(p: Vec3, tri: [u32; 3], vertices: &[Vec3]) -> f32 {
    p.distance(nearest_on_triangle(p, tri, vertices))
}

/// The point of the triangle `tri` of `vertices` nearest to `p`.
pub fn nearest_on_triangle(p: Vec3, tri: [u32; 3], vertices: &[Vec3]) -> Vec3 {
    closest_on_triangle(p, tri, vertices).0
}

/// The distance of `best`, negative when `p` lies behind its pseudonormal: the sum of its
/// tied triangles' shares, made once the nearest are known.
fn signed(p: Vec3, best: &Nearest, vertices: &[Vec3], triangles: &[[u32; 3]]) -> f32 {
    let d = best.d2.sqrt();
    let share = |&(t, feature): &(u32, Feature)| {
        let tri = triangles[t as usize];
        let [a, b, c] = tri.map(|i| vertices[i as usize]);
        let face = unit_normal(&tri, vertices);
        // Bærentzen & Aanæs's pseudonormals: an edge's is the sum of its faces' normals, a
        // vertex's the sum weighted by each face's angle there.
        match feature {
            Feature::Face | Feature::Edge => face,
            Feature::Vertex(v) => {
                let k = tri.iter().position(|&i| i == v).unwrap_or(0);
                let [o, u, w] = [k, (k + 1) % 3, (k + 2) % 3].map(|i| [a, b, c][i]);
                face * (u - o).angle_between(w - o)
            }
        }
    };
    let tied = &best.faces[..best.count];
    let normal = tied[1..]
        .iter()
        .fold(share(&tied[0]), |sum, f| sum + share(f));
    if (p - best.point).dot(normal) < 0.0 {
        -d
    } else {
        d
    }
}

/// Folds `candidates` into `best`: a nearer one replaces it, one as near (a face of the same
/// edge or vertex, or a duplicate visit) joins its ties.
fn nearest_in(
    p: Vec3,
    candidates: impl IntoIterator<Item = u32>,
    vertices: &[Vec3],
    triangles: &[[u32; 3]],
    best: &mut Nearest,
) {
    for t in candidates {
        let tri = triangles[t as usize];
        let (q, feature) = closest_on_triangle(p, tri, vertices);
        let d2 = p.distance_squared(q);
        if d2 > best.d2 * (1.0 + TIE) + f32::MIN_POSITIVE {
            continue;
        }
        if d2 >= best.d2 * (1.0 - TIE) {
            let tied = &best.faces[..best.count];
            if tied.iter().any(|&(f, _)| f == t) || best.count == best.faces.len() {
                continue;
            }
            best.faces[best.count] = (t, feature);
            best.count += 1;
            if d2 < best.d2 {
                best.d2 = d2;
                best.point = q;
            }
        } else {
            best.faces[0] = (t, feature);
            best.count = 1;
            best.d2 = d2;
            best.point = q;
        }
    }
}

/// Squared distances within this share of each other reach the same point: the faces of one
/// edge or vertex, whose nearest points differ only by rounding.
const TIE: f32 = 1e-5;

/// The point of triangle `tri` nearest to `p`, and the feature it lies on (Ericson's Voronoi
/// regions, in his order: vertex a, b, edge ab, vertex c, edges ac, bc, the face).
fn closest_on_triangle(p: Vec3, tri: [u32; 3], vertices: &[Vec3]) -> (Vec3, Feature) {
    let [ia, ib, ic] = tri;
    let [a, b, c] = tri.map(|i| vertices[i as usize]);
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, Feature::Vertex(ia));
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (b, Feature::Vertex(ib));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + ab * v, Feature::Edge);
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (c, Feature::Vertex(ic));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, Feature::Edge);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, Feature::Edge);
    }
    let denom = va + vb + vc;
    if denom <= 0.0 {
        // A degenerate triangle: its nearest corner.
        let corner = [(a, ia), (b, ib), (c, ic)]
            .into_iter()
            .min_by(|x, y| p.distance_squared(x.0).total_cmp(&p.distance_squared(y.0)))
            .expect("three corners");
        return (corner.0, Feature::Vertex(corner.1));
    }
    let (v, w) = (vb / denom, vc / denom);
    (a + ab * v + ac * w, Feature::Face)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tests::common::octasphere;

    /// A unit sphere's mesh: points inside are negative, outside positive, within the mesh's
    /// flattening of the true distance; beyond the reach, nothing.
    #[test]
    fn a_sphere_is_negative_inside_and_positive_outside() {
        let mesh = octasphere(4);
        let sd = SignedDistance::new(&mesh.vertices, &mesh.triangles, 0.5);
        // Level 4: its faces lie within 0.01 of the unit sphere.
        for dir in [Vec3::X, Vec3::new(1.0, 2.0, -3.0).normalize(), -Vec3::Z] {
            for r in [0.6, 0.9, 0.99, 1.01, 1.2, 1.45] {
                let d = sd.at(dir * r).unwrap();
                assert!((d - (r - 1.0)).abs() < 0.01, "r {r}: {d}");
            }
            assert_eq!(sd.at(dir * 1.6), None);
            assert_eq!(sd.at(dir * 0.3), None);
        }
        // A vertex is on the mesh; points beside a vertex or an edge get their sign from the
        // pseudonormals.
        for v in &mesh.vertices {
            assert_eq!(sd.at(*v), Some(0.0));
            assert!(sd.at(*v * 1.001).unwrap() > 0.0);
            assert!(sd.at(*v * 0.999).unwrap() < 0.0);
        }
        for t in &mesh.triangles {
            let mid = (mesh.vertices[t[0] as usize] + mesh.vertices[t[1] as usize]) / 2.0;
            assert!(sd.at(mid * 1.001).unwrap() > 0.0);
            assert!(sd.at(mid * 0.999).unwrap() < 0.0);
        }
    }
}
