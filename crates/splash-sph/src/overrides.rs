//! Values put on top of a configuration: the command line's flags over `--config`, the Python
//! keyword arguments over `config=`, the Blender panel's settings, through this one rule; and
//! [`OPTIONS`], the one table of these options that every front end is checked against
//! (the command line's `options_table` test: names, types, defaults and help texts).

use crate::bytes::Bytes;
use crate::config::{Config, Engine, Normals, OutputConfig, parse_aabb};
use crate::data::{MeshFormat, UpAxis};
use crate::error::{Error, Result};
use crate::field::FieldConfig;
use crate::length::Length;
use crate::mesh::VolumeScope;

/// Settings that replace a configuration's; None (or an empty `attributes`) keeps its value.
/// The callers parse them, so that their errors name the flag or argument. One field per
/// entry of [`OPTIONS`], of the same name.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Overrides {
    /// A field kind (`ssp07`, …): a different kind than the configuration's gets its defaults,
    /// the same kind keeps the parameters the configuration gives it.
    pub field: Option<String>,
    /// `spacing`: the particle spacing r.
    pub spacing: Option<f32>,
    /// `cell`: the Marching Cubes cell.
    pub cell: Option<Length>,
    /// `normals`.
    pub normals: Option<Normals>,
    /// `correct`: Newton steps of the correction.
    pub correct: Option<u32>,
    /// `slices.block`.
    pub block: Option<u32>,
    /// `engine`.
    pub engine: Option<Engine>,
    /// `threads` (at least 1).
    pub threads: Option<usize>,
    /// `max_memory`.
    pub max_memory: Option<Bytes>,
    /// `output.format`.
    pub format: Option<MeshFormat>,
    /// `output.up_axis`.
    pub up_axis: Option<UpAxis>,
    /// `output.attributes`.
    pub attributes: Option<Vec<String>>,
    /// `particle_aabb`.
    pub particle_aabb: Option<[f32; 6]>,
    /// `post.raw`: the field's exact isosurface, without post-processing.
    pub raw: Option<bool>,
    /// `post.mesh_aabb`.
    pub mesh_aabb: Option<[f32; 6]>,
    /// `post.min_component`, in particle volumes r³.
    pub min_component: Option<f64>,
    /// `post.decimate`.
    pub decimate: Option<Length>,
    /// `post.temporal`: surfaces that follow the fluid from frame to frame in a sequence.
    pub temporal: Option<bool>,
    /// `post.volume_scope`: what the volume restoration brings to N·r³.
    pub volume_scope: Option<VolumeScope>,
}

/// What a front end calls an option of [`OPTIONS`], or why it has none.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Spelling {
    /// Under this name (a long flag without its `--`, a keyword argument, a property), with
    /// the table's type, default and help text.
    Named(&'static str),
    /// Under this name, in a form of the front end's own (the reason): only its presence is
    /// checked.
    Adapted(&'static str, &'static str),
    /// Not offered, for this reason.
    Absent(&'static str),
}

impl Spelling {
    /// The name, unless the option is absent.
    pub fn name(self) -> Option<&'static str> {
        match self {
            Spelling::Named(n) | Spelling::Adapted(n, _) => Some(n),
            Spelling::Absent(_) => None,
        }
    }
}

/// The kind of value an option takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OptionValue {
    /// On or off.
    Flag,
    /// A whole number from 0.
    Count,
    /// A number.
    Number,
    /// A length: `2r`, `r/2`, `0.5r` … or a number in world units.
    Length,
    /// A size in bytes: `8G`, `512M` or a number.
    Bytes,
    /// One of these names.
    Choice(&'static [&'static str]),
    /// A box: six numbers, min x, min y, min z, max x, max y, max z.
    Box,
    /// Attribute names.
    Names,
}

