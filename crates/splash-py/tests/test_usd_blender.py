"""Blender 4.5 (the `bpy` module from PyPI) imports the CLI's USD sequence stage as one mesh
that shows frame t's vertices and velocities at frame t. Skips, saying why, without a Python
that has bpy 4.5: $SPLASH_BPY_PYTHON, else the virtualenv bpy-4.5 in $SPLASH_BPY_CACHE (default
~/.cache/splash-bpy), where scripts/test installs it."""

import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

from conftest import FRAME, FRAME_SPACING, REPO

BPY_CACHE = os.environ.get("SPLASH_BPY_CACHE") or Path.home() / ".cache" / "splash-bpy"
BPY_PYTHON = Path(os.environ.get("SPLASH_BPY_PYTHON") or Path(BPY_CACHE) / "bpy-4.5" / "bin" / "python")

# Imports the stage and prints, per frame, the evaluated mesh's vertex count and velocities.
IMPORT = """
import json, sys
import bpy
bpy.ops.wm.read_factory_settings(use_empty=True)
assert bpy.ops.wm.usd_import(filepath=sys.argv[1]) == {"FINISHED"}
scene = bpy.context.scene
meshes = [o for o in bpy.data.objects if o.type == "MESH"]
out = {"version": bpy.app.version_string, "range": [scene.frame_start, scene.frame_end],
       "objects": [o.name for o in meshes], "frames": {}}
for frame in map(int, sys.argv[2:]):
    scene.frame_set(frame)
    evaluated = meshes[0].evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = evaluated.to_mesh()
    velocity = mesh.attributes.get("velocity")
    out["frames"][frame] = [len(mesh.vertices), len(mesh.polygons),
                            velocity is not None and len(velocity.data) == len(mesh.vertices)]
    evaluated.to_mesh_clear()
print("RESULT " + json.dumps(out))
"""


def bpy_version():
    if not BPY_PYTHON.exists():
        return None
    run = subprocess.run(
        [BPY_PYTHON, "-c", "import bpy; print(bpy.app.version_string)"],
        capture_output=True,
        text=True,
    )
    return run.stdout.strip() if run.returncode == 0 else None


def test_blender_plays_the_usd_sequence(splash_bin, tmp_path):
    version = bpy_version()
    if not version or not version.startswith("4.5"):
        pytest.skip(f"no bpy 4.5 at {BPY_PYTHON} (pip install 'bpy==4.5.*' there, Python 3.11)")
    sim = tmp_path / "sim"
    sim.mkdir()
    for f in [REPO / "fixtures" / "frame_0010.ply", FRAME]:
        shutil.copy(f, sim / f.name)
    usd = tmp_path / "usd"
    subprocess.run(
        [splash_bin, "recon", sim, "--spacing", str(FRAME_SPACING), "-q", "-o", f"{usd}/",
         "--format", "usd"],
        check=True,
    )
    counts = {}
    for name in ["frame_0010.usda", "frame_0040.usda"]:
        head = (usd / name).read_text()[:300]
        counts[int(name[6:10])] = [int(head.split("splash mesh: ")[1].split()[k]) for k in (0, 2)]
    script = tmp_path / "import_usd.py"
    script.write_text(IMPORT)
    run = subprocess.run(
        [BPY_PYTHON, script, usd / "frame.usda", "10", "25", "40"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    result = json.loads(run.stdout.split("RESULT ")[1])
    assert result["range"] == [10, 40] and result["objects"] == ["Surface"]
    frames = {int(k): v for k, v in result["frames"].items()}
    assert frames[10] == counts[10] + [True]
    assert frames[40] == counts[40] + [True]
    # Between frames, the earlier one holds.
    assert frames[25] == frames[10]
    assert counts[10] != counts[40]
