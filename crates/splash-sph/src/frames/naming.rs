//! Where each frame's result goes: into a directory (frame numbers padded as Blender's sequence
//! importers expect), by a pattern with `{stem}` and `{frame:04}`, or beside its input; and the
//! checks that no two frames share an output and no output overwrites an input.

use std::path::{Path, PathBuf};

use super::{frame_number, input_stem, padded_stem};
use crate::error::{Error, Result};
use crate::io::MeshFormat;

/// Frame numbers in directory output names are zero-padded to this many digits, as Blender's
/// sequence importers expect (`fluid_0001.obj`).
pub(crate) const FRAME_DIGITS: usize = 4;

/// Where the results go.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Output {
    /// Beside each input, as `{stem}{suffix}.{ext}` (recon's suffix is `_surface`).
    BesideInput,
    /// Into a directory, as `{stem}.{ext}`, the stem's frame number padded to 4 digits
    /// (`f_9.ply` → `f_0009.obj`).
    Directory(PathBuf),
    /// A file name with `{stem}` and/or `{frame}` (`{frame:04}` pads to 4 digits) replaced per
    /// frame; a plain name is allowed for a single input.
    Pattern(String),
}

impl Output {
    /// An output as a user writes it: a trailing separator or an existing directory means a
    /// directory, anything else a pattern.
    pub fn parse(text: &str) -> Output {
        if text.ends_with('/')
            || text.ends_with(std::path::MAIN_SEPARATOR)
            || Path::new(text).is_dir()
        {
            Output::Directory(PathBuf::from(text))
        } else {
            Output::Pattern(text.to_string())
        }
    }

    /// The mesh format a file name asks for by its extension.
    pub fn format_hint(&self) -> Option<MeshFormat> {
        match self {
            Output::Pattern(p) => MeshFormat::from_path(Path::new(p)),
            _ => None,
        }
    }

    /// The mesh format: `configured` (the config's or a flag's), else the one the output
    /// name's extension implies, else OBJ. An extension that contradicts `configured` or names
    /// no mesh format is refused: OBJ text in a `.stl` would pass for a mesh of that kind
    /// until something reads it.
    pub fn mesh_format(&self, configured: Option<MeshFormat>) -> Result<MeshFormat> {
        Ok(match (configured, self.format_hint()) {
            (Some(format), hint) => {
                if let Some(hint) = hint.filter(|h| h.extension() != format.extension()) {
                    bail_config!(
                        "--format {} does not match the output name's .{} extension",
                        format_name(format),
                        hint.extension()
                    );
                }
                format
            }
            (None, Some(hint)) => hint,
            (None, None) => match self.extension() {
                Some(ext) => bail_config!(
                    "the output name's .{ext} extension is not a mesh format splash writes \
                     (.obj, .ply, .inc, .vtk, .vtu, .vtp, .usda, .vdb); rename the output or give \
                     --format"
                ),
                None => MeshFormat::Obj,
            },
        })
    }

    /// The extension of an output file name, if it has one.
    pub fn extension(&self) -> Option<String> {
        match self {
            Output::Pattern(p) => Some(Path::new(p).extension()?.to_string_lossy().into_owned()),
            _ => None,
        }
    }

    /// The output of `input` for files of extension `ext`; beside the input its name is
    /// `{stem}{suffix}.{ext}`.
    pub fn path_with(&self, input: &Path, suffix: &str, ext: &str) -> Result<PathBuf> {
        let stem = input_stem(input)
            .ok_or_else(|| Error::input(format!("{}: no file name", input.display())))?;
        Ok(match self {
            Output::BesideInput => input.with_file_name(format!("{stem}{suffix}.{ext}")),
            Output::Directory(dir) => {
                dir.join(format!("{}.{ext}", padded_stem(&stem, FRAME_DIGITS)))
            }
            Output::Pattern(p) => PathBuf::from(expand_pattern(p, &stem)?),
        })
    }
}

/// A format's name as `--format` and the config spell it.
fn format_name(format: MeshFormat) -> &'static str {
    match format {
        MeshFormat::PlyBinary => "ply",
        MeshFormat::PlyAscii => "ply-ascii",
        MeshFormat::Pov => "pov",
        MeshFormat::Usd => "usd",
        other => other.extension(),
    }
}

