//! The quadric error metric of Garland & Heckbert 1997: a vertex's planes, summed and kept.

use glam::DVec3;

/// Weight, relative to the quadric's area, of the pull towards the edge's midpoint. It picks
/// one point where the planes leave a line or a plane of minimisers (flat and creased regions)
/// and changes the others by a relative 1e-3 at most.
pub(super) const REGULARISATION: f64 = 1e-3;

/// A symmetric 4×4 error quadric `Σ w (n·x + d)²`: `A = Σ w n nᵀ`, `b = -Σ w d n`,
/// `c = Σ w d²`, with `w` the summed weights.
#[derive(Clone, Copy, Default)]
pub(super) struct Quadric {
    a: [f64; 6], // xx, xy, xz, yy, yz, zz
    b: [f64; 3],
    c: f64,
    pub(super) w: f64,
}

impl Quadric {
    pub(super) fn plane(n: DVec3, d: f64, w: f64) -> Quadric {
        Quadric {
            a: [
                w * n.x * n.x,
                w * n.x * n.y,
                w * n.x * n.z,
                w * n.y * n.y,
                w * n.y * n.z,
                w * n.z * n.z,
            ],
            b: [-w * d * n.x, -w * d * n.y, -w * d * n.z],
            c: w * d * d,
            w,
        }
    }

    pub(super) fn add(&self, o: &Quadric) -> Quadric {
        Quadric {
            a: std::array::from_fn(|i| self.a[i] + o.a[i]),
            b: std::array::from_fn(|i| self.b[i] + o.b[i]),
            c: self.c + o.c,
            w: self.w + o.w,
        }
    }

    /// `A p`.
    pub(super) fn times(&self, p: DVec3) -> DVec3 {
        let [xx, xy, xz, yy, yz, zz] = self.a;
        DVec3::new(
            xx * p.x + xy * p.y + xz * p.z,
            xy * p.x + yy * p.y + yz * p.z,
            xz * p.x + yz * p.y + zz * p.z,
        )
    }

    /// The quadric as a vertex at `p` keeps it: around `p`, in `f32`.
    pub(super) fn kept_at(&self, p: DVec3) -> Kept {
        let b = DVec3::from_array(self.b) - self.times(p);
        Kept {
            a: self.a.map(|x| x as f32),
            b: b.to_array().map(|x| x as f32),
            c: self.eval(p) as f32,
            w: self.w as f32,
        }
    }

    /// `xᵀ A x - 2 b·x + c`: the weighted sum of squared distances to the planes.
    pub(super) fn eval(&self, p: DVec3) -> f64 {
        p.dot(self.times(p)) - 2.0 * p.dot(DVec3::from_array(self.b)) + self.c
    }

    /// The minimiser of the quadric plus `λ |x - anchor|²` (`λ` = [`REGULARISATION`] × weight)
    /// on the plane `g·x = h`, by a Lagrange multiplier; without the plane when `g` is zero.
    /// `None` for an empty quadric.
    pub(super) fn minimiser(&self, anchor: DVec3, g: DVec3, h: f64) -> Option<DVec3> {
        let lambda = REGULARISATION * self.w;
        let [xx, xy, xz, yy, yz, zz] = self.a;
        let c0 = DVec3::new(xx + lambda, xy, xz);
        let c1 = DVec3::new(xy, yy + lambda, yz);
        let c2 = DVec3::new(xz, yz, zz + lambda);
        // The rows of the inverse of the symmetric matrix [c0 c1 c2] times its determinant.
        let (r0, r1, r2) = (c1.cross(c2), c2.cross(c0), c0.cross(c1));
        let det = c0.dot(r0);
        if !(det.is_finite() && det > 0.0) {
            return None;
        }
        let solve = |v: DVec3| DVec3::new(r0.dot(v), r1.dot(v), r2.dot(v)) / det;
        let y = solve(DVec3::from_array(self.b) + lambda * anchor);
        let z = solve(g);
        let gz = g.dot(z);
        Some(if gz > 0.0 {
            y + (h - g.dot(y)) / gz * z
        } else {
            y
        })
    }
}

/// A vertex's [`Quadric`] as the decimation keeps it, 44 bytes instead of 88 (cbd-large f23:
/// 23 MB less): in `f32` around the vertex's own position `p`, where `b' = b − A p` and
/// `c' = Q(p)` are as small as the planes' distances there, so that `f32`'s relative precision
/// holds them as well as `f64` holds the sums around the mesh's centre.
#[derive(Clone, Copy, Default)]
pub(super) struct Kept {
    a: [f32; 6],
    b: [f32; 3],
    c: f32,
    w: f32,
}

impl Kept {
    /// The quadric kept at `p`, around the origin again: `b = b' + A p`,
    /// `c = c' + pᵀ A p + 2 b'·p`.
    pub(super) fn at(&self, p: DVec3) -> Quadric {
        let mut q = Quadric {
            a: self.a.map(f64::from),
            b: [0.0; 3],
            c: 0.0,
            w: f64::from(self.w),
        };
        let centred = DVec3::from_array(self.b.map(f64::from));
        let ap = q.times(p);
        q.b = (centred + ap).to_array();
        q.c = f64::from(self.c) + p.dot(ap) + 2.0 * centred.dot(p);
        q
    }
}
