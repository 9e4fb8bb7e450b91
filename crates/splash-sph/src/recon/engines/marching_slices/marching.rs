//! Marching Slices within one block (Rosenberg & Birdwell 2008, Sec. 4, Algorithm 1): seeds
//! from every particle, then the lowest slab with work is polygonised, following the surface
//! cube by cube through todo lists, with slice caches only for the slices next to live slabs;
//! then once more from the crossings that walk missed (`missed_seeds.rs`).

use std::sync::atomic::{AtomicUsize, Ordering};

use glam::{DVec3, IVec3, Vec3};
use rustc_hash::FxHashSet;
use serde::Serialize;

use super::blocks::Block;
use super::lookup_cache::LookupCache;
use super::missed_seeds::MissedSeeds;
use super::seeds::particle_seeds;
use super::slice_cache::{Corner, DONE_ABOVE, DONE_BELOW, NO_VERTEX, SliceCache};
use crate::error::Result;
use crate::field::ScalarField;
use crate::mesh::marching_cubes::{
    case_index, cases, crossed_faces, crossing_normal, edge_axis, edge_corners, edge_crossing,
};
use crate::neighbours::handler_array::HandlerArray;
use crate::neighbours::neighbourhood::{Neighbourhood, reach};
use crate::recon::bricks::halo::offset;
use crate::recon::stages::field_sampling::vertex_position;

/// What one block's marching needs besides the block.
pub struct Setting<'a, F: ScalarField + ?Sized> {
    pub handlers: &'a HandlerArray,
    pub field: &'a F,
    pub cell: f32,
    /// The particle spacing r, for the missed seeds.
    pub spacing: f32,
    /// Cache the field's gradient at corners, for `normals = "grid"`.
    pub corner_gradients: bool,
    /// Keep every visited cube, to count visits to a cube already visited.
    pub check_visits: bool,
    /// Bytes held by the blocks being marched now, and their peak.
    pub in_flight: &'a InFlight,
}

#[derive(Default)]
pub struct InFlight {
    now: AtomicUsize,
    pub peak: AtomicUsize,
}

impl InFlight {
    /// Counts `bytes` more in flight, raising the peak; returns `bytes`.
    pub fn add(&self, bytes: usize) -> usize {
        let now = self.now.fetch_add(bytes, Ordering::Relaxed) + bytes;
        self.peak.fetch_max(now, Ordering::Relaxed);
        bytes
    }

    /// Counts `bytes` fewer in flight.
    pub fn sub(&self, bytes: usize) {
        self.now.fetch_sub(bytes, Ordering::Relaxed);
    }
}

/// A block's part of the mesh: triangles of its own cubes, and the vertices they use, some on
/// faces shared with other blocks.
#[derive(Default)]
pub struct BlockMesh {
    /// Per vertex: its edge, as the global index of the edge's lower corner and its axis.
    pub edges: Vec<(IVec3, u8)>,
    pub positions: Vec<Vec3>,
    /// Interpolated corner gradients, with `corner_gradients`; else empty.
    pub normals: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl BlockMesh {
    pub fn heap_bytes(&self) -> usize {
        self.edges.capacity() * size_of::<(IVec3, u8)>()
            + (self.positions.capacity() + self.normals.capacity()) * size_of::<Vec3>()
            + self.triangles.capacity() * size_of::<[u32; 3]>()
    }
}

/// The figures of one block (Fig. 7 of the paper: render and cache memory).
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct BlockStats {
    /// Global index of the block's first interior cube.
    pub lo: [i32; 3],
    pub particles: usize,
    pub cubes_visited: usize,
    /// Cubes visited again: 0 unless the algorithm is wrong (counted with `check_visits`).
    pub revisits: usize,
    pub corners: usize,
    pub peak_slices: usize,
    /// Peak bytes of slice caches, corner caches and todo lists.
    pub render_bytes: usize,
    /// Bytes of the particle lookup cache and the block's particle list.
    pub cache_bytes: usize,
}

struct Marcher<'a, F: ScalarField + ?Sized> {
    set: &'a Setting<'a, F>,
    block: &'a Block,
    /// The block's particles and their channels, in its (height) order: lookups read them
    /// nearly in sequence.
    positions: Vec<Vec3>,
    channels: Vec<Vec<f32>>,
    /// Cubes per side of the block with its margins.
    n: i32,
    side: usize,
    /// Global index of the local corner (0, 0, 0).
    origin: IVec3,
    cache: LookupCache,
    near: Neighbourhood,
    slices: Vec<Option<SliceCache>>,
    pool: Vec<SliceCache>,
    todo: Vec<Vec<[u16; 2]>>,
    mesh: BlockMesh,
    stats: BlockStats,
    visited: FxHashSet<IVec3>,
    /// A bit per cube of the block with its margins, set once visited: the missed seeds'
    /// marching starts only where the first found nothing.
    visited_bits: Vec<u64>,
    live: usize,
    /// Bytes last added to `in_flight`.
    counted: usize,
}

