//! Jitter: surface motion the fluid does not explain (issue 38). A free surface moves with the
//! fluid, so for a vertex x of mesh t with outward normal n, its signed distances d₊, d₋ to
//! meshes t+1 and t−1 should be −m₊ and +m₋, the fluid's displacement along n towards each
//! (the kernel mean of its particles' displacements, cubic spline of support 2r). What is left,
//! e₊ = d₊ + m₊ and e₋ = d₋ − m₋, is the surface's own motion; a surface that drifts smoothly
//! away from the fluid cancels in (e₊ + e₋)/2, one that jumps at frame t does not. Vertices
//! more than 2r from either neighbour (where the topology changed) or from every particle (a
//! cavity's wall, whose motion no particle tells) are left out. The carried form takes the
//! neighbours' signed distances where the fluid carries the vertex, c± at x + the
//! displacement towards t±1: shapes that the flow carries along the surface then cancel,
//! which d± ± m± counts as jitter: at a fixed point a surface moving exactly with the fluid
//! still shows its curvature swept past (about step² × curvature / 2: 0.09 r for a ball of
//! radius 4.5 r stepping r a frame, 0.05 r on dense-dambreak frame 130 stepping half a
//! spacing), and where the two frame intervals differ (simulators that write frames after
//! adaptive steps: 3.3 and 6.6 ms in turn on dense-dambreak) its slope too.

use glam::Vec3;
use rayon::prelude::*;

use super::motion::{FrameMotion, mean_motions};
use crate::error::Result;
use crate::mesh::{SignedDistance, TriMesh, area_weighted_normals, component_labels_and_volumes};

/// The parts of a surface whose carried jitter [`Jitter::parts`] sums apart, by connected
/// component: the body (the component of largest volume), pieces of at least [`DROPLET`] r³,
/// and droplets below. A droplet's few particles rearrange as it flies, so its surface
/// flickers more than the body's (dense-dambreak 120–135, raw: 2 % of the vertices, a third
/// of the mean square).
pub const PARTS: [&str; 3] = ["body", "pieces", "droplets"];

/// Volume, in r³, under which a component counts as a droplet in [`PARTS`].
pub const DROPLET: f64 = 10.0;

/// The carried sums of one of the [`PARTS`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Part {
    /// Vertices measured in the carried form.
    pub vertices: u64,
    /// Σ ((c₊ + c₋)/2)² over those, in spacings r.
    pub carried: f64,
}

impl Part {
    /// RMS((c₊ + c₋)/2) in spacings r (NaN without vertices).
    pub fn rms(&self) -> f64 {
        if self.vertices == 0 {
            f64::NAN
        } else {
            (self.carried / self.vertices as f64).sqrt()
        }
    }
}

/// Sums of squares over the vertices of inner frames, in spacings r; add frames with `+=`.
/// Vertices without an area around them or with a non-finite figure count as left out.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Jitter {
    /// Vertices measured.
    pub vertices: u64,
    /// Vertices left out: no surface within 2r in a neighbouring frame, or no particle within 2r.
    pub left_out: u64,
    /// Σ ((e₊ + e₋)/2)².
    pub jitter: f64,
    /// Σ e₊²: drift and jitter.
    pub forward: f64,
    /// Σ ((d₊ + d₋)/2)²: the surface alone, without the particles.
    pub surface: f64,
    /// Vertices measured in the carried form: both neighbours within 2r of the carried vertex.
    pub carried_vertices: u64,
    /// Σ ((c₊ + c₋)/2)² over those.
    pub carried: f64,
    /// The carried sums of each of the [`PARTS`], in order.
    pub parts: [Part; 3],
}

impl std::ops::AddAssign for Jitter {
    fn add_assign(&mut self, o: Jitter) {
        self.vertices += o.vertices;
        self.left_out += o.left_out;
        self.jitter += o.jitter;
        self.forward += o.forward;
        self.surface += o.surface;
        self.carried_vertices += o.carried_vertices;
        self.carried += o.carried;
        for (a, b) in self.parts.iter_mut().zip(o.parts) {
            a.vertices += b.vertices;
            a.carried += b.carried;
        }
    }
}

impl Jitter {
    /// RMS((e₊ + e₋)/2) in spacings r.
    pub fn rms(&self) -> f64 {
        self.mean(self.jitter)
    }

    /// RMS(e₊) in spacings r.
    pub fn forward_rms(&self) -> f64 {
        self.mean(self.forward)
    }

    /// RMS((d₊ + d₋)/2) in spacings r.
    pub fn surface_rms(&self) -> f64 {
        self.mean(self.surface)
    }

