//! One frame of a sequence, file to file: read the particles, look up and check the attributes
//! asked for, reconstruct the surface ([`surface`](super::surface)) or extract an isosurface
//! (Marching Correctors, [`iso`](crate::iso)), turn it upright if asked, write it whole (a
//! temporary renamed into place; a USD layer's values sampled at the frame's number, for a
//! sequence stage). USD output takes the particles' velocities whenever a frame has them
//! (`velocities`, for motion blur), asked for or not. The spacing and the reconstructor are kept from frame to
//! frame, so that a whole sequence shares one grid and one thread pool. Reading (`Loader`) and
//! writing (`Writer`) hold only settings, so that a sequence can run them on threads of
//! their own around the reconstruction (`overlap`).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::Vec3;

use super::Progress;
use crate::attribute_names;
use crate::config::Config;
use crate::error::{Error, Result};
use crate::frames::path_frame_number;
use crate::io::{
    self, Attribute, InputFormat, MeshFormat, Particles, UpAxis, UsdFrame, VertexAttributes,
};
use crate::iso::{self, IsoRequest};
use crate::level_set::LevelSet;
use crate::mesh::TriMesh;
use crate::recon::{Reconstruction, Sampled, Sides};
use crate::reconstructor::Reconstructor;
use crate::report::FrameStats;
use crate::spacing::estimate_spacing;
use crate::temporal::FrameMotion;

/// Turns particle files into mesh files with one configuration, frame after frame.
#[derive(Debug)]
pub struct FramePipeline {
    input_format: Option<InputFormat>,
    format: MeshFormat,
    config: Config,
    iso: Option<IsoRequest>,
    /// The sequence's spacing: the configuration's, else estimated once.
    spacing: Option<f32>,
    reconstructor: Option<Reconstructor>,
    /// Whether the configuration was checked against a frame's particles (the first one
    /// reconstructed, when the spacing was given).
    checked: bool,
    /// Whether an isosurface's warnings were shown (once a sequence, not every frame).
    iso_warned: bool,
}

impl FramePipeline {
    /// Checks the configuration, and that `format` can hold the attributes it asks for.
    /// `iso`: an isosurface of a particle quantity per frame instead of the free surface.
    pub fn new(
        input_format: Option<InputFormat>,
        format: MeshFormat,
        config: Config,
        iso: Option<IsoRequest>,
    ) -> Result<FramePipeline> {
        config.validate()?;
        if !config.output.attributes.is_empty() && !format.holds_attributes() {
            bail_config!(
                "--attributes {} needs PLY, VTK, VTU, VTP, USD or VDB output (--format ply, \
                 ply-ascii, vtk, vtu, vtp, usd or vdb): .{} files have no place for vertex \
                 attributes",
                config.output.attributes.join(","),
                format.extension()
            );
        }
        Ok(FramePipeline {
            input_format,
            format,
            spacing: config.spacing,
            checked: config.spacing.is_none(),
            iso_warned: false,
            config,
            iso,
            reconstructor: None,
        })
    }

    /// Without a spacing yet, estimates it from the first readable, non-empty frame of
    /// `earlier` (frames before this job's first one), as a run over the whole sequence would,
    /// so that every shard and every restart uses the same grid.
    pub fn spacing_from(&mut self, earlier: &[PathBuf], progress: &mut dyn Progress) {
        if self.spacing.is_some() {
            return;
        }
        for input in earlier {
            // A bad frame is reported by the job that owns it.
            let Ok(Particles { positions, .. }) = io::read_particles(input, self.input_format)
            else {
                continue;
            };
            if positions.is_empty() {
                continue;
            }
            self.spacing = estimate_spacing(&positions);
            if let Some(r) = self.spacing {
                progress.spacing_estimated(input, r);
            }
            return;
        }
    }

