"""Live mode's time per frame at the viewport and the render settings, in headless Blender:

    blender -b --factory-startup --python tests/blender/bench_live.py -- \\
        --addon target/splash_blender.zip --particles ../shared/data/cbd-small --spacing 0.014

(or `python tests/blender/bench_live.py -- …` with the `bpy` module). Each particle frame is
loaded into one object's vertices (with its velocity attribute, as a sequence loader would),
then the add-on's frame update runs without a cache, and the depsgraph is evaluated as a
redraw would (Blender builds the new mesh's normals and bounds there). End to end is the sum;
it is split into the package's `reconstruct`, the particles out of Blender
(`live.particles`), the mesh into it (`meshdata.fill`), that evaluation, and the rest (the
particle object's own evaluation, the cache key, the panel's status). `--repeat N` runs the
frames N times; `--modes viewport` skips the render settings.

`--play FPS` plays instead: the directory is imported as a particle sequence (the add-on's
operator) and each file's frame is set in turn as playback would, one settings group per
pass, and the frames are paced at FPS: after a frame's work the main thread idles until the
next frame is due (headless Blender draws nothing), which is when live mode's read-ahead
makes the next file's surface in the background. End to end is then the main thread's time
per frame change (the particle file loaded into the object, live mode, the evaluation);
"read-ahead wait" is the part spent waiting for a surface still being made, the package's
time only the main thread's own calls, and CPU counts every thread.
"""

import argparse
import os
import sys
import threading
import time

import bpy
import numpy as np

args = argparse.ArgumentParser()
args.add_argument("--addon")
args.add_argument("--particles", required=True)
args.add_argument("--spacing", type=float, required=True)
args.add_argument("--repeat", type=int, default=1)
args.add_argument("--modes", default="viewport,render")
args.add_argument("--play", type=float, default=0.0)
args = args.parse_args(sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else [])
if args.addon:
    bpy.ops.preferences.addon_install(filepath=args.addon)
bpy.ops.preferences.addon_enable(module="splash_blender")
from splash_blender import live, meshdata, vendor  # noqa: E402

try:
    from splash_blender import ahead  # noqa: E402
except ImportError:  # an add-on without read-ahead (bench/live.sh --vs)
    ahead = None
splash_sph = vendor.splash_sph()
inside = {}


def timed(name, function):
    def call(*a, **k):
        if threading.current_thread() is not threading.main_thread():
            return function(*a, **k)  # read-ahead: counted in CPU only
        started, cpu = time.perf_counter(), time.process_time()
        try:
            return function(*a, **k)
        finally:
            inside[name] = inside.get(name, 0.0) + time.perf_counter() - started
            inside[name + " cpu"] = inside.get(name + " cpu", 0.0) + time.process_time() - cpu

    return call


splash_sph.reconstruct = timed("package", splash_sph.reconstruct)
live.particles = timed("particles out", live.particles)
meshdata.fill = timed("mesh in", meshdata.fill)
if ahead is not None:
    ahead.take = timed("read-ahead wait", ahead.take)
scene = bpy.context.scene
source = bpy.data.objects.new("particles", bpy.data.meshes.new("particles"))
scene.collection.objects.link(source)
s = scene.splash
s.source, s.spacing, s.cache_mb = source, args.spacing, 0
files = sorted(f for f in os.listdir(args.particles) if f.endswith(".ply"))
modes = args.modes.split(",")
parts = ("package", "particles out", "mesh in", "evaluation", "rest")
if args.play:
    parts = ("package", "read-ahead wait", "particles in", "particles out", "mesh in",
             "evaluation", "rest")  # fmt: skip
rows = {mode: [] for mode in modes}
triangles = {mode: [] for mode in modes}