/// One option that the front ends put on top of a configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OptionSpec {
    /// Its field of [`Overrides`] and its name in [`Overrides::set`].
    pub name: &'static str,
    /// Its key in the configuration (`post.volume_scope`: `volume_scope` of `[post]`).
    pub key: &'static str,
    /// The command line's flag (`splash recon`, `splash iso`, `splash config show`).
    pub cli: Spelling,
    /// The Python keyword argument (`recon_sequence` and `config_toml`; `reconstruct` too
    /// but for the options of files and sequences).
    pub python: Spelling,
    /// The Blender add-on's setting (blender/splash_blender/settings.py).
    pub blender: Spelling,
    /// What it takes.
    pub value: OptionValue,
    /// Its value in the default configuration, as `splash config show` writes it (TOML), or
    /// empty for a key that is absent by default.
    pub default: &'static str,
    /// One line that every front end's help for it starts with (the Python docstrings: after
    /// ``` ``keyword``: ```), whitespace aside.
    pub help: &'static str,
}

/// Every option of [`Overrides`], as each front end offers it.
pub const OPTIONS: &[OptionSpec] = &[
    OptionSpec {
        name: "field",
        key: "field.kind",
        cli: Spelling::Named("field"),
        python: Spelling::Named("field"),
        blender: Spelling::Named("field"),
        value: OptionValue::Choice(&FieldConfig::KINDS),
        default: "\"ssp07\"",
        help: "Scalar field: ssp07, zb05, density, blobby, metaball or anisotropic, with its \
               default parameters unless the configuration gives the same kind",
    },
    OptionSpec {
        name: "spacing",
        key: "spacing",
        cli: Spelling::Named("spacing"),
        python: Spelling::Named("spacing"),
        blender: Spelling::Adapted(
            "spacing",
            "0 stands for none: estimated once from the current frame and kept",
        ),
        value: OptionValue::Number,
        default: "",
        help: "Particle spacing r, the simulator's equilibrium distance between particles",
    },
    OptionSpec {
        name: "cell",
        key: "cell",
        cli: Spelling::Named("cell"),
        python: Spelling::Named("cell"),
        blender: Spelling::Named("cell"),
        value: OptionValue::Length,
        default: "\"r/2\"",
        help: "Marching Cubes cell size: 2r, r, r/2, r/N, Kr or a length; at most 4r",
    },
    OptionSpec {
        name: "normals",
        key: "normals",
        cli: Spelling::Named("normals"),
        python: Spelling::Named("normals"),
        blender: Spelling::Named("normals"),
        value: OptionValue::Choice(&["field", "grid", "none"]),
        default: "\"field\"",
        help: "Vertex normals: field (the field's gradient), grid (differences of the sampled \
               grid: faster) or none",
    },
    OptionSpec {
        name: "correct",
        key: "correct",
        cli: Spelling::Named("correct"),
        python: Spelling::Named("correct"),
        blender: Spelling::Named("correct"),
        value: OptionValue::Count,
        default: "0",
        help: "Newton steps moving each vertex along its cube edge onto the field's exact \
               isosurface (Marching Correctors); 0 keeps Marching Cubes' linear interpolation",
    },
    OptionSpec {
        name: "block",
        key: "slices.block",
        cli: Spelling::Named("block"),
        python: Spelling::Named("block"),
        blender: Spelling::Absent(
            "a tuning of the slices engine's memory per block, of no use in a live viewport",
        ),
        value: OptionValue::Count,
        default: "64",
        help: "Cubes per side of a block of the slices engine",
    },
    OptionSpec {
        name: "engine",
        key: "engine",
        cli: Spelling::Named("engine"),
        python: Spelling::Named("engine"),
        blender: Spelling::Named("engine"),
        value: OptionValue::Choice(&["narrow-band", "full-gather", "scatter", "slices"]),
        default: "\"narrow-band\"",
        help: "Reconstruction engine: narrow-band, full-gather, scatter or slices",
    },
    OptionSpec {
        name: "threads",
        key: "threads",
        cli: Spelling::Named("threads"),
        python: Spelling::Named("threads"),
        blender: Spelling::Absent(
            "live mode works in Blender's process, on every core, between two redraws",
        ),
        value: OptionValue::Count,
        default: "",
        help: "Worker threads, all cores when not given; the mesh does not depend on it",
    },
    OptionSpec {
        name: "max_memory",
        key: "max_memory",
        cli: Spelling::Named("max-memory"),
        python: Spelling::Named("max_memory"),
        blender: Spelling::Absent(
            "live mode reconstructs one frame in Blender's memory; a farm job sets it",
        ),
        value: OptionValue::Bytes,
        default: "",
        help: "Heap a frame may plan to use, e.g. 8G or 512M: every engine refuses a frame \
               that needs more",
    },
    OptionSpec {
        name: "format",
        key: "output.format",
        cli: Spelling::Named("format"),
        python: Spelling::Named("format"),
        blender: Spelling::Absent(
            "live mode makes a Blender mesh; the copied command line writes PLY with \
             velocities, else OBJ",
        ),
        value: OptionValue::Choice(&[
            "obj",
            "ply",
            "ply-ascii",
            "pov",
            "vtk",
            "vtu",
            "vtp",
            "usd",
            "vdb",
        ]),
        default: "",
        help: "Mesh format: obj, ply, ply-ascii, pov, vtk, vtu, vtp, usd or vdb; from the \
               output's extension when not given, else obj",
    },
    OptionSpec {
        name: "up_axis",
        key: "output.up_axis",
        cli: Spelling::Named("up-axis"),
        python: Spelling::Named("up_axis"),
        blender: Spelling::Absent(
            "the live surface is made in the particle object's space, which Blender turns; \
             an imported sequence has its files' up axis",
        ),
        value: OptionValue::Choice(&["y", "z"]),
        default: "",
        help: "Rotate the mesh on output: z turns Y-up data Z-up, y turns Z-up data Y-up",
    },
    OptionSpec {
        name: "attributes",
        key: "output.attributes",
        cli: Spelling::Named("attributes"),
        python: Spelling::Named("attributes"),
        blender: Spelling::Adapted(
            "velocity",
            "a switch: the particles' velocity only, for motion blur",
        ),
        value: OptionValue::Names,
        default: "[]",
        help: "Particle attributes interpolated onto the mesh's vertices, by name (velocity, \
               density, …)",
    },
    OptionSpec {
        name: "particle_aabb",
        key: "particle_aabb",
        cli: Spelling::Named("particle-aabb"),
        python: Spelling::Named("particle_aabb"),
        blender: Spelling::Absent(
            "the particle object's vertices are the particles: Blender masks or deletes them",
        ),
        value: OptionValue::Box,
        default: "",
        help: "Drop the particles outside this box (min x, min y, min z, max x, max y, max z) \
               before reconstructing",
    },
    OptionSpec {
        name: "raw",
        key: "post.raw",
        cli: Spelling::Named("raw"),
        python: Spelling::Named("raw"),
        blender: Spelling::Named("raw"),
        value: OptionValue::Flag,
        default: "false",
        help: "Keep the field's exact isosurface: no smoothing and no volume restoration",
    },
    OptionSpec {
        name: "mesh_aabb",
        key: "post.mesh_aabb",
        cli: Spelling::Named("mesh-aabb"),
        python: Spelling::Named("mesh_aabb"),
        blender: Spelling::Adapted(
            "clip_object",
            "an object whose bounding box, in the particle object's space, is the box",
        ),
        value: OptionValue::Box,
        default: "",
        help: "Keep only the mesh inside this box (min x, min y, min z, max x, max y, max z); \
               the cuts are capped, so it stays closed",
    },
    OptionSpec {
        name: "min_component",
        key: "post.min_component",
        cli: Spelling::Named("min-component"),
        python: Spelling::Named("min_component"),
        blender: Spelling::Named("min_component"),
        value: OptionValue::Number,
        default: "",
        help: "Drop the parts of the mesh enclosing less than this many particle volumes r³",
    },
    OptionSpec {
        name: "decimate",
        key: "post.decimate",
        cli: Spelling::Named("decimate"),
        python: Spelling::Named("decimate"),
        blender: Spelling::Named("decimate"),
        value: OptionValue::Length,
        default: "",
        help: "Decimate with quadric edge collapses, keeping every vertex and triangle centre \
               within this distance of the full surface",
    },
    OptionSpec {
        name: "temporal",
        key: "post.temporal",
        cli: Spelling::Named("temporal"),
        python: Spelling::Named("temporal"),
        blender: Spelling::Named("temporal"),
        value: OptionValue::Flag,
        default: "false",
        help: "In a sequence, average each frame's field and surface with its neighbouring \
               frames' carried by the fluid's motion (experimental)",
    },
    OptionSpec {
        name: "volume_scope",
        key: "post.volume_scope",
        cli: Spelling::Named("volume-scope"),
        python: Spelling::Named("volume_scope"),
        blender: Spelling::Named("volume_scope"),
        value: OptionValue::Choice(&["frame", "component"]),
        default: "\"frame\"",
        help: "What the volume restoration brings to N·r³: frame (the whole mesh, one offset) \
               or component (each closed part to its own particles)",
    },
];

