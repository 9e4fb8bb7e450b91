//! The options of `splash_sph::OPTIONS` as every front end offers them (issue 41): the command
//! line's flags (clap's own definitions), the Python keyword arguments (the type stub, which
//! mypy's stubtest checks against the built module, and the docstrings of the Rust source),
//! and the Blender add-on's settings (blender/splash_blender/settings.py, read as text).
//!
//! A front end must offer each option the table names for it, under that name, and no option
//! the table says it lacks; each thing it offers is either an option or on the short lists of
//! other parameters below. Types: a flag takes no value on the command line; the stub's
//! annotation is the one of the option's kind; a Blender setting has the property type of the
//! kind, and a choice has exactly the table's names (Python `Literal`s too). Defaults: no flag
//! has a clap default (the configuration's holds, which the library's test compares with the
//! table), every Python keyword defaults to None (the same), and the Blender render settings
//! (`RENDER_DEFAULTS`) are the table's defaults. Help texts are compared after collapsing
//! whitespace: the first paragraph of a flag's help is the table's help (a full stop may
//! follow), a Python docstring has ``` ``keyword``: ``` followed by it, and a Blender
//! description starts with it. An `Adapted` spelling is checked for its presence only.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use clap::CommandFactory;
use splash_sph::{OPTIONS, OptionSpec, OptionValue, Spelling};

/// The flags of `splash config show` that are not options of the table.
const CLI_OTHERS: &[(&str, &str)] = &[
    ("config", "the configuration file the options go on top of"),
    (
        "particle-radius",
        "the spacing as half of it: r = 2 × radius",
    ),
];

/// A Python function that takes the options.
struct PythonFunction {
    name: &'static str,
    /// Its parameters that are not options.
    others: &'static [&'static str],
    /// The options it lacks, and why.
    lacks: &'static [(&'static str, &'static str)],
}

/// The Python functions that take the options.
const PYTHON_FUNCTIONS: &[PythonFunction] = &[
    PythonFunction {
        name: "recon_sequence",
        others: &[
            "inputs",
            "output",
            "progress",
            "frames",
            "shard",
            "skip_existing",
            "fail_fast",
            "input_format",
            "config",
        ],
        lacks: &[],
    },
    PythonFunction {
        name: "config_toml",
        others: &["config"],
        lacks: &[],
    },
    PythonFunction {
        name: "reconstruct",
        others: &["positions", "config", "attributes", "ids", "neighbours"],
        lacks: &[
            ("particle_aabb", "it takes an array of positions: filter it"),
            (
                "format",
                "Mesh.write takes it (and the config's output.format)",
            ),
            (
                "up_axis",
                "Mesh.write takes it (and the config's output.up_axis)",
            ),
            (
                "attributes",
                "its `attributes` are arrays by name, not names",
            ),
            (
                "temporal",
                "one frame has no neighbouring frames: its `ids` and `neighbours` make it follow them",
            ),
        ],
    },
];

/// Settings of the add-on's live mode that are not options.
const BLENDER_OTHERS: &[&str] = &[
    "enabled",
    "source",
    "cache_mb",
    "viewport",
    "render",
    "input_path",
    "output_path",
    "status",
    "error",
    "use_decimate",
    "use_min_component",
];

fn read(path: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Whitespace collapsed to single spaces.
fn normalise(text: &str) -> String {
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The text up to the bracket that closes the one just before `text` starts, aware of
/// brackets and of string literals.
fn until_close(text: &str) -> &str {
    let mut depth = 0usize;
    let mut quote: Option<char> = None;
    for (i, c) in text.char_indices() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '"' | '\'') => quote = Some(c),
            (None, '(' | '[' | '{') => depth += 1,
            (None, ')' | ']' | '}') if depth == 0 => return &text[..i],
            (None, ')' | ']' | '}') => depth -= 1,
            _ => {}
        }
    }
    panic!("unclosed bracket before {:.60}", text)
}

/// Splits at the commas outside brackets and strings.
fn split_top(text: &str) -> Vec<String> {
    let (mut out, mut current, mut depth, mut quote) = (Vec::new(), String::new(), 0, None);
    for c in text.chars() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '"' | '\'') => quote = Some(c),
            (None, '(' | '[' | '{') => depth += 1,
            (None, ')' | ']' | '}') => depth -= 1,
            (None, ',') if depth == 0 => {
                out.push(std::mem::take(&mut current));
                continue;
            }
            _ => {}
        }
        current.push(c);
    }
    out.push(current);
    out.into_iter()
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
        .collect()
}

/// The adjacent string literals at the start of `text`, joined (Python's implicit
/// concatenation; no escapes).
fn string_literals(text: &str) -> String {
    let mut out = String::new();
    let mut rest = text.trim_start();
    while let Some(body) = rest.strip_prefix('"') {
        let end = body.find('"').expect("a closed string");
        out.push_str(&body[..end]);
        rest = body[end + 1..].trim_start();
    }
    out
}

