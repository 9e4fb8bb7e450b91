//! A USD stage that plays a sequence of splash's frame layers as one animated mesh, through
//! value clips (OpenUSD, "Sequencable, Re-timable Animated Value Clips": explicit clip
//! metadata, with the static scene topology as the manifest, as `usdstitchclips` lays it out).
//!
//! `name.usda` is the stage: time range, frame rate, units, the topology sublayered, and the
//! clip set on `/Surface` (`assetPaths`, `active` and `times`: frame t's layer is active from
//! stage time t on and read at its own time t). `name.topology.usda` declares the prim's
//! attributes, as every clip layer declares them at its top (their union, the first
//! declaration of a name winning), with the metadata clips cannot carry (vertex interpolation,
//! no subdivision). A frame left out of the clips (it failed, or is not written yet) shows the
//! frame before it: clip data holds until the next active clip.

use std::fs::File;
use std::io::{self, BufReader, Write};
use std::path::{Path, PathBuf};

use super::usd_write::{USD_PRIM, declarations, up_axis_token};
use crate::data::UpAxis;
use crate::io::atomic;

/// The frame rate of the stages splash writes (USD's default): time codes per second, by
/// which renderers scale the velocities (units per second) for motion blur. A simulation saved
/// at another rate plays at its own speed, and blurs right, once the stage's
/// `timeCodesPerSecond` and `framesPerSecond` say its rate.
pub const USD_FRAMES_PER_SECOND: f64 = 24.0;

/// One frame of a stage: its layer and the time code its values are sampled at.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UsdClip {
    /// The frame's number, its layer's time code.
    pub time: u64,
    /// The frame's layer, written with that time ([`super::UsdFrame`]).
    pub layer: PathBuf,
}

/// The stage of a sequence whose first frame's layer is `first_layer`: beside it, named after
/// it without its frame number (`mesh/fluid_0001.usda` → `mesh/fluid.usda`; `sequence.usda`
/// when nothing else is left of the name).
pub fn usd_stage_path(first_layer: &Path) -> PathBuf {
    let stem = first_layer
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let without_number = match stem.rfind(|c: char| c.is_ascii_digit()) {
        Some(end) => {
            let start = stem[..end]
                .rfind(|c: char| !c.is_ascii_digit())
                .map_or(0, |i| i + 1);
            format!("{}{}", &stem[..start], &stem[end + 1..])
        }
        None => stem,
    };
    // The separators around the number go with it: `fluid_0001_surface` → `fluid_surface`.
    let separators: &[char] = &['_', '.', '-', ' '];
    let mut name = String::new();
    for part in without_number.split(separators).filter(|p| !p.is_empty()) {
        if !name.is_empty() {
            name.push('_');
        }
        name.push_str(part);
    }
    if name.is_empty() {
        name = "sequence".into();
    }
    first_layer.with_file_name(format!("{name}.usda"))
}

/// The topology layer beside `stage`: `fluid.usda` → `fluid.topology.usda`.
pub fn usd_topology_path(stage: &Path) -> PathBuf {
    stage.with_extension("topology.usda")
}