    /// Reads `input`, writes its mesh to `output`, and returns the frame's figures: a frame
    /// alone, for the tests that compare runs with it.
    #[cfg(test)]
    pub fn frame(
        &mut self,
        input: &Path,
        output: &Path,
        progress: &mut dyn Progress,
    ) -> Result<FrameStats> {
        let loaded = self.loader().load(input)?;
        let made = self.make(input, loaded, progress)?;
        self.writer().write(output, made)
    }

    /// What reads this pipeline's frames, on any thread.
    pub(super) fn loader(&self) -> Loader {
        Loader {
            input_format: self.input_format,
            particle_aabb: self.config.particle_aabb,
        }
    }

    /// What writes this pipeline's meshes, on any thread.
    pub(super) fn writer(&self) -> Writer {
        Writer {
            format: self.format,
            up_axis: self.config.output.up_axis,
        }
    }

    /// Frame `input`'s mesh from its particles: the surface reconstructed, or the isosurface.
    pub(super) fn make(
        &mut self,
        input: &Path,
        loaded: Loaded,
        progress: &mut dyn Progress,
    ) -> Result<Made> {
        match self.prepare(input, loaded, progress)? {
            Ready::Made(made) => Ok(made),
            Ready::Surface(mut prepared) => {
                let mesh = std::mem::take(&mut prepared.mesh);
                self.finish(&prepared, mesh)
            }
        }
    }

    /// Seconds between frames, to carry particles without ids by their velocities.
    pub(super) fn frame_time(&self) -> Option<f32> {
        self.config.post.frame_time
    }

    /// Why a sequence that follows the fluid cannot average its fields along the flow (only
    /// the narrow band and full gather engines sample them so, and a field fitted to a frame
    /// does not hold for the frames beside it), if it cannot.
    pub(super) fn flow_mean_missing(&self) -> Option<String> {
        use crate::config::Engine;
        let engine = self.config.engine;
        if !matches!(engine, Engine::NarrowBand | Engine::FullGather) {
            return Some(format!("the {} engine", engine.name()));
        }
        let kind = self.config.field.kind();
        (kind == "anisotropic").then(|| format!("the {kind} field"))
    }

    /// Whether a sequence's frames follow the fluid from their neighbours (`post.temporal`,
    /// for surfaces that are post-processed).
    pub(super) fn follows_fluid(&self) -> bool {
        self.iso.is_none() && self.config.post.temporal && !self.config.post.raw
    }

    /// Frame `input`'s post-processed surface, its attributes not yet carried onto it (an
    /// isosurface, or a frame without particles, is made whole).
    pub(super) fn prepare(
        &mut self,
        input: &Path,
        loaded: Loaded,
        progress: &mut dyn Progress,
    ) -> Result<Ready> {
        match self.stage(input, loaded, progress)? {
            Staged::Made(made) => Ok(Ready::Made(*made)),
            Staged::Particles(particles) => {
                self.reconstruct(input, &particles, None, None, progress)
            }
        }
    }

