"""Live mode's time per frame at the viewport and the render settings, in headless Blender:

    blender -b --factory-startup --python tests/blender/bench_live.py -- \
        --addon target/splash_blender.zip --particles ../shared/data/cbd-small --spacing 0.014

Each particle frame is loaded into one object's vertices (with its velocity attribute, as a
sequence loader would), then the add-on's frame update runs without a cache; the time in
the package's `reconstruct` within it is printed apart from the rest (particles out of
Blender, the mesh into it).
"""

import argparse
import os
import sys
import time

import bpy
import numpy as np

args = argparse.ArgumentParser()
args.add_argument("--addon")
args.add_argument("--particles", required=True)
args.add_argument("--spacing", type=float, required=True)
args = args.parse_args(sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else [])
if args.addon:
    bpy.ops.preferences.addon_install(filepath=args.addon)
bpy.ops.preferences.addon_enable(module="splash_blender")
from splash_blender import live, vendor  # noqa: E402

splash_sph = vendor.splash_sph()
inside = [0.0]
_reconstruct = splash_sph.reconstruct


def timed_reconstruct(*a, **k):
    started = time.perf_counter()
    try:
        return _reconstruct(*a, **k)
    finally:
        inside[0] += time.perf_counter() - started


splash_sph.reconstruct = timed_reconstruct
scene = bpy.context.scene
source = bpy.data.objects.new("particles", bpy.data.meshes.new("particles"))
scene.collection.objects.link(source)
s = scene.splash
s.source, s.spacing, s.cache_mb = source, args.spacing, 0
files = sorted(f for f in os.listdir(args.particles) if f.endswith(".ply"))
times = {"viewport": [], "render": []}
triangles = {"viewport": [], "render": []}
package = {"viewport": [], "render": []}
for name in files:
    p = splash_sph.read_particles(os.path.join(args.particles, name))
    source.data.clear_geometry()
    source.data.vertices.add(len(p))
    source.data.vertices.foreach_set("co", p.positions.ravel())
    if "velocity" in p:
        a = source.data.attributes.new("velocity", "FLOAT_VECTOR", "POINT")
        a.data.foreach_set("vector", p["velocity"].ravel())
    for mode, render in (("viewport", False), ("render", True)):
        inside[0] = 0.0
        started = time.perf_counter()
        ok = live.update(scene, render=render)
        times[mode].append(time.perf_counter() - started)
        package[mode].append(inside[0])
        assert ok, s.error
        triangles[mode].append(len(live.surface_object(scene, source).data.polygons))
    print(f"{name}: {len(p)} particles; {s.status}")
for mode in times:
    t, pk = np.array(times[mode]), np.array(package[mode])
    q = live.quality(scene, mode == "render")
    print(
        f"live {mode} (cell {q.cell}, {q.field}, normals {q.normals}): {len(t)} frames, "
        f"mean {t.mean():.3f} s/frame (min {t.min():.3f}, max {t.max():.3f}); in the "
        f"package's reconstruct {pk.mean():.3f} s, Blender's side (particles out, mesh in) "
        f"{(t - pk).mean():.3f} s; {min(triangles[mode])}-{max(triangles[mode])} triangles"
    )