/// Writes the stage `stage` over `clips` (in time order, at least one) and its topology layer
/// beside it ([`usd_topology_path`]), each whole (a temporary renamed into place), the topology
/// first. `frames_per_second`: the stage's time codes per second, which is what velocities
/// (units per second) are scaled by for motion blur. Errors name the layer that cannot be read
/// or the file that cannot be written.
pub fn write_usd_stage(
    stage: &Path,
    clips: &[UsdClip],
    frames_per_second: f64,
    up_axis: Option<UpAxis>,
) -> crate::error::Result<()> {
    let (Some(first), Some(last)) = (clips.first(), clips.last()) else {
        bail_config!(
            "a USD stage needs at least one frame: '{}'",
            stage.display()
        );
    };
    let (start, end) = (first.time, last.time);
    let mut declared: Vec<String> = Vec::new();
    for clip in clips {
        let read = File::open(&clip.layer)
            .and_then(|f| declarations(&mut BufReader::with_capacity(4096, f)));
        let lines = match read {
            Ok(Some(lines)) => lines,
            Ok(None) => bail_input!(
                "'{}' is not a frame layer splash wrote (no mesh '/{USD_PRIM}' at its top), so \
                 it cannot be a clip of '{}'",
                clip.layer.display(),
                stage.display()
            ),
            Err(e) => {
                return Err(crate::error::Error::Io {
                    path: clip.layer.clone(),
                    message: format!(
                        "cannot read the frame layer '{}' for the stage '{}': {e}",
                        clip.layer.display(),
                        stage.display()
                    ),
                    io_error: e,
                });
            }
        };
        merge(&mut declared, &lines);
    }
    let topology = usd_topology_path(stage);
    let metadata = |out: &mut dyn Write| -> io::Result<()> {
        writeln!(out, "    endTimeCode = {end}")?;
        writeln!(out, "    framesPerSecond = {frames_per_second}")?;
        writeln!(out, "    metersPerUnit = 1")?;
        writeln!(out, "    startTimeCode = {start}")?;
        Ok(())
    };
    let axis = |out: &mut dyn Write| -> io::Result<()> {
        if let Some(axis) = up_axis {
            writeln!(out, "    upAxis = \"{}\"", up_axis_token(axis))?;
        }
        Ok(())
    };
    atomic::write_file(&topology, |out| {
        writeln!(out, "#usda 1.0\n(\n    defaultPrim = \"{USD_PRIM}\"")?;
        metadata(out)?;
        writeln!(out, "    timeCodesPerSecond = {frames_per_second}")?;
        axis(out)?;
        writeln!(out, ")\n\ndef Mesh \"{USD_PRIM}\"\n{{")?;
        for line in &declared {
            writeln!(out, "{line}")?;
        }
        writeln!(out, "    uniform token subdivisionScheme = \"none\"\n}}")
    })?;
    let dir = stage.parent().unwrap_or(Path::new(""));
    atomic::write_file(stage, |out| {
        writeln!(out, "#usda 1.0\n(\n    defaultPrim = \"{USD_PRIM}\"")?;
        writeln!(
            out,
            "    doc = \"splash sequence: {} frames, {start} to {end}\"",
            clips.len()
        )?;
        metadata(out)?;
        let topology = asset(&topology, dir);
        writeln!(out, "    subLayers = [\n        {topology}\n    ]")?;
        writeln!(out, "    timeCodesPerSecond = {frames_per_second}")?;
        axis(out)?;
        writeln!(out, ")\n\nover \"{USD_PRIM}\" (\n    clips = {{")?;
        writeln!(out, "        dictionary default = {{")?;
        let pairs = |out: &mut dyn Write, second: &dyn Fn(usize, &UsdClip) -> u64| {
            for (k, clip) in clips.iter().enumerate() {
                let comma = if k + 1 < clips.len() { "," } else { "" };
                writeln!(
                    out,
                    "                ({}, {}){comma}",
                    clip.time,
                    second(k, clip)
                )?;
            }
            io::Result::Ok(())
        };
        writeln!(out, "            double2[] active = [")?;
        pairs(out, &|k, _| k as u64)?;
        writeln!(out, "            ]\n            asset[] assetPaths = [")?;
        for (k, clip) in clips.iter().enumerate() {
            let comma = if k + 1 < clips.len() { "," } else { "" };
            writeln!(out, "                {}{comma}", asset(&clip.layer, dir))?;
        }
        writeln!(out, "            ]")?;
        writeln!(out, "            asset manifestAssetPath = {topology}")?;
        writeln!(out, "            string primPath = \"/{USD_PRIM}\"")?;
        writeln!(out, "            double2[] times = [")?;
        pairs(out, &|_, clip| clip.time)?;
        writeln!(out, "            ]\n        }}\n    }}\n)\n{{\n}}")
    })
}

/// Adds the declarations of `lines` (an attribute's line and its metadata lines) that
/// `declared` lacks, by attribute name.
fn merge(declared: &mut Vec<String>, lines: &[String]) {
    let name = |line: &str| -> Option<String> {
        let line = line.strip_suffix(" (").unwrap_or(line).trim();
        // `type name`, at the declaration's own indentation.
        let mut words = line.split(' ');
        let (_, name) = (words.next()?, words.next()?);
        Some(name.to_string())
    };
    let mut k = 0;
    while k < lines.len() {
        // A declaration with metadata runs to its `    )`.
        let mut end = k + 1;
        if lines[k].ends_with(" (") {
            while end < lines.len() && lines[end - 1].trim() != ")" {
                end += 1;
            }
        }
        let known = declared
            .iter()
            .filter(|l| l.starts_with("    ") && !l.starts_with("     "))
            .any(|l| name(l) == name(&lines[k]));
        if !known {
            declared.extend(lines[k..end].iter().cloned());
        }
        k = end;
    }
}

