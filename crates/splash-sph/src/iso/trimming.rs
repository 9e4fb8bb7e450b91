//! Boundary trimming (Sec. III-D3, Fig. 3): a triangle is kept where the sum of weights is at
//! least the vertex threshold at all its vertices (case a), dropped where it is at most the
//! threshold at all of them (b), and otherwise cut where the weight, linear along its edges,
//! meets the threshold: one vertex below leaves a quad, split in two triangles (c); two below
//! leave a triangle (d); one below, one on and one above leave a triangle cut through the
//! vertex on the threshold (e). Cut points are shared by the triangles of an edge, so the
//! trimmed mesh stays manifold and consistently wound.

use rustc_hash::FxHashMap;

/// The trimmed triangles and the new vertices on the cut.
#[derive(Debug, Default)]
pub(crate) struct Trimmed {
    pub triangles: Vec<[u32; 3]>,
    /// New vertex `first_new + k` lies `t` of the way from vertex `a` to vertex `b`.
    pub cuts: Vec<(u32, u32, f64)>,
    /// Triangles of each case a–e.
    pub cases: [usize; 5],
}

/// Trims `triangles` whose vertices have sums of weights `weights` at `threshold`; new vertices
/// are numbered from `first_new`.
pub(crate) fn trim(
    weights: &[f64],
    triangles: &[[u32; 3]],
    threshold: f64,
    first_new: u32,
) -> Trimmed {
    let mut out = Trimmed::default();
    let mut cut_of: FxHashMap<(u32, u32), u32> = FxHashMap::default();
    let side = |v: u32| {
        (weights[v as usize] - threshold)
            .partial_cmp(&0.0)
            .map_or(0, |o| o as i32)
    };
    for &tri in triangles {
        let s = tri.map(side);
        let (below, above) = (
            s.iter().filter(|&&x| x < 0).count(),
            s.iter().filter(|&&x| x > 0).count(),
        );
        if below == 0 {
            out.cases[0] += 1;
            out.triangles.push(tri);
            continue;
        }
        if above == 0 {
            out.cases[1] += 1;
            continue;
        }
        out.cases[match (below, above) {
            (1, 2) => 2,
            (2, 1) => 3,
            _ => 4,
        }] += 1;
        let mut polygon = [0u32; 4];
        let mut len = 0;
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            if s[k] >= 0 {
                polygon[len] = a;
                len += 1;
            }
            if s[k] * s[(k + 1) % 3] < 0 {
                let (lo, hi) = (a.min(b), a.max(b));
                let next = first_new + out.cuts.len() as u32;
                polygon[len] = *cut_of.entry((lo, hi)).or_insert_with(|| {
                    let (wl, wh) = (weights[lo as usize], weights[hi as usize]);
                    out.cuts.push((lo, hi, (threshold - wl) / (wh - wl)));
                    next
                });
                len += 1;
            }
        }
        out.triangles.push([polygon[0], polygon[1], polygon[2]]);
        if len == 4 {
            out.triangles.push([polygon[0], polygon[2], polygon[3]]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One triangle with these weights at threshold 0.5.
    fn one(w: [f64; 3]) -> Trimmed {
        trim(&w, &[[0, 1, 2]], 0.5, 3)
    }

    #[test]
    fn cases_a_to_e_give_the_expected_triangles() {
        // (a) all at or above: kept as it is.
        let a = one([0.9, 0.5, 0.7]);
        assert_eq!(
            (a.triangles, a.cuts.len(), a.cases),
            (vec![[0, 1, 2]], 0, [1, 0, 0, 0, 0])
        );
        // (b) all at or below: dropped.
        let b = one([0.2, 0.5, 0.3]);
        assert!(b.triangles.is_empty() && b.cuts.is_empty() && b.cases[1] == 1);
        // (c) one below: a quad 0, 1, cut(1,2), cut(0,2) as two triangles, winding kept.
        let c = one([1.0, 0.9, 0.0]);
        assert_eq!(c.triangles, vec![[0, 1, 3], [0, 3, 4]]);
        assert_eq!(c.cuts, vec![(1, 2, (0.5 - 0.9) / (0.0 - 0.9)), (0, 2, 0.5)]);
        assert_eq!(c.cases[2], 1);
        // (d) two below: the corner triangle at the vertex above.
        let d = one([0.1, 1.0, 0.3]);
        assert_eq!(d.triangles, vec![[3, 1, 4]]);
        assert_eq!(d.cuts, vec![(0, 1, (0.5 - 0.1) / 0.9), (1, 2, 0.5 / 0.7)]);
        assert_eq!(d.cases[3], 1);
        // (e) one on the threshold: the cut runs through it.
        let e = one([0.5, 1.0, 0.0]);
        assert_eq!(e.triangles, vec![[0, 1, 3]]);
        assert_eq!(e.cuts, vec![(1, 2, 0.5)]);
        assert_eq!(e.cases[4], 1);
    }

    #[test]
    fn neighbours_share_their_cut_vertex() {
        // Two triangles over the edge 0–1, both cut on it, and on their own edges.
        let w = [1.0, 0.0, 0.0, 1.0];
        let t = trim(&w, &[[0, 1, 2], [1, 0, 3]], 0.5, 4);
        let on_edge = t.cuts.iter().filter(|c| (c.0, c.1) == (0, 1)).count();
        assert_eq!(on_edge, 1);
        assert_eq!(t.triangles.len(), 3);
    }
}
