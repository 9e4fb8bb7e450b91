//! Clearance for the volume steps (issue 38): the isosurface's inflation is taken back by an
//! offset along the normals as large as the frame needs (0.84 r inwards on cbd-large f23),
//! which would carry a thin sheet's two sides through each other, a droplet or a ridge through
//! its own centre of curvature, and two close bodies into each other. Each vertex gets a room,
//! how far it may move the way the steps move it: the least of its focal distance (from the
//! normals of its ring: d²/(d·Δn) over its ring's edges d, where the ring's normals close in)
//! and half the distance to the nearest vertex within the reach on that side whose normal
//! faces its own, each less a margin; then no more than a tenth of the distance beyond a
//! neighbour's room, so that the offset shears no triangle over another. Smoothing between
//! the steps is not held to it, so it makes crossings rare, not impossible: the guard at the
//! end (`crossings.rs`) tests the faces near two close sides (`close`) and puts back the few
//! that still cross.

use glam::Vec3;
use rayon::prelude::*;

use crate::mesh::adjacency::Neighbours;
use crate::mesh::facing::{FACING, FacingGrid};
/// How fast the room may grow along the surface, per unit length, and the most sweeps that
/// spread it. Each vertex held back lowers the offset in a cone around it, as wide as the
/// offset over the slope, and those cones come and go from frame to frame: a gentler slope
/// flickers more (issue 38, carried jitter on dense-dambreak 120–135 with 0.1, 0.15, 0.2, 0.3
/// and no limit: 0.0256, 0.0232, 0.0224, 0.0217, 0.0217 r; raw 0.0191 r). A steeper one
/// shears the triangles at a cone's foot: on cbd-large f23 with the guard of `crossings.rs`,
/// 0, 0, 9 and 26 faces still cross at 0.1, 0.2, 0.3 and no limit, bumpiness 2.40°, 2.49°,
/// 2.60°, 3.09°, slivers 0.015, 0.044, 0.070, 0.214 %.
const SLOPE: f32 = 0.2;
const SWEEPS: u32 = 8;

/// How far each vertex may still move towards its facing surface, and which way that is.
#[derive(Debug, Clone)]
pub struct Clearance {
    /// Per vertex, the room left, in world units (f32::INFINITY where nothing faces it).
    room: Vec<f32>,
    /// Per component, the direction along the normals the volume steps move it: +1 out, −1 in,
    /// 0 not at all.
    towards: Vec<f32>,
    /// Per vertex, whether a vertex of any component whose normal faces its own lies within
    /// the reach, on either side.
    close: Vec<bool>,
}

