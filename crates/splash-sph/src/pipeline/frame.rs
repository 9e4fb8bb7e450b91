//! One frame of a sequence, file to file: read the particles, look up and check the attributes
//! asked for, reconstruct the surface ([`surface`](super::surface)) or extract an isosurface
//! (Marching Correctors, [`iso`](crate::iso)), turn it upright if asked, write it whole (a
//! temporary renamed into place). The spacing and the reconstructor are kept from frame to
//! frame, so that a whole sequence shares one grid and one thread pool.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3;

use super::Progress;
use crate::attribute_names;
use crate::config::Config;
use crate::error::{Error, Result};
use crate::io::{self, Attribute, InputFormat, MeshFormat, Particles, VertexAttributes};
use crate::iso::{self, IsoRequest};
use crate::mesh::TriMesh;
use crate::reconstructor::Reconstructor;
use crate::report::FrameStats;
use crate::spacing::estimate_spacing;

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
                "--attributes {} needs PLY, VTK, VTU or VTP output (--format ply, ply-ascii, \
                 vtk, vtu or vtp): .{} files have no place for vertex attributes",
                config.output.attributes.join(","),
                format.extension()
            );
        }
        Ok(FramePipeline {
            input_format,
            format,
            spacing: config.spacing,
            checked: config.spacing.is_none(),
            config,
            iso,
            reconstructor: None,
        })
    }

    /// The spacing every frame uses: given, or estimated from the first frame with particles.
    pub fn spacing(&self) -> Option<f32> {
        self.spacing
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

    /// Reads `input`, writes its mesh to `output`, and returns the frame's figures.
    pub fn frame(
        &mut self,
        input: &Path,
        output: &Path,
        progress: &mut dyn Progress,
    ) -> Result<FrameStats> {
        let start = Instant::now();
        let mut frame = io::read_particles(input, self.input_format)?;
        let outside_box = match self.config.particle_aabb {
            Some(aabb) => frame.retain_in_box(aabb),
            None => 0,
        };
        let Particles {
            positions,
            attributes,
        } = frame;
        if let Some(request) = &self.iso {
            let read = start.elapsed();
            let request = request.clone();
            let mut stats =
                self.iso_frame(input, output, &request, positions, attributes, progress)?;
            stats.timings.read = read;
            stats.particles_outside_box = outside_box;
            return Ok(stats);
        }
        let wanted = particle_attributes(input, attributes, &self.config.output.attributes)?;
        let read = start.elapsed();
        if positions.is_empty() {
            // Nothing to reconstruct, and nothing to estimate a spacing from.
            let mut empty: Vec<(String, Attribute)> = wanted
                .iter()
                .map(|(name, a)| {
                    let empty = match a {
                        Attribute::Scalar(_) => Attribute::Scalar(Vec::new()),
                        Attribute::Vector(_) => Attribute::Vector(Vec::new()),
                    };
                    (name.clone(), empty)
                })
                .collect();
            self.write(output, &mut TriMesh::default(), &mut empty)?;
            let mut stats = FrameStats::default();
            stats.timings.read = read;
            stats.particles_outside_box = outside_box;
            return Ok(stats);
        }
        let r = self.sequence_spacing(input, &positions, progress)?;
        let reconstructor = match &mut self.reconstructor {
            Some(rec) => rec,
            slot => slot.insert(Reconstructor::new(Config {
                spacing: Some(r),
                ..self.config.clone()
            })?),
        };
        if !self.checked {
            self.checked = true;
            for warning in reconstructor.warnings(&positions) {
                progress.warning(Some(input), &warning);
            }
        }
        let columns: Vec<&Attribute> = wanted.iter().map(|(_, a)| a).collect();
        let mut observer = progress.observer();
        let surface = super::surface(reconstructor, &positions, &columns, observer.as_mut())?;
        drop((columns, observer, positions));
        let names = wanted.into_iter().map(|(name, _)| name);
        let mut named: Vec<(String, Attribute)> = names.zip(surface.attributes).collect();
        let mut stats = surface.stats;
        progress.measured(&mut stats);
        let mut mesh = surface.mesh;
        let start = Instant::now();
        self.write(output, &mut mesh, &mut named)?;
        stats.particles_outside_box = outside_box;
        stats.timings.read = read;
        stats.timings.write = start.elapsed();
        Ok(stats)
    }

    /// One frame's isosurface, written with its extra attributes.
    fn iso_frame(
        &mut self,
        input: &Path,
        output: &Path,
        request: &IsoRequest,
        positions: Vec<Vec3>,
        attributes: BTreeMap<String, Attribute>,
        progress: &mut dyn Progress,
    ) -> Result<FrameStats> {
        let r = match self.spacing {
            None if positions.is_empty() => 1.0,
            _ => self.sequence_spacing(input, &positions, progress)?,
        };
        let config = Config {
            spacing: Some(r),
            ..self.config.clone()
        };
        let surface = iso::extract(&positions, attributes, request, &config)
            .map_err(|e| e.context(format_args!("'{}'", input.display())))?;
        let (mut mesh, mut named) = (surface.mesh, surface.attributes);
        let start = Instant::now();
        self.write(output, &mut mesh, &mut named)?;
        let mut stats = FrameStats {
            spacing: r,
            cell: surface.stats.cell,
            particles: positions.len(),
            triangles: mesh.triangles.len(),
            vertices: mesh.vertices.len(),
            iso: Some(surface.stats),
            ..FrameStats::default()
        };
        stats.timings.write = start.elapsed();
        progress.measured(&mut stats);
        Ok(stats)
    }

    /// Writes a frame's mesh and its vertex attributes, turned upright if asked, whole or not
    /// at all.
    fn write(
        &self,
        output: &Path,
        mesh: &mut TriMesh,
        named: &mut [(String, Attribute)],
    ) -> Result<()> {
        if let Some(axis) = self.config.output.up_axis {
            axis.rotate_mesh(mesh, named);
        }
        let attributes = VertexAttributes {
            named,
            ..Default::default()
        };
        io::write_mesh_file_with(output, mesh, &attributes, self.format)
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

/// The attributes `names` (canonical spellings) of frame `input`, found through the alias
/// table, in the order asked, each checked finite; the frame's other attributes are dropped.
pub fn particle_attributes(
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