/// The entry of [`OPTIONS`] named `name`.
///
/// # Panics
/// When there is none: names are the program's, not the user's.
pub fn option(name: &str) -> &'static OptionSpec {
    OPTIONS
        .iter()
        .find(|o| o.name == name)
        .unwrap_or_else(|| panic!("no option '{name}' in OPTIONS"))
}

impl Overrides {
    /// Sets the option `name` (an [`OPTIONS`] name) from text, as the command line gives it:
    /// `true` or `false` for a flag, six comma-separated numbers for a box, comma-separated
    /// names for attributes.
    pub fn set(&mut self, name: &str, text: &str) -> Result<()> {
        fn number<T: std::str::FromStr>(text: &str, what: &str) -> Result<T> {
            text.trim()
                .parse()
                .map_err(|_| Error::config(format!("'{text}' is not {what}")))
        }
        let flag = |text: &str| number::<bool>(text, "true or false");
        match name {
            "field" => self.field = Some(text.trim().to_string()),
            "spacing" => self.spacing = Some(number(text, "a number")?),
            "cell" => self.cell = Some(Length::parse(text)?),
            "normals" => self.normals = Some(Normals::parse(text)?),
            "correct" => self.correct = Some(number(text, "a count")?),
            "block" => self.block = Some(number(text, "a count")?),
            "engine" => self.engine = Some(Engine::parse(text)?),
            "threads" => self.threads = Some(number(text, "a count")?),
            "max_memory" => self.max_memory = Some(Bytes::parse(text)?),
            "format" => self.format = Some(MeshFormat::parse(text)?),
            "up_axis" => self.up_axis = Some(UpAxis::parse(text)?),
            "attributes" => self.attributes = Some(OutputConfig::parse_attributes(text)?),
            "particle_aabb" => self.particle_aabb = Some(parse_aabb(text)?),
            "raw" => self.raw = Some(flag(text)?),
            "mesh_aabb" => self.mesh_aabb = Some(parse_aabb(text)?),
            "min_component" => self.min_component = Some(number(text, "a number")?),
            "decimate" => self.decimate = Some(Length::parse(text)?),
            "temporal" => self.temporal = Some(flag(text)?),
            "volume_scope" => self.volume_scope = Some(VolumeScope::parse(text)?),
            _ => return Err(Error::config(format!("no option '{name}'"))),
        }
        Ok(())
    }
}

