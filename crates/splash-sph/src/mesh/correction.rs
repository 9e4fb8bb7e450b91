//! Marching Correctors' correction step (Sec. III-D2): move a Marching Cubes vertex along its cube
//! edge onto the exact isosurface of the interpolant, by safeguarded Newton–Raphson.

use glam::Vec3;

/// One cube edge crossed by the isosurface: corner positions and the interpolant's values there,
/// one on each side of `level`.
#[derive(Debug, Clone, Copy)]
pub struct CrossedEdge {
    /// First corner.
    pub a: Vec3,
    /// Second corner.
    pub b: Vec3,
    /// The interpolant at `a`.
    pub value_a: f32,
    /// The interpolant at `b`.
    pub value_b: f32,
}

impl CrossedEdge {
    /// The linear-interpolation parameter of Marching Cubes, the correction's starting point.
    pub fn linear_t(&self, level: f32) -> f32 {
        let span = self.value_b - self.value_a;
        if span == 0.0 {
            0.5
        } else {
            ((level - self.value_a) / span).clamp(0.0, 1.0)
        }
    }

    /// The point at parameter `t` of the edge.
    pub fn at(&self, t: f32) -> Vec3 {
        self.a + (self.b - self.a) * t
    }

    /// The parameter of the edge's point on the isosurface `level` after at most `iterations`
    /// Newton steps from the linear estimate. `eval` returns the interpolant and its gradient
    /// at a point. The directional derivative along the edge drives each step; a step that
    /// leaves the bracket known to hold the root (initially the whole edge, narrowed with every
    /// evaluation) or meets a flat derivative falls back to false position on the bracket
    /// (Illinois variant) where that cuts at least a tenth off either end, else bisection, so the result never leaves the edge and never moves
    /// away from a root the corners bracket. False position rather than bisection: on an edge
    /// nearly tangent to the surface Newton overshoots, and three bisections left vertices of a
    /// sphere up to 2 % of its radius off (false position: 1e-7); bisection where false
    /// position would crawl along one end (the steep blobby field at cell r).
    pub fn correct(
        &self,
        level: f32,
        iterations: u32,
        mut eval: impl FnMut(Vec3) -> (f32, Vec3),
    ) -> f32 {
        let direction = self.b - self.a;
        // Keep `lo` on the side of `a`, `hi` on the side of `b`, with their residuals.
        let below_at_a = self.value_a < level;
        let (mut lo, mut hi) = (0.0f32, 1.0f32);
        let (mut r_lo, mut r_hi) = (self.value_a - level, self.value_b - level);
        let mut last_moved = None;
        let mut t = self.linear_t(level);
        for _ in 0..iterations {
            let (value, gradient) = eval(self.at(t));
            let residual = value - level;
            if residual == 0.0 {
                break;
            }
            let moved_lo = (value < level) == below_at_a;
            if moved_lo {
                (lo, r_lo) = (t, residual);
            } else {
                (hi, r_hi) = (t, residual);
            }
            // Illinois: an end kept twice has its residual halved, so false position moves it.
            if last_moved == Some(moved_lo) {
                if moved_lo {
                    r_hi *= 0.5;
                } else {
                    r_lo *= 0.5;
                }
            }
            last_moved = Some(moved_lo);
            let inside = |x: f32| x > lo && x < hi;
            let slope = gradient.dot(direction);
            let newton = t - residual / slope;
            if newton == t {
                // Converged to f32's resolution: t may now sit on the end of the bracket it
                // narrowed, and a fallback step would throw it away.
                break;
            }
            let secant = lo + (hi - lo) * r_lo / (r_lo - r_hi);
            t = if slope.is_finite() && slope != 0.0 && inside(newton) {
                newton
            } else if inside(secant) && (secant - lo).min(hi - secant) > 0.1 * (hi - lo) {
                // False position, unless it would crawl along one end of the bracket.
                secant
            } else {
                0.5 * (lo + hi)
            };
        }
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere(x: Vec3) -> (f32, Vec3) {
        (x.length(), x.normalize_or_zero())
    }

    #[test]
    fn newton_lands_on_a_curved_surface_where_linear_interpolation_misses() {
        // Edge from inside to outside of the unit sphere, off-centre so the field is not linear.
        let a = Vec3::new(0.5, 0.6, 0.0);
        let b = Vec3::new(1.0, 0.6, 0.0);
        let edge = CrossedEdge {
            a,
            b,
            value_a: a.length(),
            value_b: b.length(),
        };
        let linear = edge.at(edge.linear_t(1.0));
        let corrected = edge.at(edge.correct(1.0, 3, sphere));
        assert!((linear.length() - 1.0).abs() > 1e-3);
        assert!(
            (corrected.length() - 1.0).abs() < 1e-6,
            "{}",
            corrected.length()
        );
    }

    #[test]
    fn more_steps_than_needed_keep_the_converged_vertex() {
        // Once Newton has converged to f32's resolution its next step would land on the end of
        // the narrowed bracket; a fallback there used to halve the bracket (a sphere vertex
        // 2 % of the radius off).
        for (a, b) in [
            (Vec3::new(0.5, 0.6, 0.0), Vec3::new(1.0, 0.6, 0.0)),
            (Vec3::new(0.0, 0.9, 0.1), Vec3::new(0.0, 1.1, 0.1)),
        ] {
            let edge = CrossedEdge {
                a,
                b,
                value_a: a.length(),
                value_b: b.length(),
            };
            for iterations in [3, 5, 10, 30] {
                let x = edge.at(edge.correct(1.0, iterations, sphere));
                assert!((x.length() - 1.0).abs() < 1e-5, "{iterations}: {x}");
            }
        }
    }

    #[test]
    fn zero_iterations_is_marching_cubes() {
        let edge = CrossedEdge {
            a: Vec3::ZERO,
            b: Vec3::X,
            value_a: 0.0,
            value_b: 4.0,
        };
        assert_eq!(edge.correct(1.0, 0, |_| unreachable!()), 0.25);
    }

    #[test]
    fn a_flat_or_misleading_derivative_falls_back_to_bisection_inside_the_edge() {
        // Step function: zero gradient everywhere, root at t = 0.3.
        let edge = CrossedEdge {
            a: Vec3::ZERO,
            b: Vec3::X,
            value_a: -1.0,
            value_b: 1.0,
        };
        let step = |x: Vec3| (if x.x < 0.3 { -1.0 } else { 1.0 }, Vec3::ZERO);
        let t = edge.correct(0.0, 20, step);
        assert!((t - 0.3).abs() < 1e-5, "{t}");
        // A gradient pointing the wrong way never throws the vertex off the edge.
        let t = edge.correct(0.0, 20, |x: Vec3| (x.x - 0.3, -Vec3::X));
        assert!((0.0..=1.0).contains(&t) && (t - 0.3).abs() < 1e-5, "{t}");
    }
}