fn choices(value: OptionValue) -> Option<BTreeSet<String>> {
    match value {
        OptionValue::Choice(names) => Some(names.iter().map(|n| n.to_string()).collect()),
        _ => None,
    }
}

/// Where `name` of front end `what` differs from the table's entry `o`, if it does: a name
/// that the table gives and the front end lacks, or the other way round.
fn presence(
    problems: &mut Vec<String>,
    what: &str,
    spelling: Spelling,
    has: impl Fn(&str) -> bool,
    o: &OptionSpec,
) {
    match spelling {
        Spelling::Named(n) | Spelling::Adapted(n, _) if !has(n) => {
            problems.push(format!("{what} lacks option {} (as {n})", o.name))
        }
        Spelling::Absent(why) if has(o.name) || has(&o.name.replace('_', "-")) => {
            problems.push(format!(
                "{what} has {} though the table says it has none ({why})",
                o.name
            ))
        }
        _ => {}
    }
}

fn cli(problems: &mut Vec<String>) {
    let mut cli = crate::Cli::command();
    cli.build();
    let show = cli
        .find_subcommand("config")
        .and_then(|c| c.find_subcommand("show"))
        .expect("splash config show");
    let recon = cli.find_subcommand("recon").expect("splash recon");
    let args: BTreeMap<&str, &clap::Arg> = show
        .get_arguments()
        .filter_map(|a| a.get_long().map(|l| (l, a)))
        .filter(|(l, _)| *l != "help")
        .collect();
    for flag in args.keys() {
        let option = OPTIONS.iter().any(|o| o.cli.name() == Some(flag));
        if !option && !CLI_OTHERS.iter().any(|(f, _)| f == flag) {
            problems.push(format!(
                "--{flag} is neither an option of the table nor one of CLI_OTHERS"
            ));
        }
    }
    for o in OPTIONS {
        presence(
            problems,
            "the command line",
            o.cli,
            |n| args.contains_key(n),
            o,
        );
        let Spelling::Named(flag) = o.cli else {
            continue;
        };
        let Some(arg) = args.get(flag) else { continue };
        if !recon.get_arguments().any(|a| a.get_long() == Some(flag)) {
            problems.push(format!("splash recon lacks --{flag}"));
        }
        let help = arg
            .get_help()
            .map(|h| normalise(&h.to_string()))
            .unwrap_or_default();
        if help.trim_end_matches('.') != normalise(o.help) {
            problems.push(format!(
                "--{flag}'s help is \"{help}\", the table's \"{}\"",
                o.help
            ));
        }
        let long = arg.get_long_help().map(|h| normalise(&h.to_string()));
        if long
            .as_ref()
            .is_some_and(|l| !l.starts_with(&normalise(o.help)))
        {
            problems.push(format!(
                "--{flag}'s long help does not start with the table's help"
            ));
        }
        // A switch's implicit false leaves the configuration's value (only true overrides it).
        let defaults: Vec<_> = arg.get_default_values().iter().collect();
        let switch_off = o.value == OptionValue::Flag && defaults == ["false"];
        if !defaults.is_empty() && !switch_off {
            problems.push(format!(
                "--{flag} has a default of its own: the configuration's must hold"
            ));
        }
        let takes_value = arg.get_num_args().is_some_and(|n| n.takes_values());
        if takes_value == (o.value == OptionValue::Flag) {
            problems.push(format!(
                "--{flag}: a flag takes no value, other options one"
            ));
        }
    }
}

/// The parameters of the stub's function `name`: (name, annotation, default).
fn stub_parameters(stub: &str, name: &str) -> Vec<(String, String, String)> {
    let start = stub
        .find(&format!("\ndef {name}("))
        .unwrap_or_else(|| panic!("no def {name} in the stub"));
    let open = start + stub[start..].find('(').unwrap() + 1;
    split_top(until_close(&stub[open..]))
        .into_iter()
        .filter(|p| p != "*" && p != "/")
        .map(|p| {
            let (head, default) = p.split_once(" = ").unwrap_or((&p, ""));
            let (name, annotation) = head.split_once(':').unwrap_or((head, ""));
            (
                name.trim().into(),
                normalise(annotation),
                default.trim().into(),
            )
        })
        .collect()
}