impl Config {
    /// The configuration with `overrides` on top, validated.
    pub fn apply(mut self, o: &Overrides) -> Result<Config> {
        if let Some(kind) = &o.field
            && self.field.kind() != kind
        {
            self.field = FieldConfig::named(kind)?;
        }
        self.spacing = o.spacing.or(self.spacing);
        self.cell = o.cell.unwrap_or(self.cell);
        self.normals = o.normals.unwrap_or(self.normals);
        self.correct = o.correct.unwrap_or(self.correct);
        self.slices.block = o.block.unwrap_or(self.slices.block);
        self.engine = o.engine.unwrap_or(self.engine);
        self.threads = o.threads.or(self.threads);
        self.max_memory = o.max_memory.or(self.max_memory);
        self.output.format = o.format.or(self.output.format);
        self.output.up_axis = o.up_axis.or(self.output.up_axis);
        if let Some(a) = &o.attributes {
            self.output.attributes = a.clone();
        }
        self.particle_aabb = o.particle_aabb.or(self.particle_aabb);
        self.post.raw = o.raw.unwrap_or(self.post.raw);
        self.post.mesh_aabb = o.mesh_aabb.or(self.post.mesh_aabb);
        self.post.min_component = o.min_component.or(self.post.min_component);
        self.post.decimate = o.decimate.or(self.post.decimate);
        self.post.temporal = o.temporal.unwrap_or(self.post.temporal);
        self.post.volume_scope = o.volume_scope.unwrap_or(self.post.volume_scope);
        self.validate()?;
        Ok(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The value at a dotted `key` of `config` as `splash config show` writes it, or "".
    fn shown(config: &Config, key: &str) -> String {
        let table: toml::Table = toml::from_str(&config.to_toml()).unwrap();
        let mut value = Some(toml::Value::Table(table));
        for part in key.split('.') {
            value = value.and_then(|v| v.get(part).cloned());
        }
        value.map_or_else(String::new, |v| v.to_string())
    }

    /// A value of each kind that no default has.
    fn example(value: OptionValue, default: &str) -> String {
        match value {
            OptionValue::Flag => "true".into(),
            OptionValue::Count => "3".into(),
            OptionValue::Number => "0.5".into(),
            OptionValue::Length => "r".into(),
            OptionValue::Bytes => "2G".into(),
            OptionValue::Box => "0,0,0,1,1,1".into(),
            OptionValue::Names => "velocity".into(),
            OptionValue::Choice(names) => names
                .iter()
                .find(|n| format!("\"{n}\"") != default)
                .unwrap()
                .to_string(),
        }
    }

    #[test]
    fn the_table_has_every_override_with_the_configurations_default_and_each_reaches_its_key() {
        // Overrides' fields, in order, from its Debug form.
        let debug = format!("{:?}", Overrides::default());
        let fields: Vec<&str> = debug
            .trim_start_matches("Overrides { ")
            .trim_end_matches(" }")
            .split(", ")
            .map(|f| f.split(':').next().unwrap())
            .collect();
        let names: Vec<&str> = OPTIONS.iter().map(|o| o.name).collect();
        assert_eq!(fields, names, "Overrides' fields and OPTIONS differ");
        let defaults = Config::default();
        for o in OPTIONS {
            assert_eq!(shown(&defaults, o.key), o.default, "{}: default", o.name);
            assert!(
                !o.help.contains("  ") && !o.help.ends_with('.') && !o.help.contains('\n'),
                "{}: help is one line without a full stop",
                o.name
            );
            if let OptionValue::Choice(names) = o.value {
                for n in names {
                    Overrides::default().set(o.name, n).unwrap();
                }
            }
            let mut set = Overrides::default();
            let text = example(o.value, o.default);
            set.set(o.name, &text).unwrap();
            assert_ne!(set, Overrides::default(), "{}: set", o.name);
            let config = Config::default().apply(&set).unwrap();
            assert_ne!(
                shown(&config, o.key),
                o.default,
                "{} = {text} does not reach {}",
                o.name,
                o.key
            );
            if !matches!(o.name, "field" | "attributes") {
                assert!(Overrides::default().set(o.name, "?").is_err(), "{}", o.name);
            }
        }
        assert!(Overrides::default().set("fields", "ssp07").is_err());
        assert_eq!(
            option("engine").value,
            OptionValue::Choice(&["narrow-band", "full-gather", "scatter", "slices"])
        );
        assert_eq!(
            Engine::ALL.map(Engine::name),
            ["narrow-band", "full-gather", "scatter", "slices"]
        );
    }

    #[test]
    fn overrides_replace_only_what_they_give_and_a_field_of_the_same_kind_keeps_its_keys() {
        let config = Config::from_toml(
            "spacing = 0.02\nthreads = 3\n[field]\nkind = \"blobby\"\nblobbiness = 3.0\n",
        )
        .unwrap();
        assert_eq!(config.clone().apply(&Overrides::default()).unwrap(), config);
        let same_kind = Overrides {
            field: Some("blobby".into()),
            spacing: Some(0.05),
            ..Overrides::default()
        };
        let c = config.clone().apply(&same_kind).unwrap();
        assert_eq!((c.spacing, c.threads), (Some(0.05), Some(3)));
        assert_eq!(c.field, config.field);
        let other = Overrides {
            field: Some("metaball".into()),
            ..Overrides::default()
        };
        let c = config.clone().apply(&other).unwrap();
        assert_eq!(c.field, FieldConfig::named("metaball").unwrap());
        let zero = Overrides {
            threads: Some(0),
            ..Overrides::default()
        };
        assert!(config.apply(&zero).is_err());
    }
}