impl Clearance {
    /// The room of each vertex of `vertices` (unit `normals`, component `of_vertex[v]`, u32::MAX
    /// for unused vertices) moving by `towards[c]` along its normal, up to `reach`: half the
    /// distance to the nearest vertex on that side whose normal faces it, less `margin`. No
    /// reach (0 or not finite): unlimited room.
    pub fn new(
        vertices: &[Vec3],
        normals: &[Vec3],
        rings: &Neighbours,
        of_vertex: &[u32],
        towards: Vec<f32>,
        reach: f32,
        margin: f32,
    ) -> Clearance {
        // The focal distance along each vertex's normal, from its ring's: an offset beyond it
        // folds the surface over itself (a ridge moved inwards, a valley outwards).
        let mut room: Vec<f32> = (0..vertices.len())
            .into_par_iter()
            .map(|v| {
                let dir = match of_vertex[v] {
                    u32::MAX => return f32::INFINITY,
                    c => towards[c as usize],
                };
                let (p, n) = (vertices[v], normals[v]);
                let mut focal = f32::INFINITY;
                for &u in rings.of(v) {
                    let d = vertices[u as usize] - p;
                    let closing = -dir * d.dot(normals[u as usize] - n);
                    if closing > 0.0 {
                        focal = focal.min(d.length_squared() / closing);
                    }
                }
                (focal - margin).max(0.0)
            })
            .collect();
        let side = |v: usize| match of_vertex[v] {
            u32::MAX => 0.0,
            c => towards[c as usize],
        };
        // Every used vertex is in the grid, those of components that do not move too, to find
        // every vertex close to another (`close`); only those that move hold others back.
        let Some(grid) = FacingGrid::new(vertices, |v| of_vertex[v] != u32::MAX, reach) else {
            let close = vec![false; vertices.len()];
            return Clearance {
                room,
                towards,
                close,
            };
        };
        let rooms = grid.each(vertices, normals, |v, facing| {
            let (p, n, dir) = (vertices[v], normals[v], side(v));
            // The nearest facing vertex that moves, on the side this one moves to; and the
            // nearest of all.
            let (mut nearest, mut any) = (f32::INFINITY, f32::INFINITY);
            for &u in facing {
                let d = vertices[u as usize] - p;
                if n.dot(normals[u as usize]) < FACING {
                    any = any.min(d.length_squared());
                    if dir * d.dot(n) > 0.0 && side(u as usize) != 0.0 {
                        nearest = nearest.min(d.length_squared());
                    }
                }
            }
            let nearest = nearest.sqrt();
            let r = if nearest <= reach {
                (0.5 * nearest - margin).max(0.0)
            } else {
                f32::INFINITY
            };
            (v as u32, r, any <= reach * reach)
        });
        let mut close = vec![false; vertices.len()];
        for (v, r, c) in rooms {
            room[v as usize] = room[v as usize].min(r);
            close[v as usize] = c;
        }
        // Room that changes by at most SLOPE per unit of length along the surface: a vertex
        // beside one held back moves little more than it, so that the offset does not fold the
        // triangles between them. Sweeps forwards and backwards in place (on one thread, so the
        // same on any number) until nothing changes, the least room over the mesh's paths, or
        // SWEEPS have run: on cbd-large f23 and cbd-small f40 all of them run without settling,
        // so the room is an upper bound of that least room where it spreads far.
        // A vertex is visited only while a neighbour's room has changed since its last visit
        // (`stale`): a visit of any other finds every bound as it was, and changes nothing.
        let mut stale = vec![true; room.len()];
        for sweep in 0..SWEEPS {
            let mut changed = false;
            for k in 0..room.len() {
                let v = if sweep % 2 == 0 {
                    k
                } else {
                    room.len() - 1 - k
                };
                if !std::mem::take(&mut stale[v]) {
                    continue;
                }
                let mut lowered = false;
                for &u in rings.of(v) {
                    let bound =
                        room[u as usize] + SLOPE * vertices[v].distance(vertices[u as usize]);
                    if bound < room[v] {
                        room[v] = bound;
                        lowered = true;
                    }
                }
                if lowered {
                    changed = true;
                    for &u in rings.of(v) {
                        stale[u as usize] = true;
                    }
                }
            }
            if !changed {
                break;
            }
        }
        Clearance {
            room,
            towards,
            close,
        }
    }

    /// Which vertices have a vertex within the reach (of any component, on either side) whose
    /// normal faces their own: where two sides of the surface are close. None are without a
    /// reach.
    pub fn into_close(self) -> Vec<bool> {
        self.close
    }

    /// Gives vertices added after the others (a refinement's midpoints) the room of the vertex
    /// each came from.
    pub fn extend(&mut self, parents: impl IntoIterator<Item = u32>) {
        for p in parents {
            self.room.push(self.room[p as usize]);
            self.close.push(self.close[p as usize]);
        }
    }

    /// Moves each vertex by its component's `offsets` along its unit normal, as far as its room
    /// lets it towards the surface that faces it; moving away gives room back.
    pub fn offset(
        &mut self,
        vertices: &mut [Vec3],
        normals: &[Vec3],
        of_vertex: &[u32],
        offsets: &[f32],
    ) {
        let towards = &self.towards;
        vertices
            .par_iter_mut()
            .zip(&mut self.room)
            .zip(normals)
            .zip(of_vertex)
            .for_each(|(((p, room), n), &c)| {
                if c == u32::MAX {
                    return;
                }
                let (offset, dir) = (offsets[c as usize], towards[c as usize]);
                let along = offset * dir;
                let moved = if along > 0.0 {
                    let allowed = along.min(*room);
                    *room -= allowed;
                    allowed * dir
                } else {
                    *room -= along;
                    offset
                };
                *p += moved * *n;
            });
    }
}