    /// Frame `input`'s particles with what carries them to other frames and the attributes
    /// asked for (an isosurface, or a frame without particles, is made whole).
    pub(super) fn stage(
        &mut self,
        input: &Path,
        loaded: Loaded,
        progress: &mut dyn Progress,
    ) -> Result<Staged> {
        let Loaded {
            positions,
            mut attributes,
            outside_box,
            read,
        } = loaded;
        let time = path_frame_number(input);
        if let Some(request) = &self.iso {
            let request = request.clone();
            let mut made = self.iso_frame(input, &request, positions, attributes, progress)?;
            made.stats.timings.read = read;
            made.stats.particles_outside_box = outside_box;
            made.time = time;
            return Ok(Staged::Made(Box::new(made)));
        }
        let mut names = self.config.output.attributes.clone();
        if self.format == MeshFormat::Usd
            && !names.iter().any(|n| n == "velocity")
            && let Some(velocity) = attribute_names::take(&mut attributes, "velocity")
        {
            attributes.insert("velocity".into(), velocity);
            names.push("velocity".into());
        }
        let (motion, ids_warning) = if self.follows_fluid() {
            FrameMotion::new(positions, &mut attributes)
        } else {
            let motion = FrameMotion {
                positions,
                ..FrameMotion::default()
            };
            (motion, None)
        };
        let wanted = particle_attributes(input, attributes, &names)?;
        if motion.positions.is_empty() {
            // Nothing to reconstruct, and nothing to estimate a spacing from.
            let named: Vec<(String, Attribute)> = wanted
                .iter()
                .map(|(name, a)| {
                    let empty = match a {
                        Attribute::Scalar(_) => Attribute::Scalar(Vec::new()),
                        Attribute::Vector(_) => Attribute::Vector(Vec::new()),
                    };
                    (name.clone(), empty)
                })
                .collect();
            let mut stats = FrameStats::default();
            stats.timings.read = read;
            stats.particles_outside_box = outside_box;
            return Ok(Staged::Made(Box::new(Made {
                mesh: TriMesh::default(),
                named,
                stats,
                time,
                level_set: None,
            })));
        }
        Ok(Staged::Particles(FrameParticles {
            motion: Arc::new(motion),
            ids_warning,
            wanted,
            outside_box,
            read,
            time,
        }))
    }

    /// The sequence's reconstructor, made with the spacing of its first frame (`input`,
    /// `positions`) and checked against it.
    fn sequence_reconstructor(
        &mut self,
        input: &Path,
        positions: &[Vec3],
        progress: &mut dyn Progress,
    ) -> Result<&Reconstructor> {
        let r = self.sequence_spacing(input, positions, progress)?;
        let reconstructor = match &mut self.reconstructor {
            Some(rec) => rec,
            slot => slot.insert(Reconstructor::new(Config {
                spacing: Some(r),
                ..self.config.clone()
            })?),
        };
        if !self.checked {
            self.checked = true;
            for warning in reconstructor.warnings(positions) {
                progress.warning(Some(input), &warning);
            }
        }
        Ok(reconstructor)
    }

    /// Frame `input`'s field sampled on its closed band, for its own surface and the means
    /// along the flow of the frames beside it (None where the engine does not sample so).
    pub(super) fn sample(
        &mut self,
        input: &Path,
        particles: &FrameParticles,
        progress: &mut dyn Progress,
    ) -> Result<Option<Sampled>> {
        let positions = &particles.motion.positions;
        let reconstructor = self.sequence_reconstructor(input, positions, progress)?;
        let mut observer = progress.observer();
        reconstructor
            .sample(positions, Some(observer.as_mut()))
            .map_err(|e| e.context("reconstruction failed"))
    }

    /// The post-processed surface of frame `input`'s `particles`, from `own` (its field
    /// [`sample`](Self::sample)d) where given; with `sides`, its field averaged along the
    /// flow with the frames beside it.
    pub(super) fn reconstruct(
        &mut self,
        input: &Path,
        particles: &FrameParticles,
        own: Option<&Sampled>,
        sides: Option<&Sides<'_>>,
        progress: &mut dyn Progress,
    ) -> Result<Ready> {
        let fields = (own, sides);
        self.reconstruct_sampling(input, particles, fields, None, progress)
            .0
    }

