#!/usr/bin/env python3
"""Simulates scene B2, a ball of water thrown into a pool, and keeps 30 frames from the impact.
SPlisHSPlasH (pysplishsplash 2.19.0), DFSPH, particle radius 0.01 m (splash's spacing r = 0.02),
walls by volume maps: a ball of 4,116 particles thrown down and sideways at 2.5 m/s into a pool
of 27,735 in a closed box. Copies the 30 frames from the impact, every output step at 200 fps,
into OUT_DIR as the simulator writes them: binary legacy VTK, points with id, velocity and
density. The frames keep the simulator's numbers (ParticleData_Fluid_K.vtk, written at t of
about (K-1)/200 s, becomes frame_KKKK.vtk). The scene (scene.json, box.obj, ball.geo) and the
full raw output go to WORK (default OUT_DIR-raw). Installs nothing: run it with a venv holding
pysplishsplash (whose import needs the system's libGLdispatch preloaded). About 1.5 minutes on
2 cores. The simulator runs on several threads, so two runs give slightly different files.

    python3 -m venv /work/venv-sph && /work/venv-sph/bin/pip install pysplishsplash==2.19.0
    LD_PRELOAD=/lib/x86_64-linux-gnu/libGLdispatch.so.0 /work/venv-sph/bin/python bench/make-ball-pool.py /work/scenes/B2
    ... bench/make-ball-pool.py OUT_DIR --work /tmp/b2-raw --frames 30 --radius 0.01
"""
import argparse
import json
import os
import shutil
import struct
import sys
import time

R = 0.01  # particle radius (--radius); lattice spacing 2R, splash's r. Lengths below are in D.
D = 2 * R
POOL = (44, 16, 44)  # FluidBlock's size: 43 x 15 x 43 = 27,735 particles
# The block stands GAP off the floor and the walls: its outer particles are then 3 radii from the
# walls. At 2 radii (no gap) the volume maps give them 1.3 times the rest density (2.7 in the
# corners) and the pool erupts along the walls; at 3 radii they start at 0.86 of it and settle.
GAP = 0.5
BOX = (POOL[0] + 2 * GAP, 62.5, POOL[2] + 2 * GAP)
BALL_CELLS2 = 98.5  # lattice points (i+1/2, j+1/2, k)*D with squared norm <= this: 4,116
BALL_CENTRE = (13, 38, 22.5)  # lowest particle 13 D above the pool's top layer
BALL_VELOCITY = (1.5, -2.0, 0.0)
FPS = 200


def pool_count():
    # SimulatorBase::createFluidBlocks: round(extent / 2r) - 1 particles along each axis
    n = 1
    for e in POOL:
        n *= round(e) - 1
    return n


def ball_points():
    n = int(BALL_CELLS2**0.5) + 1
    pts = []
    for i in range(-n - 1, n + 1):
        for j in range(-n - 1, n + 1):
            for k in range(-n, n + 1):
                a, b = i + 0.5, j + 0.5
                if a * a + b * b + k * k <= BALL_CELLS2:
                    pts.append((a * D, b * D, k * D))
    return pts


def write_geo(path, pts):
    """Houdini ASCII .geo, which SPlisHSPlasH reads through Partio (one dummy attribute, as
    Partio's reader needs one; the scene's initialVelocity overrides it anyway)."""
    with open(path, "w") as f:
        f.write(f"PGEOMETRY V5\nNPoints {len(pts)} NPrims 0\nNPointGroups 0 NPrimGroups 0\n")
        f.write("NPointAttrib 1 NVertexAttrib 0 NPrimAttrib 0 NAttrib 0\nPointAttrib\n")
        f.write("velocity 3 vector 0 0 0\n")
        for p in pts:
            f.write(f"{p[0]:.6f} {p[1]:.6f} {p[2]:.6f} 1 (0 0 0)\n")
        f.write("beginExtra\nendExtra\n")


def write_box(path, hi):
    """The container: a closed box from the origin to hi, faces wound like SPlisHSPlasH's UnitBox.obj."""
    x, y, z = hi
    v = [(0, 0, z), (x, 0, z), (0, y, z), (x, y, z), (0, y, 0), (x, y, 0), (0, 0, 0), (x, 0, 0)]
    f = [(1, 2, 3), (3, 2, 4), (3, 4, 5), (5, 4, 6), (5, 6, 7), (7, 6, 8),
         (7, 8, 1), (1, 8, 2), (2, 8, 4), (4, 8, 6), (7, 1, 5), (5, 1, 3)]
    with open(path, "w") as out:
        out.writelines(f"v {a} {b} {c}\n" for a, b, c in v)
        out.writelines(f"f {a} {b} {c}\n" for a, b, c in f)