    /// RMS((c₊ + c₋)/2) in spacings r: the carried form.
    pub fn carried_rms(&self) -> f64 {
        if self.carried_vertices == 0 {
            f64::NAN
        } else {
            (self.carried / self.carried_vertices as f64).sqrt()
        }
    }

    fn mean(&self, sum: f64) -> f64 {
        if self.vertices == 0 {
            f64::NAN
        } else {
            (sum / self.vertices as f64).sqrt()
        }
    }
}

/// The meshes of frames t−1, t, t+1 and the particles of frame t with their displacements to
/// frames t+1 (`forward`) and from t−1 (`backward`: the displacement of each particle of
/// frame t since t−1).
#[derive(Debug, Clone, Copy)]
pub struct Window<'a> {
    /// Meshes t−1, t, t+1.
    pub meshes: [&'a TriMesh; 3],
    /// Frame t's particles.
    pub particles: &'a FrameMotion,
    /// Per particle of frame t: its position at t+1 minus at t.
    pub forward: &'a [Option<Vec3>],
    /// Per particle of frame t: its position at t minus at t−1.
    pub backward: &'a [Option<Vec3>],
}

/// The jitter of frame t's mesh in `window`, at spacing `spacing` (r).
pub fn frame_jitter(window: &Window<'_>, spacing: f32) -> Result<Jitter> {
    let [prev, mesh, next] = window.meshes;
    let reach = 2.0 * spacing;
    let normals = area_weighted_normals(&mesh.vertices, &mesh.triangles);
    let positions = &window.particles.positions;
    let support = 2.0 * spacing;
    let motions = mean_motions(
        &mesh.vertices,
        positions,
        &[window.forward, window.backward],
        support,
        0.0,
    )?;
    let [ahead, behind] = <[_; 2]>::try_from(motions).expect("one mean per displacement");
    let (to_prev, to_next) = rayon::join(
        || SignedDistance::new(&prev.vertices, &prev.triangles, reach),
        || SignedDistance::new(&next.vertices, &next.triangles, reach),
    );
    let r = f64::from(spacing);
    let parts = vertex_parts(mesh, r);
    Ok(mesh
        .vertices
        .par_iter()
        .enumerate()
        .map(|(i, &x)| {
            let mut out = Jitter::default();
            let n = normals[i];
            if n == Vec3::ZERO || !n.is_finite() {
                // No area around it, or a non-finite vertex nearby (a peer's mesh may have one).
                out.left_out = 1;
                return out;
            }
            let (Some(d_next), Some(d_prev), Some(ahead), Some(behind)) =
                (to_next.at(x), to_prev.at(x), ahead[i], behind[i])
            else {
                // No surface near in a neighbour, or no particle near to say how the fluid moves.
                out.left_out = 1;
                return out;
            };
            let (m_next, m_prev) = (n.dot(ahead), n.dot(behind));
            if !(d_next + d_prev + m_next + m_prev).is_finite() {
                out.left_out = 1;
                return out;
            }
            let e_next = f64::from(d_next + m_next) / r;
            let e_prev = f64::from(d_prev - m_prev) / r;
            let surface = f64::from(d_next + d_prev) / (2.0 * r);
            if let (Some(c_next), Some(c_prev)) = (to_next.at(x + ahead), to_prev.at(x - behind))
                && (c_next + c_prev).is_finite()
            {
                out.carried_vertices = 1;
                out.carried = (f64::from(c_next + c_prev) / (2.0 * r)).powi(2);
                out.parts[usize::from(parts[i])] = Part {
                    vertices: 1,
                    carried: out.carried,
                };
            }
            out.vertices = 1;
            out.jitter = ((e_next + e_prev) / 2.0).powi(2);
            out.forward = e_next * e_next;
            out.surface = surface * surface;
            out
        })
        .reduce(Jitter::default, |mut a, b| {
            a += b;
            a
        }))
}

/// Which of the [`PARTS`] each vertex of `mesh` belongs to (vertices no triangle uses count
/// as the body's; they are never measured), at spacing `r`.
fn vertex_parts(mesh: &TriMesh, r: f64) -> Vec<u8> {
    let (labels, volumes) = component_labels_and_volumes(mesh);
    let body = (0..volumes.len()).max_by(|&a, &b| volumes[a].total_cmp(&volumes[b]));
    let of_component: Vec<u8> = (0..volumes.len())
        .map(|c| {
            if Some(c) == body {
                0
            } else if volumes[c].abs() >= DROPLET * r * r * r {
                1
            } else {
                2
            }
        })
        .collect();
    let mut parts = vec![0u8; mesh.vertices.len()];
    for (t, &label) in mesh.triangles.iter().zip(&labels) {
        for &i in t {
            parts[i as usize] = of_component[label as usize];
        }
    }
    parts
}