def measure(mode, work, idle=None):
    """Times `work` (a frame's update) and the evaluation after it into rows[mode]; the CPU
    time includes `idle()` after them (playback's wait for the next frame)."""
    inside.clear()
    started, cpu = time.perf_counter(), time.process_time()
    ok = work()
    updated = time.perf_counter()
    bpy.context.evaluated_depsgraph_get()
    inside["evaluation"] = time.perf_counter() - updated
    total = time.perf_counter() - started
    if idle is not None:
        idle()
    cpu = time.process_time() - cpu
    assert ok, s.error
    inside["rest"] = total - sum(inside.get(k, 0.0) for k in parts[:-1])
    # CPU seconds of every thread (the package's workers too): less swayed by a busy
    # machine than the wall clock.
    cpus = [cpu, inside.get("package cpu", 0.0)]
    rows[mode].append([total] + [inside.get(k, 0.0) for k in parts] + cpus)
    triangles[mode].append(len(live.surface_object(scene, source).data.polygons))


if args.play:
    from splash_blender import sequence  # noqa: E402

    sequence.load = timed("particles in", sequence.load)
    scene.frame_set(1)
    source.data.vertices.add(1)  # a source until the sequence's object replaces it
    assert bpy.ops.splash.import_particles(directory=args.particles) == {"FINISHED"}
    source = next(o for o in scene.objects if o.splash_sequence.particles)
    numbers = [n for n, _ in sequence.frame_files(args.particles, particles=True)]
    s.source, s.enabled = source, True
    for mode in modes:
        live._state["rendering"] = mode == "render"
        for _ in range(args.repeat):
            live.clear_cache()
            scene.frame_set(numbers[-1])  # the pass starts by jumping back to the first frame
            due = time.perf_counter()
            for number in numbers:
                due += 1.0 / args.play
                measure(
                    mode,
                    lambda: (scene.frame_set(number), s.error == "")[1],
                    lambda: time.sleep(max(0.0, due - time.perf_counter())),
                )
                print(f"{mode} frame {number}: {s.status}")
    live._state["rendering"] = False
    files = numbers
else:
    for name in files * args.repeat:
        p = splash_sph.read_particles(os.path.join(args.particles, name))
        source.data.clear_geometry()
        source.data.vertices.add(len(p))
        source.data.vertices.foreach_set("co", p.positions.ravel())
        if "velocity" in p:
            a = source.data.attributes.new("velocity", "FLOAT_VECTOR", "POINT")
            a.data.foreach_set("vector", p["velocity"].ravel())
        for mode in modes:
            measure(mode, lambda: live.update(scene, render=mode == "render"))
        print(f"{name}: {len(p)} particles; {s.status}")
print(
    f"Blender {bpy.app.version_string}, {len(files)} frames x {args.repeat}"
    + (f", played at {args.play:g} fps" if args.play else "")
)
for mode in modes:
    t = np.array(rows[mode])
    q = live.quality(scene, mode == "render")
    print(
        f"live {mode}{' played' if args.play else ''} (cell {q.cell}, {q.field}, "
        f"normals {q.normals}, "
        f"{'raw' if getattr(q, 'raw', False) else 'post-processed'}): "
        f"mean {t[:, 0].mean():.3f} s/frame (median {np.median(t[:, 0]):.3f}, min "
        f"{t[:, 0].min():.3f}, max {t[:, 0].max():.3f}); "
        + ", ".join(f"{k} {t[:, i + 1].mean():.4f}" for i, k in enumerate(parts))
        + f"; Blender's side {(t[:, 0] - t[:, 1] - (t[:, 2] if args.play else 0)).mean():.3f} s; "
        + (
            # The read-ahead's CPU is not the main thread's: only the whole is told.
            f"CPU {t[:, -2].mean():.3f} s (every thread, the wait for the next frame included); "
            if args.play
            else f"CPU {t[:, -2].mean():.3f} s (package {t[:, -1].mean():.3f}, Blender's side "
            f"{(t[:, -2] - t[:, -1]).mean():.3f}); "
        )
        + f"{min(triangles[mode])}-{max(triangles[mode])} triangles"
        + (f"; {(t[:, 0] > 1.0 / args.play).sum()} of {len(t)} frames over 1/{args.play:g} s"
           if args.play else "")  # fmt: skip
    )
sys.stdout.flush()
if not bpy.app.binary_path:
    os._exit(0)  # the bpy module 4.2 crashes freeing the add-on's panels at exit (see test_addon)