def scene(stop_at):
    return {
        "Configuration": {
            "particleRadius": R,
            "simulationMethod": 4,  # DFSPH
            "gravitation": [0, -9.81, 0],
            "timeStepSize": 0.001,
            "cflMethod": 1,
            "cflFactor": 1,
            "cflMaxTimeStepSize": 0.001,  # so frames are written within 1 ms of (K-1)/200 s
            "boundaryHandlingMethod": 2,  # volume maps: every exported particle is fluid
            "stopAt": stop_at,
            "enableVTKExport": True,
            "dataExportFPS": FPS,
            "particleAttributes": "id;velocity;density",
            "DFSPH": {"minIterations": 2, "maxIterations": 100, "maxError": 0.05,
                      "maxIterationsV": 100, "maxErrorV": 0.1, "enableDivergenceSolver": True},
        },
        "Materials": [{"id": "Fluid", "density0": 1000, "viscosityMethod": 1,
                       "Standard viscosity": {"viscosity": 0.01}}],
        "RigidBodies": [{"geometryFile": "box.obj", "translation": [0, 0, 0], "scale": [1, 1, 1],
                         "isDynamic": False, "isWall": True, "mapInvert": True, "mapThickness": 0.0,
                         "mapResolution": [30, 40, 30]}],
        "FluidBlocks": [{"denseMode": 0, "start": [GAP * D] * 3,
                         "end": [(GAP + e) * D for e in POOL]}],
        "FluidModels": [{"particleFile": "ball.geo", "translation": [c * D for c in BALL_CENTRE],
                         "scale": [1, 1, 1], "initialVelocity": list(BALL_VELOCITY)}],
    }


def read_vtk(path):
    """Heights and ids of the simulator's binary (big-endian) legacy VTK file."""
    with open(path, "rb") as f:
        data = f.read()
    i = data.index(b"POINTS ")
    eol = data.index(b"\n", i)
    _, n, kind = data[i:eol].decode().split()
    n, size = int(n), {"float": 4, "double": 8}[kind]
    xyz = struct.unpack_from(f">{3 * n}{'f' if size == 4 else 'd'}", data, eol + 1)
    i = data.index(b"LOOKUP_TABLE id_table\n") + len(b"LOOKUP_TABLE id_table\n")
    ids = struct.unpack_from(f">{n}I", data, i)
    return xyz[1::3], ids


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out_dir")
    ap.add_argument("--work", help="scene and raw output (default OUT_DIR-raw)")
    ap.add_argument("--frames", type=int, default=30)
    ap.add_argument("--radius", type=float, default=0.01, help="particle radius (default %(default)s)")
    a = ap.parse_args()
    global R, D
    R, D = a.radius, 2 * a.radius
    work = os.path.abspath(a.work or a.out_dir.rstrip("/") + "-raw")
    os.makedirs(work, exist_ok=True)

    n_pool, ball = pool_count(), ball_points()
    # Free fall of the ball's lowest particle to one diameter above the pool's top particle.
    drop = (BALL_CENTRE[1] - GAP - POOL[1]) * D + min(p[1] for p in ball)
    vy, g = -BALL_VELOCITY[1], 9.81
    t_hit = (-vy + (vy * vy + 2 * g * drop) ** 0.5) / g
    stop_at = round(t_hit + (a.frames + 6) / FPS, 3)
    write_geo(os.path.join(work, "ball.geo"), ball)
    write_box(os.path.join(work, "box.obj"), [b * D for b in BOX])
    with open(os.path.join(work, "scene.json"), "w") as f:
        json.dump(scene(stop_at), f, indent=1)
    print(f"pool {n_pool} + ball {len(ball)} = {n_pool + len(ball)} particles; "
          f"impact expected at t = {t_hit:.3f} s; simulating to {stop_at} s", flush=True)

    import pysplishsplash as sph  # after the scene is written, so that --help works without it

    t0 = time.time()
    base = sph.Exec.SimulatorBase()
    base.init(["make-ball-pool", "--no-gui", "--no-initial-pause", "--stopAt", str(stop_at),
               "--output-dir", os.path.join(work, "out"), os.path.join(work, "scene.json")],
              "make-ball-pool")
    base.run()
    wall = time.time() - t0

    vtk = os.path.join(work, "out", "vtk")
    names = {int(n.rsplit("_", 1)[1][:-4]): n for n in os.listdir(vtk) if n.endswith(".vtk")}
    frames = sorted(names)
    first = None
    for k in frames:
        ys, ids = read_vtk(os.path.join(vtk, names[k]))
        top = max(y for y, i in zip(ys, ids) if i < n_pool)
        low = min(y for y, i in zip(ys, ids) if i >= n_pool)
        if low - top <= D:  # the ball's surface touches the pool's
            first = k
            break
    keep = list(range(first, first + a.frames)) if first else []
    if not keep or any(k not in names for k in keep):
        sys.exit(f"impact frame {first}: not {a.frames} frames after it in {vtk} ({frames[0]}..{frames[-1]})")
    os.makedirs(a.out_dir, exist_ok=True)
    for k in keep:
        shutil.copyfile(os.path.join(vtk, names[k]), os.path.join(a.out_dir, f"frame_{k:04d}.vtk"))
    print(f"simulated in {wall:.0f} s; impact at frame {first} (t = {(first - 1) / FPS:.3f} s); "
          f"kept frame_{keep[0]:04d} .. frame_{keep[-1]:04d} in {a.out_dir}")


if __name__ == "__main__":
    main()