/// The stub's annotations for each kind of value.
fn python_types(value: OptionValue) -> Vec<String> {
    let fixed = match value {
        OptionValue::Flag => "Optional[bool]",
        OptionValue::Count => "Optional[int]",
        OptionValue::Number => "Optional[float]",
        OptionValue::Length => "Union[str, float, None]",
        OptionValue::Bytes => "Union[str, int, None]",
        OptionValue::Box => "Optional[Sequence[float]]",
        OptionValue::Names => "Union[str, Sequence[str], None]",
        OptionValue::Choice(names) => {
            let quoted: Vec<String> = names.iter().map(|n| format!("\"{n}\"")).collect();
            return vec![
                "Optional[str]".into(),
                format!("Optional[Literal[{}]]", quoted.join(", ")),
            ];
        }
    };
    vec![fixed.into()]
}

/// The doc comments of the Python crate's sources, as one text.
fn rust_docstrings() -> String {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/splash-py/src");
    let mut text = String::new();
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    for file in files {
        for line in std::fs::read_to_string(file).unwrap().lines() {
            if let Some(doc) = line.trim_start().strip_prefix("///") {
                text.push_str(doc);
                text.push('\n');
            }
        }
    }
    normalise(&text)
}

fn python(problems: &mut Vec<String>) {
    let stub = read("crates/splash-py/python/splash_sph/_native.pyi");
    let docs = [
        ("the stub", normalise(&stub)),
        ("the Python crate's doc comments", rust_docstrings()),
    ];
    for PythonFunction {
        name: function,
        others,
        lacks,
    } in PYTHON_FUNCTIONS
    {
        let params = stub_parameters(&stub, function);
        let what = format!("Python's {function}");
        for (name, annotation, default) in &params {
            let option = OPTIONS.iter().find(|o| o.python.name() == Some(name));
            if others.contains(&name.as_str()) {
                continue;
            }
            let Some(o) = option else {
                problems.push(format!("{what}'s {name} is neither an option of the table nor one of its other parameters"));
                continue;
            };
            if lacks.iter().any(|(n, _)| n == &o.name) {
                problems.push(format!(
                    "{what} has {name}, which PYTHON_FUNCTIONS says it lacks"
                ));
            }
            if default != "None" {
                problems.push(format!(
                    "{what}'s {name} defaults to {default}, not None (the configuration's)"
                ));
            }
            if let Spelling::Named(_) = o.python
                && !python_types(o.value).contains(annotation)
            {
                problems.push(format!(
                    "{what}'s {name}: {annotation}, not {:?}",
                    python_types(o.value)
                ));
            }
        }
        for o in OPTIONS {
            let lacked = lacks.iter().any(|(n, _)| n == &o.name);
            let has = |n: &str| params.iter().any(|(p, ..)| p == n);
            if lacked {
                continue;
            }
            presence(problems, &what, o.python, has, o);
        }
    }
    for o in OPTIONS {
        let Spelling::Named(keyword) = o.python else {
            continue;
        };
        let entry = format!("``{keyword}``: {}", normalise(o.help));
        for (where_, text) in &docs {
            if !text.contains(&entry) {
                problems.push(format!("{where_} lacks \"{entry}\""));
            }
        }
    }
}

/// A Blender property: its type and its arguments' text.
struct Property {
    kind: String,
    args: String,
}

impl Property {
    fn arg(&self, name: &str) -> Option<String> {
        split_top(&self.args)
            .into_iter()
            .find_map(|a| a.strip_prefix(&format!("{name}=")).map(str::to_string))
    }
}

/// The properties of settings.py between `def _quality` and the sequence's group (the live
/// settings and the two quality groups): `name: XProperty(` or `"name": XProperty(`.
fn blender_properties(settings: &str) -> BTreeMap<String, Property> {
    let from = settings
        .find("def _quality")
        .expect("_quality in settings.py");
    let to = settings
        .find("class SPLASH_PG_sequence")
        .expect("SPLASH_PG_sequence");
    let text = &settings[from..to];
    let mut out = BTreeMap::new();
    for (i, _) in text.match_indices("Property(") {
        let line_start = text[..i].rfind('\n').map_or(0, |n| n + 1);
        let head = text[line_start..i].trim();
        let Some((name, kind)) = head.split_once(':') else {
            continue;
        };
        let name = name.trim().trim_matches('"').to_string();
        let kind = format!("{}Property", kind.trim());
        let args = until_close(&text[i + "Property(".len()..]).to_string();
        out.insert(name, Property { kind, args });
    }
    out
}

/// The ids of a list of enum items `NAME = [("id", …), …]` of settings.py.
fn enum_ids(settings: &str, list: &str) -> BTreeSet<String> {
    let start = settings
        .find(&format!("\n{list} = ["))
        .unwrap_or_else(|| panic!("no {list} in settings.py"));
    let open = start + settings[start..].find('[').unwrap() + 1;
    split_top(until_close(&settings[open..]))
        .iter()
        .map(|item| {
            let item = item.trim_start_matches('(');
            string_literals(item)
        })
        .collect()
}

