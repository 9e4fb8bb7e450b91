# SPDX-License-Identifier: GPL-2.0-or-later
"""The `splash recon` command line equivalent to the panel's render settings, and back.

Pure Python (no bpy): `to_command` takes the settings as a dict, `from_command` returns one.
"""

import shlex

FIELDS = ("ssp07", "zb05", "density", "blobby", "metaball", "anisotropic")
NORMALS = ("field", "grid", "none")
ENGINES = ("narrow-band", "full-gather", "scatter", "slices")
VOLUME_SCOPES = ("frame", "component")


def to_command(s):
    """`splash recon …` for settings `s`: input, output, spacing, cell, field, normals,
    engine, correct (Newton steps, 0: none), velocity (bool), up_axis ("" or "y"/"z"), and
    post-processing: raw (bool), volume_scope ("frame" or "component"), temporal (bool),
    decimate (in r) and min_component (in r³), None when off, mesh_aabb (six numbers) or
    None."""
    words = ["splash", "recon", s.get("input") or "PARTICLES"]
    if s.get("spacing"):
        # Blender keeps it as a float32: 7 digits say all it holds.
        words += ["--spacing", f"{s['spacing']:.7g}"]
    words += ["--cell", s["cell"], "--field", s["field"], "--normals", s["normals"]]
    if s.get("engine", "narrow-band") != "narrow-band":
        words += ["--engine", s["engine"]]
    if s.get("correct"):
        words.append(f"--correct={int(s['correct'])}")
    if s.get("raw"):
        words.append("--raw")
    if s.get("volume_scope", "frame") != "frame":
        words += ["--volume-scope", s["volume_scope"]]
    if s.get("temporal"):
        words.append("--temporal")
    if s.get("decimate") is not None:
        words += ["--decimate", f"{s['decimate']:.7g}r"]
    if s.get("min_component") is not None:
        words += ["--min-component", f"{s['min_component']:.7g}"]
    if s.get("mesh_aabb") is not None:
        words += ["--mesh-aabb", ",".join(f"{x:.7g}" for x in s["mesh_aabb"])]
    if s.get("velocity"):
        # OBJ has no room for velocities.
        words += ["--attributes", "velocity", "--format", "ply"]
    if s.get("up_axis"):
        words += ["--up-axis", s["up_axis"]]
    words += ["-o", s.get("output") or "mesh/"]
    return " ".join(shlex.quote(w) for w in words)


class CommandError(ValueError):
    """A command line the panel cannot take."""


def from_command(line):
    """Settings parsed from a `splash recon` line, and a list of the words ignored (options
    the panel has no place for). Raises CommandError for a line that is not `splash recon`
    or has a bad value."""
    try:
        words = shlex.split(line)
    except ValueError as e:
        raise CommandError(f"cannot split the command line: {e}") from None
    if words and words[0].endswith("splash"):
        words = words[1:]
    if not words or words[0] != "recon":
        raise CommandError("expected a 'splash recon …' command line")
    words = words[1:]
    out, ignored, inputs, decimate = {}, [], [], []
    takes_value = {
        "--spacing", "--particle-radius", "--cell", "--field", "--normals", "--engine",
        "--attributes", "--up-axis", "-o", "--output", "--format", "--config", "--threads",
        "--frames", "--shard", "--max-memory", "--input-format", "--particle-aabb",
        "--block", "--log-format", "--report", "--decimate", "--min-component", "--mesh-aabb",
        "--volume-scope",
    }  # fmt: skip
    i = 0
    while i < len(words):
        word = words[i]
        if word.startswith("--") and "=" in word:
            word, value = word.split("=", 1)
            i += 1
        elif word in takes_value:
            if i + 1 >= len(words):
                raise CommandError(f"{word} needs a value")
            value = words[i + 1]
            i += 2
        elif word == "--raw":
            out["raw"] = True
            i += 1
            continue
        elif word == "--temporal":
            out["temporal"] = True
            i += 1
            continue
        elif word == "--correct":
            # As the CLI takes it: bare, 3 steps; a count only as --correct=N.
            out["correct"] = 3
            i += 1
            continue
        else:
            if word.startswith("-"):
                ignored.append(word)
            else:
                inputs.append(word)
            i += 1
            continue
        if word == "--spacing":
            out["spacing"] = _number(word, value)
        elif word == "--particle-radius":
            out["spacing"] = 2.0 * _number(word, value)
        elif word == "--cell":
            out["cell"] = value
        elif word == "--field":
            out["field"] = _choice(word, value, FIELDS)
        elif word == "--normals":
            out["normals"] = _choice(word, value, NORMALS)
        elif word == "--engine":
            out["engine"] = _choice(word, value, ENGINES)
        elif word == "--attributes":
            names = [n.strip().lower() for n in value.split(",")]
            out["velocity"] = any(n in ("velocity", "velocities", "vel", "v") for n in names)
        elif word == "--up-axis":
            out["up_axis"] = _choice(word, value.lower(), ("y", "z"))
        elif word == "--decimate":
            decimate.append(value)
        elif word == "--min-component":
            out["min_component"] = _number(word, value, positive=False)
        elif word == "--correct":
            out["correct"] = _count(word, value)
        elif word == "--volume-scope":
            out["volume_scope"] = _choice(word, value, VOLUME_SCOPES)
        elif word in ("-o", "--output"):
            out["output"] = value
        else:
            ignored.append(f"{word} {value}")
    if inputs:
        out["input"] = " ".join(shlex.quote(w) for w in inputs)
    if decimate:
        # The panel holds it in r: a plain length needs the line's spacing.
        out["decimate"] = _in_spacings("--decimate", decimate[-1], out.get("spacing"))
    return out, ignored


def _number(option, value, positive=True):
    try:
        number = float(value)
    except ValueError:
        raise CommandError(f"{option} {value}: expected a number") from None
    if not (number > 0 if positive else number >= 0):
        sign = "positive" if positive else "non-negative"
        raise CommandError(f"{option} {value}: expected a {sign} number")
    return number


def _count(option, value):
    """A number of Newton steps, 0 to 32 as the CLI takes them."""
    if not value.isdigit() or int(value) > 32:
        raise CommandError(f"{option}={value}: expected a count from 0 to 32")
    return int(value)


def _in_spacings(option, value, spacing):
    """A length as spacings r: "0.1r" and "r" as written, a plain length divided by the
    line's --spacing."""
    text = value.strip().lower()
    if text.endswith("r"):
        return _number(option, text[:-1] or "1")
    if spacing is None:
        raise CommandError(f"{option} {value}: the panel takes it in spacings r (e.g. 0.1r), "
                           "or as a length with --spacing on the line")  # fmt: skip
    return _number(option, text) / spacing


def _choice(option, value, choices):
    if value not in choices:
        raise CommandError(f"{option} {value}: expected one of {', '.join(choices)}")
    return value