/// The outputs of all `inputs` (`what` each is, for messages: "mesh", "preview"), checked
/// before any work starts: a plain name for several inputs, an output that is an input, and
/// two inputs sharing an output are errors.
pub fn output_paths(
    inputs: &[PathBuf],
    output: &Output,
    what: &str,
    suffix: &str,
    ext: &str,
) -> Result<Vec<PathBuf>> {
    let outputs: Vec<PathBuf> = inputs
        .iter()
        .map(|i| output.path_with(i, suffix, ext))
        .collect::<Result<_>>()?;
    if let Output::Pattern(p) = output
        && inputs.len() > 1
        && !p.contains("{stem}")
        && !p.contains("{frame")
    {
        bail_config!(
            "-o {p} names one file for {} inputs: give a directory (ending in /) or a pattern \
             with {{stem}} or {{frame:04}}",
            inputs.len()
        );
    }
    for (input, output) in inputs.iter().zip(&outputs) {
        if inputs.iter().any(|i| same_file(i, output)) {
            bail_config!(
                "the {what} of {} would overwrite the input {}: choose another output name",
                input.display(),
                output.display()
            );
        }
    }
    let mut sorted: Vec<(&PathBuf, &PathBuf)> = outputs.iter().zip(inputs).collect();
    sorted.sort();
    for w in sorted.windows(2) {
        if w[0].0 == w[1].0 {
            bail_config!(
                "{} and {} would both be written to {}",
                w[0].1.display(),
                w[1].1.display(),
                w[0].0.display()
            );
        }
    }
    Ok(outputs)
}

fn expand_pattern(pattern: &str, stem: &str) -> Result<String> {
    let mut out = pattern.replace("{stem}", stem);
    while let Some(start) = out.find("{frame") {
        let end = start
            + out[start..].find('}').ok_or_else(|| {
                Error::config(format!("unclosed '{{frame' in output pattern '{pattern}'"))
            })?;
        let spec = &out[start + "{frame".len()..end];
        let width = match spec.strip_prefix(':') {
            None if spec.is_empty() => 0,
            Some(w) => w.parse::<usize>().map_err(|_| {
                Error::config(format!(
                    "bad '{{frame{spec}}}' in output pattern '{pattern}': use {{frame}} or \
                     {{frame:04}}"
                ))
            })?,
            None => bail_config!("bad '{{frame{spec}}}' in output pattern '{pattern}'"),
        };
        let number = frame_number(stem).ok_or_else(|| {
            Error::input(format!(
                "'{stem}' has no frame number for the output pattern '{pattern}'"
            ))
        })?;
        out.replace_range(start..=end, &format!("{number:0width$}"));
    }
    Ok(out)
}

/// Whether `a` and `b` name one file: by their canonical paths where both exist (`./f.ply`
/// and `f.ply`, links), else as written.
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_expand() {
        assert_eq!(
            expand_pattern("m/{stem}.obj", "frame_7").unwrap(),
            "m/frame_7.obj"
        );
        assert_eq!(
            expand_pattern("m/f_{frame:04}.obj", "frame_7").unwrap(),
            "m/f_0007.obj"
        );
        assert_eq!(expand_pattern("{frame}.ply", "x12").unwrap(), "12.ply");
        assert!(expand_pattern("{frame:x}.ply", "x12").is_err());
        assert!(expand_pattern("{frame}.ply", "nodigits").is_err());
    }

    #[test]
    fn the_format_follows_the_name_unless_given() {
        let format = |name: &str, given| Output::parse(name).mesh_format(given);
        assert_eq!(format("m/{stem}.ply", None).unwrap(), MeshFormat::PlyBinary);
        assert_eq!(format("m/{stem}", None).unwrap(), MeshFormat::Obj);
        let given = Some(MeshFormat::PlyAscii);
        assert_eq!(format("m/{stem}.PLY", given).unwrap(), MeshFormat::PlyAscii);
        let clash = format("x.ply", Some(MeshFormat::Obj))
            .unwrap_err()
            .to_string();
        assert!(clash.contains("--format obj does not match the output name's .ply"));
        assert!(format("x.stl", None).is_err());
    }

    #[test]
    fn outputs_are_named_and_checked() {
        let inputs: Vec<PathBuf> = ["s/f_9.ply", "s/f_10.ply"].map(PathBuf::from).into();
        let names = |o: &Output| output_paths(&inputs, o, "mesh", "_surface", "obj");
        assert_eq!(
            names(&Output::Directory("m".into())).unwrap(),
            ["m/f_0009.obj", "m/f_0010.obj"].map(PathBuf::from)
        );
        assert_eq!(
            names(&Output::BesideInput).unwrap(),
            ["s/f_9_surface.obj", "s/f_10_surface.obj"].map(PathBuf::from)
        );
        let one = names(&Output::Pattern("m.obj".into())).unwrap_err();
        assert!(
            one.to_string().contains("names one file for 2 inputs"),
            "{one}"
        );
        let input = names(&Output::Pattern("s/f_{frame}.ply".into())).unwrap_err();
        assert!(
            input.to_string().contains("would overwrite the input"),
            "{input}"
        );
        let both = ["s/a_1.ply", "t/a_1.ply"].map(PathBuf::from);
        let clash = output_paths(&both, &Output::Directory("m".into()), "mesh", "", "obj");
        assert!(
            clash
                .unwrap_err()
                .to_string()
                .contains("would both be written to m/a_0001.obj")
        );
    }
}