/// Marches one block; the block's memory is freed when this returns.
pub fn march<F: ScalarField + ?Sized>(
    set: &Setting<F>,
    block: &Block,
) -> Result<(BlockMesh, BlockStats)> {
    let n = block.size + 2 * block.margin;
    let origin = block.lo - block.margin;
    let handlers = set.handlers;
    let (positions, channels) = handlers.gather(&block.particles);
    let support = set.field.support();
    let cache = LookupCache::new(
        positions.len(),
        n,
        in_cubes(&positions, &channels, set, origin),
    )?;
    let mut m = Marcher {
        set,
        block,
        positions,
        channels,
        n,
        side: n as usize + 1,
        origin,
        cache,
        near: Neighbourhood::default(),
        slices: (0..=n).map(|_| None).collect(),
        pool: Vec::new(),
        todo: vec![Vec::new(); n as usize],
        mesh: BlockMesh::default(),
        stats: BlockStats {
            lo: block.lo.to_array(),
            particles: block.particles.len(),
            ..BlockStats::default()
        },
        visited: FxHashSet::default(),
        visited_bits: vec![0; (n as usize).pow(3).div_ceil(64)],
        live: 0,
        counted: 0,
    };
    m.stats.cache_bytes = m.cache.heap_bytes()
        + block.heap_bytes()
        + m.positions.capacity() * size_of::<Vec3>()
        + m.channels
            .iter()
            .map(|c| c.capacity() * size_of::<f32>())
            .sum::<usize>();
    m.account();
    let reach_slabs = (f64::from(support) / f64::from(set.cell)).ceil() as i32;
    m.seed(reach_slabs);
    m.run();
    // Pushed after the first marching is done, so that its mesh is unchanged and the missed
    // components' triangles follow.
    m.seed_missed()?;
    m.run();
    m.account();
    set.in_flight.sub(m.counted);
    Ok((m.mesh, m.stats))
}