    /// [`reconstruct`](Self::reconstruct), and meanwhile on the same threads the
    /// [`sample`](Self::sample) of the frame `ahead` (if any) that a sequence needs next:
    /// neither keeps both threads busy throughout (a frame's stages are not all parallel), so
    /// each fills what the other leaves. The sample's error is left to its own frame to report.
    pub(super) fn reconstruct_sampling(
        &mut self,
        input: &Path,
        particles: &FrameParticles,
        (own, sides): (Option<&Sampled>, Option<&Sides<'_>>),
        ahead: Option<&FrameParticles>,
        progress: &mut dyn Progress,
    ) -> (Result<Ready>, Option<Sampled>) {
        let positions = &particles.motion.positions;
        if let Err(e) = self.sequence_reconstructor(input, positions, progress) {
            return (Err(e), None);
        }
        let reconstructor = self.prepared_reconstructor();
        let mut observer = progress.observer();
        let mut beside = ahead.map(|_| progress.observer());
        let (rec, sampled) = reconstructor.install(|| {
            let mut surface = || {
                reconstructor.reconstruct_along_flow(positions, own, sides, Some(&mut *observer))
            };
            match ahead.zip(beside.as_mut()) {
                Some((later, beside)) => {
                    let sample =
                        || reconstructor.sample(&later.motion.positions, Some(&mut **beside));
                    let (rec, sampled) = rayon::join(surface, sample);
                    (rec, sampled.ok().flatten())
                }
                None => (surface(), None),
            }
        });
        drop((observer, beside));
        let rec = rec.map_err(|e| e.context("reconstruction failed"));
        (rec.map(|rec| ready(rec, particles, progress)), sampled)
    }

    /// A prepared frame made whole with `mesh` (its own surface, or that surface moved): its
    /// attributes carried onto the mesh's vertices.
    pub(super) fn finish(&self, prepared: &Prepared, mesh: TriMesh) -> Result<Made> {
        if self.format == MeshFormat::Vdb {
            return self.finish_level_set(prepared, mesh);
        }
        let columns: Vec<&Attribute> = prepared.wanted.iter().map(|(_, a)| a).collect();
        let values = self.prepared_reconstructor().interpolate_all(
            &mesh,
            &prepared.motion.positions,
            &columns,
        )?;
        let names = prepared.wanted.iter().map(|(name, _)| name.clone());
        let mut stats = prepared.stats;
        stats.triangles = mesh.triangles.len();
        stats.vertices = mesh.vertices.len();
        Ok(Made {
            mesh,
            named: names.zip(values).collect(),
            stats,
            time: prepared.time,
            level_set: None,
        })
    }

    /// [`finish`](Self::finish) for VDB output: the mesh's level set, its attributes carried
    /// onto its active voxels.
    fn finish_level_set(&self, prepared: &Prepared, mesh: TriMesh) -> Result<Made> {
        let reconstructor = self.prepared_reconstructor();
        let mut stats = prepared.stats;
        stats.triangles = mesh.triangles.len();
        stats.vertices = mesh.vertices.len();
        let wanted = !prepared.wanted.is_empty();
        let voxels = reconstructor.install(|| {
            upright_level_set(
                mesh,
                stats.cell,
                self.config.output.up_axis,
                wanted,
                |points| {
                    let columns: Vec<&Attribute> = prepared.wanted.iter().map(|(_, a)| a).collect();
                    let values = reconstructor.interpolate_at(
                        points,
                        &prepared.motion.positions,
                        &columns,
                    )?;
                    let names = prepared.wanted.iter().map(|(n, _)| n.clone());
                    Ok(names.zip(values).collect())
                },
            )
        })?;
        stats.timings.write = voxels.time;
        Ok(Made {
            mesh: TriMesh::default(),
            named: voxels.grids,
            stats,
            time: prepared.time,
            level_set: Some(voxels.level_set),
        })
    }

    /// The reconstructor of the frames prepared so far.
    pub(super) fn prepared_reconstructor(&self) -> &Reconstructor {
        self.reconstructor
            .as_ref()
            .expect("a prepared surface has its reconstructor")
    }

    /// One frame's isosurface, with its extra attributes.
    fn iso_frame(
        &mut self,
        input: &Path,
        request: &IsoRequest,
        positions: Vec<Vec3>,
        attributes: BTreeMap<String, Attribute>,
        progress: &mut dyn Progress,
    ) -> Result<Made> {
        let r = match self.spacing {
            None if positions.is_empty() => 1.0,
            _ => self.sequence_spacing(input, &positions, progress)?,
        };
        let config = Config {
            spacing: Some(r),
            ..self.config.clone()
        };
        // For VDB output, the level set is made while the particles' attributes can still be
        // sampled at its voxels.
        let vdb = self.format == MeshFormat::Vdb;
        let up_axis = config.output.up_axis;
        let wanted = !config.output.attributes.is_empty();
        let mut level_set_time = Duration::ZERO;
        let (surface, level_set) = iso::extract_then(
            &positions,
            attributes,
            request,
            &config,
            |mut surface, extras| {
                if !vdb {
                    extras.onto_vertices(&mut surface);
                    return Ok((surface, None));
                }
                let mesh = std::mem::take(&mut surface.mesh);
                let voxels =
                    upright_level_set(mesh, surface.stats.cell, up_axis, wanted, |points| {
                        Ok(extras.at(points))
                    })?;
                level_set_time = voxels.time;
                surface.attributes = voxels.grids;
                Ok((surface, Some(voxels.level_set)))
            },
        )
        .map_err(|e| e.context(format_args!("'{}'", input.display())))?;
        if !self.iso_warned && !surface.warnings.is_empty() {
            self.iso_warned = true;
            for warning in &surface.warnings {
                progress.warning(Some(input), warning);
            }
        }
        let mut stats = FrameStats {
            spacing: r,
            cell: surface.stats.cell,
            particles: positions.len(),
            triangles: surface.stats.triangles,
            vertices: surface.stats.vertices,
            iso: Some(surface.stats),
            ..FrameStats::default()
        };
        stats.timings.write = level_set_time;
        progress.measured(&mut stats);
        Ok(Made {
            mesh: surface.mesh,
            named: surface.attributes,
            stats,
            time: None,
            level_set,
        })
    }

    /// The sequence's spacing: the one given or found on an earlier frame, else estimated from
    /// this frame's particles and kept, so that the whole sequence shares one spacing, hence one
    /// grid.
    fn sequence_spacing(
        &mut self,
        input: &Path,
        positions: &[Vec3],
        progress: &mut dyn Progress,
    ) -> Result<f32> {
        if let Some(r) = self.spacing {
            return Ok(r);
        }
        let r = estimate_spacing(positions).ok_or_else(|| {
            Error::input(format!(
                "cannot estimate the particle spacing from {} particles; give --spacing or \
                 --particle-radius",
                positions.len()
            ))
        })?;
        progress.spacing_estimated(input, r);
        self.spacing = Some(r);
        Ok(r)
    }
}

/// Frame `particles`' reconstruction `rec` as a prepared frame, with what only the caller
/// measures (`progress`).
fn ready(rec: Reconstruction, particles: &FrameParticles, progress: &mut dyn Progress) -> Ready {
    let mut stats = rec.stats;
    progress.measured(&mut stats);
    stats.particles_outside_box = particles.outside_box;
    stats.timings.read = particles.read;
    Ready::Surface(Prepared {
        mesh: rec.mesh,
        close: rec.close,
        motion: Arc::clone(&particles.motion),
        ids_warning: particles.ids_warning.clone(),
        wanted: particles.wanted.clone(),
        stats,
        time: particles.time,
    })
}

/// Reads frames: the particles in the particle box and their attributes. Holds only settings,
/// so that another thread can read ahead.
#[derive(Debug, Clone, Copy)]
pub(super) struct Loader {
    input_format: Option<InputFormat>,
    particle_aabb: Option<[f32; 6]>,
}

/// A frame read, waiting for its reconstruction.
#[derive(Debug)]
pub(super) struct Loaded {
    positions: Vec<Vec3>,
    attributes: BTreeMap<String, Attribute>,
    outside_box: usize,
    read: Duration,
}

impl Loader {
    pub(super) fn load(&self, input: &Path) -> Result<Loaded> {
        let start = Instant::now();
        let mut frame = io::read_particles(input, self.input_format)?;
        let outside_box = match self.particle_aabb {
            Some(aabb) => frame.retain_in_box(aabb),
            None => 0,
        };
        let Particles {
            positions,
            attributes,
        } = frame;
        Ok(Loaded {
            positions,
            attributes,
            outside_box,
            read: start.elapsed(),
        })
    }
}

/// A frame made whole, or its particles waiting for their reconstruction.
#[derive(Debug)]
pub(super) enum Staged {
    Made(Box<Made>),
    Particles(FrameParticles),
}

/// A frame's particles, with what [`Prepared`] takes from them.
#[derive(Debug)]
pub(super) struct FrameParticles {
    /// The particles, with their ids and velocities when the sequence follows the fluid.
    pub(super) motion: Arc<FrameMotion>,
    ids_warning: Option<String>,
    wanted: Vec<(String, Attribute)>,
    outside_box: usize,
    read: Duration,
    time: Option<u64>,
}

/// A frame made whole, or its surface waiting for its neighbours and its attributes.
#[derive(Debug)]
pub(super) enum Ready {
    Made(Made),
    Surface(Prepared),
}

/// A frame's post-processed surface before its attributes are carried onto it: what a
/// sequence whose surfaces follow the fluid holds of a frame until its neighbours are made.
#[derive(Debug)]
pub(super) struct Prepared {
    pub(super) mesh: TriMesh,
    /// Per vertex, whether another side of the surface faces it (see
    /// [`Reconstruction`](crate::Reconstruction)); empty where unknown.
    pub(super) close: Vec<bool>,
    /// The particles, with their ids and velocities when the sequence follows the fluid.
    pub(super) motion: Arc<FrameMotion>,
    /// Why the file's ids cannot carry the particles, for a warning.
    pub(super) ids_warning: Option<String>,
    wanted: Vec<(String, Attribute)>,
    pub(super) stats: FrameStats,
    time: Option<u64>,
}

impl Prepared {
    /// The reconstructor's spacing and cell for the frame.
    pub(super) fn grid(&self) -> (f32, f32) {
        (self.stats.spacing, self.stats.cell)
    }
}

/// A frame's mesh and vertex attributes, waiting to be written, with its figures.
#[derive(Debug)]
pub(super) struct Made {
    mesh: TriMesh,
    named: Vec<(String, Attribute)>,
    stats: FrameStats,
    /// The frame's number: a USD layer's time code.
    time: Option<u64>,
    /// For VDB output, the level set, already upright, whose active voxels `named` are on.
    level_set: Option<LevelSet>,
}

#[cfg(test)]
impl Made {
    /// The level set of VDB output, and the grids on its voxels.
    pub(super) fn level_set_and_grids(&self) -> (&LevelSet, &[(String, Attribute)]) {
        (self.level_set.as_ref().expect("VDB output"), &self.named)
    }
}

/// Writes meshes: turned upright if asked, whole or not at all.
#[derive(Debug, Clone, Copy)]
pub(super) struct Writer {
    format: MeshFormat,
    up_axis: Option<UpAxis>,
}

impl Writer {
    /// Writes `made` to `output` and returns its figures with the write's time.
    pub(super) fn write(&self, output: &Path, made: Made) -> Result<FrameStats> {
        let Made {
            mut mesh,
            mut named,
            mut stats,
            time,
            level_set,
        } = made;
        let start = Instant::now();
        if let Some(level_set) = level_set {
            level_set.write_file(output, &named)?;
            stats.timings.write += start.elapsed();
            return Ok(stats);
        }
        if let Some(axis) = self.up_axis {
            axis.rotate_mesh(&mut mesh, &mut named);
        }
        if self.format == MeshFormat::Vdb {
            // A frame without particles (no voxels: any voxel size will do).
            let voxel = if stats.cell > 0.0 { stats.cell } else { 1.0 };
            let level_set = LevelSet::of_mesh(&mesh, voxel)?;
            level_set.write_file(output, &named)?;
            stats.timings.write = start.elapsed();
            return Ok(stats);
        }
        let attributes = VertexAttributes {
            named: &named,
            ..Default::default()
        };
        if self.format == MeshFormat::Usd {
            let up_axis = self.up_axis;
            io::write_usd_file(output, &mesh, &attributes, UsdFrame { time, up_axis })?;
        } else {
            io::write_mesh_file_with(output, &mesh, &attributes, self.format)?;
        }
        stats.timings.write = start.elapsed();
        Ok(stats)
    }
}

/// A frame's level set for VDB output, the grids on its active voxels, and the time they took,
/// which counts as writing the frame.
struct Voxels {
    level_set: LevelSet,
    grids: Vec<(String, Attribute)>,
    time: Duration,
}

/// `mesh`'s level set on voxels of `cell`, turned upright first as every output is, and when
/// attributes are `wanted`, those `sample` gives at its active voxels (at their places before
/// the turn, where the particles are; vectors turned with the grid).
fn upright_level_set(
    mut mesh: TriMesh,
    cell: f32,
    up_axis: Option<UpAxis>,
    wanted: bool,
    sample: impl FnOnce(&[Vec3]) -> Result<Vec<(String, Attribute)>>,
) -> Result<Voxels> {
    let start = Instant::now();
    if let Some(axis) = up_axis {
        axis.rotate_mesh(&mut mesh, &mut []);
    }
    let level_set = LevelSet::of_mesh(&mesh, cell)?;
    drop(mesh);
    let mut grids = Vec::new();
    if wanted {
        let mut points = level_set.positions();
        if let Some(axis) = up_axis {
            axis.inverse().rotate(&mut points);
        }
        grids = sample(&points)?;
        if let Some(axis) = up_axis {
            axis.rotate_mesh(&mut TriMesh::default(), &mut grids);
        }
    }
    Ok(Voxels {
        level_set,
        grids,
        time: start.elapsed(),
    })
}

/// The attributes `names` (canonical spellings) of frame `input`, found through the alias
/// table, in the order asked, each checked finite; the frame's other attributes are dropped.
pub(crate) fn particle_attributes(
    input: &Path,
    mut attributes: BTreeMap<String, Attribute>,
    names: &[String],
) -> Result<Vec<(String, Attribute)>> {
    let mut out = Vec::with_capacity(names.len());
    for name in names {
        let Some(attribute) = attribute_names::take(&mut attributes, name) else {
            let mut has: Vec<&str> = attributes.keys().map(String::as_str).collect();
            has.extend(out.iter().map(|(n, _): &(String, Attribute)| n.as_str()));
            has.sort_unstable();
            let shown: Vec<&str> = has.iter().take(12).copied().collect();
            bail_input!(
                "'{}' has no particle attribute '{name}'; it has {}{}",
                input.display(),
                if has.is_empty() {
                    "none".to_string()
                } else {
                    shown.join(", ")
                },
                if has.len() > shown.len() {
                    format!(" and {} more", has.len() - shown.len())
                } else {
                    String::new()
                }
            );
        };
        // The reader leaves attributes as they are; interpolated, one of these would spread.
        let bad = match &attribute {
            Attribute::Scalar(s) => s
                .iter()
                .position(|x| !x.is_finite())
                .map(|i| (i, s[i].to_string())),
            Attribute::Vector(v) => v
                .iter()
                .position(|x| !x.is_finite())
                .map(|i| (i, format!("({}, {}, {})", v[i].x, v[i].y, v[i].z))),
        };
        if let Some((i, value)) = bad {
            let what = if name == "velocity" {
                "velocities"
            } else {
                name
            };
            bail_input!(
                "cannot read {what} from '{}': particle {i} has a non-finite {name} {value}",
                input.display()
            );
        }
        out.push((name.clone(), attribute));
    }
    Ok(out)
}
