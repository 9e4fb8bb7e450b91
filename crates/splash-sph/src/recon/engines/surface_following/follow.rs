//! Surface-following Marching Cubes (Rosenberg & Birdwell 2008, Sec. 2 and the baselines of
//! Sec. 7; Wyvill et al. 1986): from seed cubes, each cube the surface crosses is visited once,
//! triangulated, and its neighbours across the faces the surface crosses go on a todo stack;
//! corners and the cubes done are kept in a corner cache, an array or a hash map.

use glam::{IVec3, Vec3};

use crate::mesh::marching_cubes::{
    case_index, cases, crossed_faces, crossing_normal, edge_axis, edge_corners, edge_crossing,
};
use crate::recon::bricks::halo::offset;
use crate::recon::engines::marching_slices::marching::BlockMesh;
use crate::recon::stages::field_sampling::vertex_position;

/// A corner cache: the field at corners (computed at first use), the mesh vertices on their
/// edges, and which cubes are done, in the follower's corner coordinates.
pub trait Corners {
    fn value(&mut self, c: IVec3) -> f32;
    /// The field's gradient at `c`, for `normals = "grid"`.
    fn gradient(&mut self, c: IVec3) -> Vec3;
    /// The vertex on the edge from `c` along `axis`, if made.
    fn vertex(&self, c: IVec3, axis: usize) -> Option<u32>;
    fn set_vertex(&mut self, c: IVec3, axis: usize, id: u32);
    /// Whether `cube` was visited; a visited cube's corners are cached.
    fn done(&self, cube: IVec3) -> bool;
    fn set_done(&mut self, cube: IVec3);
    /// Bytes held: the paper's "render memory".
    fn heap_bytes(&self) -> usize;
}

/// The cubes a block holds: 0..`n` per axis, its own `margin..margin + size`.
#[derive(Clone, Copy)]
pub struct Bounds {
    pub n: i32,
    pub margin: i32,
    pub size: i32,
}

pub struct Follower<C> {
    pub corners: C,
    /// Global index of corner (0, 0, 0).
    origin: IVec3,
    cell: f32,
    corner_gradients: bool,
    /// The block's cubes; unbounded without.
    bounds: Option<Bounds>,
    todo: Vec<IVec3>,
    pub mesh: BlockMesh,
    pub cubes_visited: usize,
    /// Peak bytes of the todo stack.
    pub todo_bytes: usize,
}

impl<C: Corners> Follower<C> {
    pub fn new(
        corners: C,
        origin: IVec3,
        cell: f32,
        corner_gradients: bool,
        bounds: Option<Bounds>,
    ) -> Self {
        Follower {
            corners,
            origin,
            cell,
            corner_gradients,
            bounds,
            todo: Vec::new(),
            mesh: BlockMesh::default(),
            cubes_visited: 0,
            todo_bytes: 0,
        }
    }

    /// Whether `cube` is one the follower may visit.
    pub fn within(&self, cube: IVec3) -> bool {
        self.bounds
            .is_none_or(|b| cube.cmpge(IVec3::ZERO).all() && cube.cmplt(IVec3::splat(b.n)).all())
    }

    pub fn push(&mut self, cube: IVec3) {
        self.todo.push(cube);
    }

    /// Visits every cube on the todo stack and those it leads to.
    pub fn run(&mut self) {
        while let Some(cube) = self.todo.pop() {
            self.visit(cube);
        }
        self.todo_bytes = self
            .todo_bytes
            .max(self.todo.capacity() * size_of::<IVec3>());
    }

    fn visit(&mut self, cube: IVec3) {
        if self.corners.done(cube) {
            return;
        }
        let values: [f32; 8] = std::array::from_fn(|c| self.corners.value(cube + offset(c)));
        self.corners.set_done(cube);
        self.cubes_visited += 1;
        let own = self.bounds.is_none_or(|b| {
            let c = cube - b.margin;
            c.cmpge(IVec3::ZERO).all() && c.cmplt(IVec3::splat(b.size)).all()
        });
        if own {
            for t in cases()[case_index(&values)].triangles() {
                let tri = t.map(|e| self.vertex(cube, &values, e as usize));
                self.mesh.triangles.push(tri);
            }
        }
        // Neighbours across faces the surface crosses.
        for step in crossed_faces(&values) {
            let next = cube + step;
            if self.within(next) && !self.corners.done(next) {
                self.todo.push(next);
            }
        }
    }

    /// The vertex on edge `e` of `cube`, kept by the edge's lower corner, placed as every
    /// engine places it.
    fn vertex(&mut self, cube: IVec3, values: &[f32; 8], e: usize) -> u32 {
        let (c0, c1) = edge_corners(e);
        let axis = edge_axis(e);
        let at = cube + offset(c0);
        if let Some(id) = self.corners.vertex(at, axis) {
            return id;
        }
        let (v0, v1) = (values[c0], values[c1]);
        let global = self.origin + at;
        let (p, t) = edge_crossing(vertex_position(global, self.cell), axis, self.cell, v0, v1);
        let id = self.mesh.positions.len() as u32;
        self.mesh.positions.push(p);
        self.mesh.edges.push((global, axis as u8));
        if self.corner_gradients {
            let (g0, g1) = (
                self.corners.gradient(at),
                self.corners.gradient(cube + offset(c1)),
            );
            self.mesh
                .normals
                .push(crossing_normal(g0, g1, t, axis, v0, v1));
        }
        self.corners.set_vertex(at, axis, id);
        id
    }
}