/// An asset path as USD text: relative to the stage's directory (`@./fluid_0001.usda@`) when
/// the file is in it, else absolute; in triple delimiters when the name holds an `@`.
fn asset(path: &Path, stage_dir: &Path) -> String {
    let text = match (path.parent(), path.file_name()) {
        (Some(dir), Some(name)) if dir == stage_dir => format!("./{}", name.to_string_lossy()),
        _ => std::path::absolute(path)
            .unwrap_or_else(|_| path.to_path_buf())
            .to_string_lossy()
            .into_owned(),
    };
    if text.contains('@') {
        format!("@@@{text}@@@")
    } else {
        format!("@{text}@")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::TriMesh;
    use crate::io::{Attribute, VertexAttributes, write_usd_file};
    use glam::Vec3;

    #[test]
    fn stage_names_drop_the_frame_number() {
        for (layer, stage) in [
            ("m/fluid_0001.usda", "m/fluid.usda"),
            ("m/frame_0001_surface.usda", "m/frame_surface.usda"),
            ("m/fluid.0007.usda", "m/fluid.usda"),
            ("m/0001.usda", "m/sequence.usda"),
            ("plain.usda", "plain.usda"),
        ] {
            assert_eq!(
                usd_stage_path(Path::new(layer)),
                Path::new(stage),
                "{layer}"
            );
        }
        assert_eq!(
            usd_topology_path(Path::new("m/fluid.usda")),
            Path::new("m/fluid.topology.usda")
        );
    }

    /// Three frames, the second without velocities: the topology declares the union (normals
    /// with their interpolation, velocities once), the stage lists the layers at their times.
    #[test]
    fn a_stage_lists_its_clips_and_declares_their_attributes() {
        let dir = std::env::temp_dir().join(format!("splash-usd-stage-{}", std::process::id()));
        let mesh = TriMesh {
            vertices: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: vec![Vec3::Z; 3],
            triangles: vec![[0, 1, 2]],
        };
        let velocity = [("velocity".to_string(), Attribute::Vector(vec![Vec3::X; 3]))];
        let mut clips = Vec::new();
        for time in [2, 4, 6] {
            let layer = dir.join(format!("fluid_{time:04}.usda"));
            let named: &[_] = if time == 4 { &[] } else { &velocity };
            let attributes = VertexAttributes {
                named,
                ..Default::default()
            };
            let frame = super::super::UsdFrame {
                time: Some(time),
                up_axis: None,
            };
            write_usd_file(&layer, &mesh, &attributes, frame).unwrap();
            clips.push(UsdClip { time, layer });
        }
        let stage = usd_stage_path(&clips[0].layer);
        write_usd_stage(&stage, &clips, 24.0, Some(UpAxis::Z)).unwrap();
        let topology = std::fs::read_to_string(usd_topology_path(&stage)).unwrap();
        assert_eq!(topology.matches("velocities").count(), 1, "{topology}");
        assert_eq!(topology.matches("interpolation = \"vertex\"").count(), 1);
        assert!(topology.contains("subdivisionScheme = \"none\""));
        let text = std::fs::read_to_string(&stage).unwrap();
        for line in [
            "                @./fluid_0004.usda@,",
            "                (4, 1),",
            "                (6, 6)",
            "    startTimeCode = 2",
            "    endTimeCode = 6",
            "    timeCodesPerSecond = 24",
            "    upAxis = \"Z\"",
            "            asset manifestAssetPath = @./fluid.topology.usda@",
        ] {
            assert!(text.lines().any(|l| l == line), "{line}:\n{text}");
        }
        // A layer that is not a frame layer is refused, by name.
        std::fs::write(&clips[1].layer, "#usda 1.0\n").unwrap();
        let e = write_usd_stage(&stage, &clips, 24.0, None).unwrap_err();
        assert!(e.to_string().contains("fluid_0004.usda"), "{e}");
        assert!(write_usd_stage(&stage, &[], 24.0, None).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
