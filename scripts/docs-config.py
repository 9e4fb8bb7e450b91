#!/usr/bin/env python3
"""Writes the configuration reference (Markdown) from the configuration types themselves.

Keys and their nesting come from the serde structs of crates/splash-sph (`Config` and the
types of its fields), descriptions from their doc comments, defaults from `splash config show`
(the serialised `Config::default()`, once per field kind). A key without a doc comment, a key
that the CLI prints but no struct declares, a field kind without a struct, or a value of
configs/default.toml that is not the default is an error: the page cannot go stale.

Usage: docs-config.py SPLASH_BINARY OUT.md
"""

import re
import subprocess
import sys
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

ROOT = Path(__file__).resolve().parent.parent
SOURCES = ROOT / "crates" / "splash-sph" / "src"
KINDS_ENUM = "FieldConfig"


def fail(message):
    sys.exit(f"docs-config: {message}")


def doc_text(lines):
    """A doc comment as one Markdown line for a table cell: rustdoc's intra-doc links become
    plain code, pipes are escaped."""
    text = " ".join(line.strip() for line in lines).strip()
    text = re.sub(r"\[(`[^`]+`)\]\((?!https?:)[^)]*\)", r"\1", text)
    text = re.sub(r"\[(`[^`]+`)\](?!\()", r"\1", text)
    return text.replace("|", "\\|")


def parse_sources():
    """Every `pub struct` and `pub enum` with named fields or variants: its doc comment, serde
    options and members (name, Rust type or variant payload, doc comment, serde rename)."""
    items = {}
    item_re = re.compile(r"^pub (struct|enum) (\w+)\b.*\{\s*$")
    for path in sorted(SOURCES.rglob("*.rs")):
        lines = path.read_text(encoding="utf-8").splitlines()
        docs, attrs = [], []
        i = 0
        while i < len(lines):
            line = lines[i].strip()
            m = item_re.match(line)
            if line.startswith("///"):
                docs.append(line[3:])
            elif line.startswith("#["):
                attrs.append(line)
            elif m:
                kind, name = m.groups()
                members, i = parse_members(lines, i + 1, kind)
                items[name] = {
                    "kind": kind,
                    "doc": doc_text(docs),
                    "serde": " ".join(a for a in attrs if "serde" in a),
                    "members": members,
                    "file": path.relative_to(ROOT).as_posix(),
                }
                docs, attrs = [], []
            else:
                docs, attrs = [], []
            i += 1
    return items


def parse_members(lines, i, kind):
    members, docs, rename = [], [], None
    field_re = re.compile(r"^pub (\w+): (.+),$")
    variant_re = re.compile(r"^(\w+)(?:\(([\w:]+)\))?,$")
    while i < len(lines):
        line = lines[i].strip()
        if line == "}":
            return members, i
        if line.startswith("///"):
            docs.append(line[3:])
        elif line.startswith("#["):
            m = re.search(r'rename = "([^"]+)"', line)
            if m:
                rename = m.group(1)
        else:
            m = (field_re if kind == "struct" else variant_re).match(line)
            if m:
                members.append(
                    {"name": m.group(1), "type": m.group(2), "doc": doc_text(docs), "rename": rename}
                )
            docs, rename = [], None
        i += 1
    fail("unterminated item")


def serde_name(item, member):
    if member["rename"]:
        return member["rename"]
    name = member["name"]
    if "kebab-case" in item["serde"]:
        return re.sub(r"(?<!^)([A-Z])", r"-\1", name).lower()
    if "lowercase" in item["serde"]:
        return name.lower()
    return name


def last(type_name):
    return type_name.split("::")[-1]


def describe_type(items, rust_type):
    """The value a key takes, as a user writes it."""
    m = re.fullmatch(r"Option<(.+)>", rust_type)
    if m:
        return describe_type(items, m.group(1))
    m = re.fullmatch(r"Vec<(.+)>", rust_type)
    if m:
        return f"list of {describe_type(items, m.group(1))}s"
    m = re.fullmatch(r"\[(\w+); (\d+)\]", rust_type)
    if m:
        return f"{m.group(2)} numbers"
    t = last(rust_type)
    simple = {
        "f32": "number",
        "f64": "number",
        "u32": "integer ≥ 0",
        "u64": "integer ≥ 0",
        "usize": "integer ≥ 0",
        "bool": "`true` or `false`",
        "String": "name",
        "Length": "length: `2r`, `r/2`, `0.5r` (spacings r) or a number (world units)",
        "Bytes": "bytes: `\"8G\"`, `\"512M\"` or a number",
    }
    if t in simple:
        return simple[t]
    item = items.get(t)
    if item and item["kind"] == "enum":
        return "one of " + ", ".join(f"`{serde_name(item, v)}`" for v in item["members"])
    fail(f"no description of the type {rust_type}: add it to describe_type in {__file__}")