/// The dict literal `NAME = {…}` of settings.py: key -> value as written.
fn dict_literal(settings: &str, name: &str) -> BTreeMap<String, String> {
    let start = settings
        .find(&format!("\n{name} = {{"))
        .unwrap_or_else(|| panic!("no {name} in settings.py"));
    let open = start + settings[start..].find('{').unwrap() + 1;
    split_top(until_close(&settings[open..]))
        .iter()
        .filter_map(|entry| {
            let (k, v) = entry.split_once(':')?;
            Some((k.trim().trim_matches('"').to_string(), v.trim().to_string()))
        })
        .collect()
}

fn blender(problems: &mut Vec<String>) {
    let settings = read("blender/splash_blender/settings.py");
    let command = read("blender/splash_blender/command.py");
    let function = |name: &str| {
        let start = command
            .find(&format!("\ndef {name}("))
            .expect("in command.py");
        let end = command[start + 1..]
            .find("\ndef ")
            .map_or(command.len(), |e| start + 1 + e);
        command[start..end].to_string()
    };
    let (to_command, from_command) = (function("to_command"), function("from_command"));
    let properties = blender_properties(&settings);
    let defaults = dict_literal(&settings, "RENDER_DEFAULTS");
    for name in properties.keys() {
        let option = OPTIONS
            .iter()
            .any(|o| o.blender.name() == Some(name.as_str()));
        if !option && !BLENDER_OTHERS.contains(&name.as_str()) {
            problems.push(format!(
                "Blender's {name} is neither an option of the table nor one of BLENDER_OTHERS"
            ));
        }
    }
    for o in OPTIONS {
        presence(
            problems,
            "Blender",
            o.blender,
            |n| properties.contains_key(n),
            o,
        );
        // What the panel has, its copied command line carries, and a pasted one sets.
        if let (Some(_), Some(flag)) = (o.blender.name(), o.cli.name()) {
            if !to_command.contains(&format!("\"--{flag}")) {
                problems.push(format!(
                    "Blender's command.to_command never writes --{flag}"
                ));
            }
            let named = matches!(o.blender, Spelling::Named(_));
            if named && !from_command.contains(&format!("== \"--{flag}\"")) {
                problems.push(format!(
                    "Blender's command.from_command never reads --{flag}"
                ));
            }
        }
        let Spelling::Named(name) = o.blender else {
            continue;
        };
        let Some(p) = properties.get(name) else {
            continue;
        };
        let description = p
            .arg("description")
            .map(|d| normalise(&string_literals(&d)));
        if !description
            .as_ref()
            .is_some_and(|d| d.starts_with(&normalise(o.help)))
        {
            problems.push(format!(
                "Blender's {name}: description {description:?} does not start with the table's \"{}\"",
                o.help
            ));
        }
        let kinds: &[&str] = match o.value {
            OptionValue::Flag => &["BoolProperty"],
            OptionValue::Count => &["IntProperty"],
            OptionValue::Number => &["FloatProperty"],
            OptionValue::Length => &["StringProperty", "FloatProperty"],
            OptionValue::Choice(_) => &["EnumProperty"],
            OptionValue::Bytes | OptionValue::Box | OptionValue::Names => &["StringProperty"],
        };
        if !kinds.contains(&p.kind.as_str()) {
            problems.push(format!(
                "Blender's {name} is a {}, not one of {kinds:?}",
                p.kind
            ));
        }
        if let Some(want) = choices(o.value) {
            let ids = p.arg("items").map(|list| enum_ids(&settings, &list));
            if ids.as_ref() != Some(&want) {
                problems.push(format!(
                    "Blender's {name}: items {ids:?}, the table's {want:?}"
                ));
            }
        }
        if !o.default.is_empty() {
            let python = defaults.get(name).map(|v| match v.as_str() {
                "True" => "true".to_string(),
                "False" => "false".to_string(),
                v => v.to_string(),
            });
            if python.as_deref() != Some(o.default) {
                problems.push(format!(
                    "Blender's RENDER_DEFAULTS[{name:?}] is {python:?}, the table's default {}",
                    o.default
                ));
            }
            if p.arg("default").as_deref() != Some(&format!("d[\"{name}\"]")) {
                problems.push(format!(
                    "Blender's {name} does not take its default from the group's defaults"
                ));
            }
        }
    }
}

/// Every front end offers the table's options, with its types, defaults and help texts.
#[test]
fn every_front_end_offers_the_options_of_the_table() {
    let mut problems = Vec::new();
    cli(&mut problems);
    python(&mut problems);
    blender(&mut problems);
    let names: BTreeSet<&str> = OPTIONS.iter().map(|o| o.name).collect();
    assert_eq!(names.len(), OPTIONS.len(), "option names repeat");
    assert!(
        problems.is_empty(),
        "splash_sph::OPTIONS and the front ends differ:\n{}",
        problems.join("\n")
    );
}