impl<F: ScalarField + ?Sized> Marcher<'_, F> {
    /// Seeds (Sec. 4, `seeds.rs`), on the block's todo lists.
    fn seed(&mut self, reach_slabs: i32) {
        // The positions apart, as the walks ask the field (and so the cache) for corners.
        let local: Vec<DVec3> = (0..self.positions.len()).map(|i| self.local(i)).collect();
        let top = Some(self.n - 1);
        let seeds = particle_seeds(
            local.len(),
            |i| local[i],
            reach_slabs,
            top,
            |c| self.value(c),
        );
        for cube in seeds {
            self.push(cube);
        }
    }

    /// Missed seeds (`missed_seeds.rs`): the unvisited cubes around each crossing edge found
    /// near sparse particles.
    fn seed_missed(&mut self) -> Result<()> {
        let seeds = MissedSeeds {
            handlers: self.set.handlers,
            field: self.set.field,
            spacing: self.set.spacing,
            cell: self.set.cell,
            lo: self.block.lo,
            size: self.block.size,
        };
        for (c, axis) in seeds.crossing_edges(&self.positions)? {
            let (a, b) = (IVec3::AXES[(axis + 1) % 3], IVec3::AXES[(axis + 2) % 3]);
            let edge = c - self.origin;
            for cube in [edge, edge - a, edge - b, edge - a - b] {
                if within(cube, self.n) && !self.was_visited(cube) {
                    self.push(cube);
                }
            }
        }
        Ok(())
    }

    fn bit(&self, cube: IVec3) -> usize {
        let n = self.n as usize;
        (cube.z as usize * n + cube.y as usize) * n + cube.x as usize
    }

    fn was_visited(&self, cube: IVec3) -> bool {
        let i = self.bit(cube);
        self.visited_bits[i >> 6] >> (i & 63) & 1 != 0
    }

    fn push(&mut self, cube: IVec3) {
        self.todo[cube.z as usize].push([cube.x as u16, cube.y as u16]);
    }

    /// Algorithm 1.
    fn run(&mut self) {
        while let Some(z) = self.todo.iter().position(|t| !t.is_empty()) {
            self.allocate(z);
            self.allocate(z + 1);
            self.account();
            while let Some([x, y]) = self.todo[z].pop() {
                self.visit(IVec3::new(i32::from(x), i32::from(y), z as i32));
            }
            self.account();
            if z == 0 || self.todo[z - 1].is_empty() {
                self.free(z);
            }
            if z + 1 == self.todo.len() || self.todo[z + 1].is_empty() {
                self.free(z + 1);
            }
        }
    }

    fn visit(&mut self, cube: IVec3) {
        let (z, i) = (cube.z as usize, self.entry(cube));
        let (below, above) = (self.slice(z), self.slice(z + 1));
        if below.entry(i) & DONE_ABOVE != 0
            || above.entry(i) & DONE_BELOW != 0
            || self.was_visited(cube)
        {
            return;
        }
        let bit = self.bit(cube);
        self.visited_bits[bit >> 6] |= 1 << (bit & 63);
        self.slices[z].as_mut().unwrap().set_flag(i, DONE_ABOVE);
        self.slices[z + 1].as_mut().unwrap().set_flag(i, DONE_BELOW);
        self.stats.cubes_visited += 1;
        if self.set.check_visits && !self.visited.insert(cube) {
            self.stats.revisits += 1;
        }
        let ids: [u32; 8] = std::array::from_fn(|c| self.corner(cube + offset(c)));
        let values: [f32; 8] = std::array::from_fn(|c| {
            let at = cube + offset(c);
            self.slice(at.z as usize).corners[ids[c] as usize].value
        });
        if within(cube - self.block.margin, self.block.size) {
            self.polygonise(cube, &ids, &values);
        }
        // Neighbours across faces the surface crosses (cubesToDo).
        for step in crossed_faces(&values) {
            let next = cube + step;
            if within(next, self.n) && !self.done(next, cube) {
                self.push(next);
            }
        }
    }

    /// Whether cube `next`, next to `cube`, is done, by the flags of the slices `cube`'s slab
    /// has allocated.
    fn done(&self, next: IVec3, cube: IVec3) -> bool {
        let i = self.entry(next);
        if next.z < cube.z {
            self.slice(cube.z as usize).entry(i) & DONE_BELOW != 0
        } else {
            self.slice(next.z as usize).entry(i) & DONE_ABOVE != 0
        }
    }

    fn polygonise(&mut self, cube: IVec3, ids: &[u32; 8], values: &[f32; 8]) {
        for t in cases()[case_index(values)].triangles() {
            let tri = t.map(|e| self.vertex(cube, ids, values, e as usize));
            self.mesh.triangles.push(tri);
        }
    }

    /// The vertex on edge `e` of `cube`, kept by the edge's lower corner (lookupOrEval's
    /// vertex indices).
    fn vertex(&mut self, cube: IVec3, ids: &[u32; 8], values: &[f32; 8], e: usize) -> u32 {
        let (c0, c1) = edge_corners(e);
        let axis = edge_axis(e);
        let at = cube + offset(c0);
        let z = at.z as usize;
        let existing = self.slice(z).corners[ids[c0] as usize].vertices[axis];
        if existing != NO_VERTEX {
            return existing;
        }
        let (v0, v1) = (values[c0], values[c1]);
        let global = self.origin + at;
        let p0 = vertex_position(global, self.set.cell);
        let (p, t) = edge_crossing(p0, axis, self.set.cell, v0, v1);
        let id = self.mesh.positions.len() as u32;
        self.mesh.positions.push(p);
        self.mesh.edges.push((global, axis as u8));
        if self.set.corner_gradients {
            let end = cube + offset(c1);
            let (g0, g1) = (self.gradient(at, ids[c0]), self.gradient(end, ids[c1]));
            self.mesh
                .normals
                .push(crossing_normal(g0, g1, t, axis, v0, v1));
        }
        self.slices[z].as_mut().unwrap().corners[ids[c0] as usize].vertices[axis] = id;
        id
    }

    /// The cached corner `c` (local), computed first if new: lookupOrEval.
    fn corner(&mut self, c: IVec3) -> u32 {
        let i = self.entry(c);
        if let Some(id) = self.slice(c.z as usize).corner(i) {
            return id;
        }
        let value = self.value(c);
        self.stats.corners += 1;
        let corner = Corner {
            at: [c.x as u16, c.y as u16],
            value,
            gradient: Vec3::NAN,
            vertices: [NO_VERTEX; 3],
        };
        self.slices[c.z as usize]
            .as_mut()
            .unwrap()
            .insert(i, corner)
    }

    fn gradient(&mut self, c: IVec3, id: u32) -> Vec3 {
        let cached = self.slice(c.z as usize).corners[id as usize].gradient;
        if !cached.x.is_nan() {
            return cached;
        }
        self.gather(c);
        let g = self.set.field.gradient(&self.near, Vec3::ZERO);
        self.slices[c.z as usize].as_mut().unwrap().corners[id as usize].gradient = g;
        g
    }

    /// The field at local corner `c`, from exactly the particles in reach of it.
    fn value(&mut self, c: IVec3) -> f32 {
        self.gather(c);
        self.set.field.value(&self.near, Vec3::ZERO)
    }

    fn gather(&mut self, c: IVec3) {
        let anchor = vertex_position(self.origin + c, self.set.cell);
        let particle = in_cubes(&self.positions, &self.channels, self.set, self.origin);
        let candidates = self.cache.lookup(c, particle);
        self.near
            .pick(anchor, candidates, &self.positions, &self.channels);
    }

    /// Particle i in cube units of the block.
    fn local(&self, i: usize) -> DVec3 {
        in_cubes(&self.positions, &self.channels, self.set, self.origin)(i).0
    }

    fn entry(&self, c: IVec3) -> usize {
        c.y as usize * self.side + c.x as usize
    }

    fn slice(&self, z: usize) -> &SliceCache {
        self.slices[z]
            .as_ref()
            .expect("slices of the slab in work are allocated")
    }

    fn allocate(&mut self, z: usize) {
        if self.slices[z].is_none() {
            self.slices[z] = Some(SliceCache::new(self.side, self.pool.pop()));
            self.live += 1;
            self.stats.peak_slices = self.stats.peak_slices.max(self.live);
        }
    }

    /// Frees slice `z` once no slab next to it has work, into the pool.
    fn free(&mut self, z: usize) {
        if let Some(mut s) = self.slices[z].take() {
            s.reset(self.side);
            self.pool.push(s);
            self.live -= 1;
        }
    }

    /// Updates the render memory's peak and the bytes in flight.
    fn account(&mut self) {
        let slices: usize = self
            .slices
            .iter()
            .flatten()
            .chain(&self.pool)
            .map(SliceCache::heap_bytes)
            .sum();
        let todo: usize = self
            .todo
            .iter()
            .map(|t| t.capacity() * size_of::<[u16; 2]>())
            .sum();
        let render = slices + todo + self.visited_bits.capacity() * size_of::<u64>();
        self.stats.render_bytes = self.stats.render_bytes.max(render);
        let now = render + self.stats.cache_bytes;
        if now >= self.counted {
            self.set.in_flight.add(now - self.counted);
        } else {
            self.set.in_flight.sub(self.counted - now);
        }
        self.counted = now;
    }
}

/// Particle i of the block in cube units of the block (whose corner (0, 0, 0) is global corner
/// `origin`), with its reach in cubes.
fn in_cubes<'a, F: ScalarField + ?Sized>(
    positions: &'a [Vec3],
    channels: &'a [Vec<f32>],
    set: &Setting<'a, F>,
    origin: IVec3,
) -> impl Fn(usize) -> (DVec3, f64) + 'a {
    let particle_reach = reach(channels, set.field.support(), set.field.reach_channel());
    let (cell, origin) = (f64::from(set.cell), origin.as_dvec3());
    move |i| {
        let p = positions[i].as_dvec3() / cell - origin;
        (p, f64::from(particle_reach(i)) / cell)
    }
}

/// Whether cube `c` is one of the `n`³ from the origin.
fn within(c: IVec3, n: i32) -> bool {
    c.cmpge(IVec3::ZERO).all() && c.cmplt(IVec3::splat(n)).all()
}