def show_value(value):
    if isinstance(value, bool):
        return "`true`" if value else "`false`"
    if isinstance(value, str):
        return f'`"{value}"`'
    if isinstance(value, list):
        return "`[" + ", ".join(show_value(v).strip("`") for v in value) + "]`"
    return f"`{value}`"


def config_show(binary, *flags):
    out = subprocess.run(
        [binary, "config", "show", *flags], check=True, capture_output=True, text=True
    ).stdout
    return tomllib.loads(out)


def rows(items, struct_name, defaults, prefix, out, tables):
    """Rows of one table; nested structs become tables of their own."""
    struct = items[struct_name]
    declared = set()
    for field in struct["members"]:
        key = field["name"]
        declared.add(key)
        where = f"{struct_name}.{key} ({struct['file']})"
        if not field["doc"]:
            fail(f"{where} has no doc comment: say what the key does, its unit and source")
        t = last(field["type"])
        if t == KINDS_ENUM:
            tables.append((prefix + key, t, None))
            continue
        if t in items and items[t]["kind"] == "struct":
            tables.append((prefix + key, t, defaults.get(key, {})))
            continue
        optional = field["type"].startswith("Option<")
        if key in defaults:
            default = show_value(defaults[key])
        elif optional:
            default = "absent"
        else:
            fail(f"{where}: `splash config show` prints no default for it")
        out.append(
            f"| `{prefix}{key}` | {default} | {describe_type(items, field['type'])} | {field['doc']} |"
        )
    extra = set(k for k in defaults if k != "kind") - declared
    if extra:
        fail(f"`splash config show` prints {sorted(extra)} that {struct_name} does not declare")


def table(items, title, struct_name, defaults, prefix, lines, level=2):
    """Appends a table's heading (unless title is None), doc comment and rows to lines; returns
    its nested tables."""
    struct = items[struct_name]
    if not struct["doc"]:
        fail(f"{struct_name} ({struct['file']}) has no doc comment")
    if title:
        lines += [f"{'#' * level} {title}", ""]
    lines += [struct["doc"], ""]
    out, tables = [], []
    rows(items, struct_name, defaults, prefix, out, tables)
    if out:
        lines += ["| key | default | value | meaning |", "|---|---|---|---|", *out, ""]
    return tables


def main():
    if len(sys.argv) != 3:
        fail(__doc__.strip().splitlines()[-1])
    binary, target = sys.argv[1], Path(sys.argv[2])
    items = parse_sources()
    defaults = config_show(binary)
    lines = [
        "# Configuration reference",
        "",
        "Generated by `scripts/docs` from the configuration types of `splash-sph` (keys and",
        "doc comments) and `splash config show` (defaults). A configuration file sets any of",
        "these keys (`splash recon --config FILE`); command-line flags override it, and",
        "`splash config show [--config FILE] [flags]` prints what a run resolves to.",
        "Unknown keys, wrong types and out-of-range values are errors naming the file, the key",
        "and its line. Lengths are multiples of the particle spacing r or world units.",
        "",
    ]
    pending = table(items, "Top level", "Config", defaults, "", lines)
    while pending:
        key, struct_name, values = pending.pop(0)
        if struct_name == KINDS_ENUM:
            enum = items[KINDS_ENUM]
            lines += [f"## `[{key}]`", "", enum["doc"], ""]
            for variant in enum["members"]:
                kind = serde_name(enum, variant)
                if not variant["type"] or last(variant["type"]) not in items:
                    fail(f"field kind {kind} has no config struct")
                values = config_show(binary, "--field", kind)[key]
                if values.get("kind") != kind:
                    fail(f"`splash config show --field {kind}` printed kind {values.get('kind')}")
                lines += [f"### `kind = \"{kind}\"`", "", variant["doc"], ""]
                if table(items, None, last(variant["type"]), values, f"{key}.", lines):
                    fail(f"nested tables in field kind {kind}")
            continue
        pending += table(items, f"`[{key}]`", struct_name, values, f"{key}.", lines)
    check_default_toml(defaults)
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text("\n".join(lines).rstrip() + "\n", encoding="utf-8")


def check_default_toml(defaults):
    """configs/default.toml writes the defaults out: each value it sets must be the default."""
    path = ROOT / "configs" / "default.toml"
    written = tomllib.loads(path.read_text(encoding="utf-8"))

    def walk(values, truth, prefix):
        for key, value in values.items():
            if isinstance(value, dict):
                walk(value, truth.get(key, {}), f"{prefix}{key}.")
            elif key not in truth or truth[key] != value:
                fail(
                    f"{path.relative_to(ROOT)} sets {prefix}{key} = {value!r}, but the default is "
                    f"{truth.get(key, 'absent')!r}"
                )

    walk(written, defaults, "")


if __name__ == "__main__":
    main()
