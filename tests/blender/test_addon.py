"""The Blender add-on in headless Blender: tests/blender/run starts it as

    blender -b --factory-startup --python tests/blender/test_addon.py

with SPLASH_ADDON_ZIP (the built add-on), SPLASH_BIN (the splash command), SPLASH_REPO and
SPLASH_TEST_DIR (a scratch directory) in the environment. It installs and enables the zip (a
legacy add-on, or a 4.2+ extension when it has blender_manifest.toml), imports 3-frame
sequences that `splash recon` writes as PLY, VTU and OBJ (two real frames of fixtures/ and a
ball of particles moving at one known velocity), steps the frames and checks counts, normals
and velocities against the files, checks live mode against the package, its post-processing
options (raw, decimate, smallest component, clip box) by what each does to the mesh, errors in
the UI, the command line round trip, and renders with Workbench and Cycles (motion blur by
velocity). Any failure exits Blender with status 1.
"""

import importlib
import os
import shlex
import shutil
import subprocess
import sys
import traceback
import zipfile

import bpy
import numpy as np
from mathutils import Vector
from mathutils.bvhtree import BVHTree

ZIP = os.environ["SPLASH_ADDON_ZIP"]
SPLASH = os.environ["SPLASH_BIN"]
REPO = os.environ["SPLASH_REPO"]
WORK = os.environ["SPLASH_TEST_DIR"]
SPACING = 0.014
BALL_VELOCITY = np.array([3.0, 0.0, 0.0], np.float32)
checks = []


def check(condition, what):
    checks.append(what)
    if not condition:
        raise AssertionError(what)


def write_particles_ply(path, positions, velocities):
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(positions)}\n"
        + "".join(f"property float {k}\n" for k in ("x", "y", "z", "vx", "vy", "vz"))
        + "end_header\n"
    )
    table = np.hstack([positions, velocities]).astype("<f4")
    with open(path, "wb") as f:
        f.write(header.encode())
        f.write(table.tobytes())


def make_particles():
    """frame_0001, _0002: the fixtures' real frames; frame_0003: a ball moving at
    BALL_VELOCITY (every vertex gets exactly that velocity: a kernel-weighted mean of equal
    values)."""
    particles = os.path.join(WORK, "particles")
    os.makedirs(particles, exist_ok=True)
    shutil.copy(os.path.join(REPO, "fixtures/frame_0010.ply"), f"{particles}/frame_0001.ply")
    shutil.copy(os.path.join(REPO, "fixtures/frame_0040.ply"), f"{particles}/frame_0002.ply")
    k = np.arange(-8, 9) * SPACING
    lattice = np.stack(np.meshgrid(k, k, k, indexing="ij"), -1).reshape(-1, 3)
    ball = lattice[np.linalg.norm(lattice, axis=1) <= 8 * SPACING] + [0.6, 0.3, 0.4]
    velocities = np.tile(BALL_VELOCITY, (len(ball), 1))
    write_particles_ply(f"{particles}/frame_0003.ply", ball, velocities)
    return particles


def recon(particles, fmt):
    out = os.path.join(WORK, f"seq_{fmt}") + "/"
    extra = [] if fmt == "obj" else ["--attributes", "velocity"]
    subprocess.run(
        [SPLASH, "recon", particles, "--spacing", str(SPACING), "--cell", "r", "--format", fmt,
         "-q", "-o", out] + extra,
        check=True,
    )  # fmt: skip
    return out


def file_counts(path):
    """Vertex and triangle counts from the file's own header or lines (not read_mesh)."""
    with open(path, "rb") as f:
        data = f.read()
    if path.endswith(".ply"):
        head = data[: data.index(b"end_header")].decode().split("\n")
        count = {w[1]: int(w[2]) for w in (line.split() for line in head) if w[:1] == ["element"]}
        return count["vertex"], count.get("face", 0)
    if path.endswith(".vtu"):
        import re

        m = re.search(rb'NumberOfPoints="(\d+)" NumberOfCells="(\d+)"', data)
        return int(m.group(1)), int(m.group(2))
    lines = data.split(b"\n")
    return sum(x.startswith(b"v ") for x in lines), sum(x.startswith(b"f ") for x in lines)


def ply_table(path):
    """The vertex table of a binary PLY mesh, parsed here from its header."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    head = data[:end].decode().split("\n")
    n = next(int(w[2]) for w in (x.split() for x in head) if w[:2] == ["element", "vertex"])
    names = []
    for line in head:
        w = line.split()
        if w[:1] == ["element"] and w[1] != "vertex":
            break
        if w[:2] == ["property", "float"]:
            names.append(w[2])
    return np.frombuffer(data, np.dtype([(k, "<f4") for k in names]), n, end)


def mesh_arrays(obj):
    me = obj.data
    v = np.empty(3 * len(me.vertices), np.float32)
    me.vertices.foreach_get("co", v)
    f = np.empty(3 * len(me.polygons), np.int32)
    me.polygons.foreach_get("vertices", f)
    return v.reshape(-1, 3), f.reshape(-1, 3)


def edges_match(me):
    """Whether `me` has each side of its triangles once as an edge and each corner points to
    the edge to the next corner, as Blender's own `calc_edges` would make them, and
    `validate` finds nothing to mend."""
    e = np.empty(2 * len(me.edges), np.int32)
    me.edges.foreach_get("vertices", e)
    e = np.sort(e.reshape(-1, 2), axis=1)
    corner_edge = np.empty(len(me.loops), np.int32)
    me.loops.foreach_get("edge_index", corner_edge)
    f = np.empty(len(me.loops), np.int32)
    me.polygons.foreach_get("vertices", f)
    f = f.reshape(-1, 3)
    sides = np.sort(np.stack([f.ravel(), np.roll(f, -1, axis=1).ravel()], axis=1), axis=1)
    return (
        len(np.unique(e, axis=0)) == len(e) == len(np.unique(sides, axis=0))
        and np.array_equal(e[corner_edge], sides)
        and not me.validate(verbose=False)
    )


def velocity_of(obj):
    a = obj.data.attributes.get("velocity")
    if a is None:
        return None
    out = np.empty(3 * len(obj.data.vertices), np.float32)
    a.data.foreach_get("vector", out)
    return out.reshape(-1, 3)


def split_normals(obj):
    """Per-loop normals (what shading uses) and each loop's vertex."""
    me = obj.data
    if hasattr(me, "calc_normals_split"):
        me.calc_normals_split()
    n = np.empty(3 * len(me.loops), np.float32)
    me.loops.foreach_get("normal", n)
    idx = np.empty(len(me.loops), np.int32)
    me.loops.foreach_get("vertex_index", idx)
    return n.reshape(-1, 3), idx


def test_sequences(sequence, particles):
    scene = bpy.context.scene
    seqs = {}
    for fmt in ("ply", "vtu", "obj"):
        directory = recon(particles, fmt)
        scene.frame_set(1)
        obj, files = sequence.import_sequence(bpy.context, directory, "Y", name=f"fluid_{fmt}")
        check([n for n, _ in files] == [1, 2, 3], f"{fmt}: three frames listed")
        seqs[fmt] = obj
        for frame in (1, 2, 3):
            scene.frame_set(frame)
            path = obj.splash_sequence.file
            check(path.endswith(f"frame_{frame:04d}.{fmt}"), f"{fmt} frame {frame}: its file")
            check(obj.splash_sequence.error == "", f"{fmt} frame {frame}: no error")
            nv, nf = file_counts(path)
            v, f = mesh_arrays(obj)
            check((len(v), len(f)) == (nv, nf), f"{fmt} frame {frame}: {nv} vertices, {nf} faces")
            check(obj.data.has_custom_normals, f"{fmt} frame {frame}: custom split normals")
            check(all(p.use_smooth for p in obj.data.polygons[:50]), f"{fmt}: smooth shaded")
            check(edges_match(obj.data), f"{fmt} frame {frame}: the package's edges")
            vel = velocity_of(obj)
            check((vel is None) == (fmt == "obj"), f"{fmt} frame {frame}: velocity iff PLY/VTU")
            if fmt == "ply":
                table = ply_table(path)
                xyz = np.stack([table[k] for k in "xyz"], 1)
                check(np.array_equal(v, xyz), f"ply frame {frame}: vertices as in the file")
                normals = np.stack([table[k] for k in ("nx", "ny", "nz")], 1)
                loop_n, loop_v = split_normals(obj)
                cos = np.sum(loop_n * normals[loop_v], axis=1)
                check(cos.min() > 0.9999, f"ply frame {frame}: split normals are the file's")
                expect = np.stack([table[k] for k in ("vx", "vy", "vz")], 1)
                pick = np.linspace(0, len(v) - 1, 7).astype(int)
                check(np.array_equal(vel[pick], expect[pick]), f"ply frame {frame}: velocities")
                if frame == 3:
                    check(np.allclose(vel, BALL_VELOCITY, atol=1e-6), "ball: the known velocity")
            if fmt == "vtu":
                pv, pf = mesh_arrays(seqs["ply"])  # not stepped since: still at frame 3
                if frame == 3:
                    check(np.array_equal(v, pv) and np.array_equal(f, pf), "vtu mesh = ply mesh")
                    check(np.array_equal(vel, velocity_of(seqs["ply"])), "vtu velocity = ply")
        # Upright: the object turns Y-up data so that y becomes Blender's z.
        world = np.array(obj.matrix_world)[:3, :3]
        check(np.allclose(world @ [0, 1, 0], [0, 0, 1], atol=1e-6), f"{fmt}: Y-up turned upright")
    return seqs


def test_vdb(particles, seqs, sequence):
    """The VDB sequence splash writes, imported as Blender's own Volume object (no add-on
    involved): its grids, its frames, a bounding box around the PLY mesh of the same frame,
    and the Volume to Mesh modifier's mesh of the level set enclosing the PLY mesh's volume.
    Then imported by the add-on ("Import splash sequence" of the directory): the same Volume
    sequence, turned upright like the mesh sequences."""
    directory = recon(particles, "vdb")
    names = sorted(os.listdir(directory))
    check(names == [f"frame_{k:04d}.vdb" for k in (1, 2, 3)], f"vdb: three files ({names})")
    bpy.context.scene.frame_set(2)
    bpy.ops.object.volume_import(
        filepath=os.path.join(directory, names[0]), directory=directory,
        files=[{"name": n} for n in names], use_sequence_detection=True,
    )  # fmt: skip
    vol = bpy.context.selected_objects[0]
    check(vol.type == "VOLUME" and vol.data.is_sequence, "vdb: a Volume sequence")
    check(vol.data.frame_duration == 3, "vdb: three frames")
    vol.data.grids.load()
    grids = {g.name: g.data_type for g in vol.data.grids}
    check(grids == {"surface": "FLOAT", "v": "VECTOR_FLOAT"}, f"vdb: grids {grids}")
    bpy.context.scene.frame_set(3)
    v, f = mesh_arrays(seqs["ply"])  # stepped to frame 3 too
    corners = np.array([list(c) for c in vol.bound_box])
    lo, hi = corners.min(0), corners.max(0)
    cell = SPACING
    inside = np.all(v.min(0) >= lo) and np.all(v.max(0) <= hi)
    check(inside and np.all(v.min(0) - lo < 12 * cell) and np.all(hi - v.max(0) < 12 * cell),
          f"vdb frame 3: bounds {lo} {hi} around the mesh's {v.min(0)} {v.max(0)}")  # fmt: skip
    host = bpy.data.objects.new("vdb_mesh", bpy.data.meshes.new("vdb_mesh"))
    bpy.context.scene.collection.objects.link(host)
    mod = host.modifiers.new("level set", "VOLUME_TO_MESH")
    mod.object, mod.grid_name, mod.threshold, mod.resolution_mode = vol, "surface", 0.0, "GRID"
    evaluated = host.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = evaluated.to_mesh()
    lv = np.empty(3 * len(mesh.vertices), np.float32)
    mesh.vertices.foreach_get("co", lv)
    lv = lv.reshape(-1, 3).astype(np.float64)
    mesh.calc_loop_triangles()
    lt = np.empty(3 * len(mesh.loop_triangles), np.int32)
    mesh.loop_triangles.foreach_get("vertices", lt)
    lt = lt.reshape(-1, 3)

    def volume(p, t):
        a, b, c = p[t[:, 0]], p[t[:, 1]], p[t[:, 2]]
        return abs(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6)

    ours, theirs = volume(v.astype(np.float64), f), volume(lv, lt)
    check(abs(theirs / ours - 1) < 0.02, f"vdb frame 3: volume {theirs} against the mesh's {ours}")

    def farthest(points, p, t):
        """The largest distance from `points` to the surface of triangles `t` over `p`."""
        tree = BVHTree.FromPolygons(p.tolist(), t.tolist())
        return max(tree.find_nearest(q)[3] for q in points.tolist())

    # Blender 3.4 and 4.5's Volume to Mesh adds half a voxel to every vertex of OpenVDB's mesh
    # (Blender issue #85312, to match the volume as Blender draws it): its mesh of the ball
    # comes out half a voxel higher on every axis; Blender 5.0's does not. The grid's own zero
    # crossing is where splash's mesh is (tests/vdb_cli.rs meshes it with vdb_tool).
    shift = 0.5 * cell if bpy.app.version < (5, 0, 0) else 0.0
    moved = (lv.min(0) + lv.max(0)) / 2 - (v.min(0) + v.max(0)) / 2
    check(np.allclose(moved, shift, atol=0.1 * cell), f"vdb frame 3: Blender's half voxel {moved}")
    # Two-sided Hausdorff at the vertices, that half voxel taken back: each surface within
    # half a cell of the other.
    there, back = farthest(v, lv - shift, lt), farthest(lv - shift, v, f)
    check(max(there, back) < 0.5 * cell,
          f"vdb frame 3: Hausdorff {there / cell:.3f} (mesh to level set), "
          f"{back / cell:.3f} (back) cells")  # fmt: skip
    evaluated.to_mesh_clear()

    obj, files = sequence.import_sequence(bpy.context, directory, "Y", name="fluid_vdb")
    check([n for n, _ in files] == [1, 2, 3], "vdb add-on import: three frames listed")
    check(obj.type == "VOLUME" and obj.data.is_sequence and obj.data.frame_duration == 3,
          "vdb add-on import: a Volume sequence of three frames")  # fmt: skip
    bpy.context.view_layer.update()
    world = np.array(obj.matrix_world)[:3, :3]
    check(np.allclose(world @ [0, 1, 0], [0, 0, 1], atol=1e-6), "vdb add-on import: Y-up upright")
    obj.data.grids.load()
    check({g.name for g in obj.data.grids} == {"surface", "v"}, "vdb add-on import: its grids")
    box = np.array([list(c) for c in obj.bound_box])
    check(np.allclose(box, corners, atol=1e-6), f"vdb add-on import: frame 3's box {box.min(0)}")
    result = bpy.ops.splash.import_sequence(directory=directory)
    active = bpy.context.view_layer.objects.active
    check("FINISHED" in result and active.type == "VOLUME", "vdb: the import operator")
    for o in (obj, active):  # upright, they would stand in the renders' view
        bpy.data.objects.remove(o)
    # Out of the way of the renders.
    for obj in (host, vol):
        bpy.data.objects.remove(obj)


def test_live(live, splash_sph, command, ui):
    scene = bpy.context.scene
    p = splash_sph.read_particles(os.path.join(REPO, "fixtures/frame_0040.ply"))
    me = bpy.data.meshes.new("particles")
    me.vertices.add(len(p))
    me.vertices.foreach_set("co", p.positions.ravel())
    vel = me.attributes.new("velocity", "FLOAT_VECTOR", "POINT")
    vel.data.foreach_set("vector", p["velocity"].ravel())
    source = bpy.data.objects.new("particles", me)
    scene.collection.objects.link(source)
    s = scene.splash
    s.source, s.spacing = source, SPACING
    check(
        (s.viewport.cell, s.viewport.field, s.viewport.normals, s.viewport.raw)
        == ("r", "density", "none", True),
        "viewport defaults: coarse cell, fast field, Blender's normals, raw isosurface",
    )
    check(
        (s.render.raw, s.render.use_decimate, s.render.use_min_component, s.clip_object)
        == (False, False, False, None),
        "render defaults: post-processed, no decimation, no droplets dropped, no clip box",
    )
    s.render.cell, s.render.field, s.render.normals = "r/2", "ssp07", "field"
    s.enabled = True  # reconstructs at once with the viewport settings
    check(s.error == "", f"live: no error ({s.error})")
    surface = live.surface_object(scene, source)
    for rendering, q in ((False, s.viewport), (True, s.render)):
        check(
            live.update(scene, render=rendering), f"live ({'render' if rendering else 'viewport'})"
        )
        want = splash_sph.reconstruct(
            p.positions, SPACING, cell=q.cell, field=q.field, normals=q.normals, raw=q.raw,
            attributes={"velocity": p["velocity"]},
        )  # fmt: skip
        v, f = mesh_arrays(surface)
        same = np.array_equal(v, want.vertices) and np.array_equal(f, want.faces)
        check(same, f"live {q.cell} {q.field}: the package's mesh ({len(f)} triangles)")
        check(np.array_equal(velocity_of(surface), want.attributes["velocity"]), "live velocity")
        check(edges_match(surface.data), f"live {q.cell} {q.field}: the package's edges")
        # Custom normals at render: the post-processed mesh's area-weighted ones go to
        # Blender only where it takes them as one attribute (4.5+).
        custom = rendering and live.meshdata.FREE_NORMALS
        check(surface.data.has_custom_normals == custom, f"live: custom normals {custom}")
    # Raw, the field's normals become custom normals in every Blender.
    s.render.raw = True
    check(live.update(scene, render=True), "live render, raw")
    want = splash_sph.reconstruct(p.positions, SPACING, cell="r/2", field="ssp07", raw=True)
    loop_n, loop_v = split_normals(surface)
    check(
        surface.data.has_custom_normals
        and np.sum(loop_n * want.normals[loop_v], axis=1).min() > 0.9999,
        "live render, raw: the field's normals as custom normals",
    )
    s.render.raw = False
    for rendering in (False, True):
        live.update(scene, render=rendering)
        check("cached" in s.status, f"live: back to a setting seen, from the cache ({s.status})")
    # The panel's command line, run by the CLI, writes the surface live mode renders.
    s.input_path = os.path.join(REPO, "fixtures/frame_0040.ply")
    s.output_path = os.path.join(WORK, "cli", "frame_0040.ply")
    line = command.to_command(ui._settings(scene))
    subprocess.run([SPLASH, *shlex.split(line)[1:], "-q"], check=True)
    table = ply_table(s.output_path)
    v, f = mesh_arrays(surface)
    check(
        np.array_equal(v, np.stack([table[k] for k in "xyz"], 1))
        and np.array_equal(
            velocity_of(surface), np.stack([table[k] for k in ("vx", "vy", "vz")], 1)
        ),
        f"the copied command line writes the live render surface: {line}",
    )
    # Errors land in the panel, not in an exception.
    s.viewport.cell = "banana"
    check(not live.update(scene, render=False), "live: a bad cell fails")
    check("banana" in s.error, f"live: the error names the bad cell ({s.error})")
    s.viewport.cell = "r"
    empty = bpy.data.objects.new("empty", bpy.data.meshes.new("empty"))
    scene.collection.objects.link(empty)
    s.source = empty
    check(not live.update(scene, render=False), "live: no particles fails")
    check("no vertices" in s.error, f"live: says there are no particles ({s.error})")
    s.source = None
    check(not live.update(scene, render=False), "live: no object fails")
    # Frame changes reconstruct with the viewport settings, a render with the render ones.
    counts = {}
    for rendering, q in ((False, s.viewport), (True, s.render)):
        mesh = splash_sph.reconstruct(
            p.positions, SPACING, cell=q.cell, field=q.field, normals=q.normals, raw=q.raw
        )
        counts[rendering] = len(mesh.faces)
    s.source = source
    scene.frame_set(scene.frame_current + 1)
    check(s.error == "", f"live frame change: no error ({s.error})")
    check(len(surface.data.polygons) == counts[False], "live frame change: viewport settings")
    seen = []

    def during(scene, *_):
        seen.append(len(surface.data.polygons))

    bpy.app.handlers.render_post.append(during)
    render(os.path.join(WORK, "live.png"), "BLENDER_WORKBENCH", (32, 32))
    bpy.app.handlers.render_post.remove(during)
    check(seen == [counts[True]], f"live render: render settings ({seen} vs {counts[True]})")
    check(len(surface.data.polygons) == counts[False], "live after the render: viewport again")
    s.enabled = False
    # A particle sequence imported by the add-on (velocity kept) as live mode's source.
    scene.frame_set(1)
    result = bpy.ops.splash.import_particles(directory=os.path.join(WORK, "particles"))
    check(result == {"FINISHED"}, "import a particle sequence")
    points = next(o for o in scene.objects if o.splash_sequence.particles)
    s.source, s.enabled = points, True
    scene.frame_set(2)
    check(len(points.data.vertices) == len(p), "the particle object follows the frame")
    want = splash_sph.reconstruct(
        p.positions, SPACING, cell=s.viewport.cell, field=s.viewport.field, normals="none",
        raw=s.viewport.raw, attributes={"velocity": p["velocity"]},
    )  # fmt: skip
    v, f = mesh_arrays(live.surface_object(scene, points))
    check(np.array_equal(f, want.faces), "live on the imported particles: the package's mesh")
    check(
        np.array_equal(
            velocity_of(live.surface_object(scene, points)), want.attributes["velocity"]
        ),
        "live on the imported particles: their velocity",
    )
    # Played forward, the next file's surface is made in the background meanwhile: the
    # package's mesh, with the settings and particles of the frame it is shown at.
    ball = splash_sph.read_particles(os.path.join(WORK, "particles", "frame_0003.ply"))

    def shows(cell, what):
        want = splash_sph.reconstruct(
            ball.positions, SPACING, cell=cell, field=s.viewport.field, normals="none",
            raw=s.viewport.raw, attributes={"velocity": ball["velocity"]},
        )  # fmt: skip
        v, f = mesh_arrays(live.surface_object(scene, points))
        check(
            np.array_equal(v, want.vertices) and np.array_equal(f, want.faces),
            f"live, {what}: the package's mesh",
        )

    scene.frame_set(3)
    check("read ahead" in s.status, f"live played forward: read ahead ({s.status})")
    shows("r", "read ahead")
    # Settings changed meanwhile: what was made ahead is dropped.
    s.cache_mb = 0
    for frame in (1, 2):
        scene.frame_set(frame)
    s.viewport.cell = "2r"
    scene.frame_set(3)
    check("read ahead" not in s.status, f"live: a stale read-ahead is dropped ({s.status})")
    shows("2r", "the settings changed after the read-ahead started")
    # A modifier may move the particles: no read-ahead.
    points.modifiers.new("move", "DISPLACE")
    for frame in (1, 2, 3):
        scene.frame_set(frame)
    check("read ahead" not in s.status, f"live: no read-ahead through a modifier ({s.status})")
    points.modifiers.remove(points.modifiers[0])
    # Frame 4 shows the last file still: its surface stays, not reconstructed again.
    scene.frame_set(3)
    scene.frame_set(4)
    check(s.status.startswith("frame 3:"), f"live: a held file keeps its surface ({s.status})")
    s.viewport.cell, s.cache_mb = "r", 1024
    s.enabled = False


def closed(faces):
    """Whether every edge of the triangles `faces` is shared by exactly two of them, once in
    each direction (closed, manifold and consistently wound)."""
    a = faces.astype(np.int64)
    half = np.concatenate([a[:, [0, 1]], a[:, [1, 2]], a[:, [2, 0]]])
    n = int(a.max()) + 1
    forward = np.sort(half[:, 0] * n + half[:, 1])
    backward = np.sort(half[:, 1] * n + half[:, 0])
    return len(np.unique(forward)) == len(forward) and np.array_equal(forward, backward)


def test_post(live, splash_sph, command, ui):
    """The panel's post-processing options, each against the package's own mesh and for the
    change it makes: raw, decimate, smallest component, clip box; and the command line."""
    scene = bpy.context.scene
    s = scene.splash
    p = splash_sph.read_particles(os.path.join(REPO, "fixtures/frame_0040.ply"))
    lo, hi = p.positions.min(0), p.positions.max(0)
    # A lone particle 12 r beyond the fluid: a droplet of its own.
    droplet = np.array([hi[0] + 12 * SPACING, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2])
    positions = np.vstack([p.positions, droplet]).astype(np.float32)
    me = bpy.data.meshes.new("post_particles")
    me.vertices.add(len(positions))
    me.vertices.foreach_set("co", positions.ravel())
    source = bpy.data.objects.new("post_particles", me)
    source.location = (1.0, 2.0, 3.0)  # the clip box is taken in the particles' space
    scene.collection.objects.link(source)
    s.source, s.spacing, s.velocity, s.enabled = source, SPACING, False, False
    q = s.render
    q.cell, q.field, q.normals = "r", "ssp07", "none"
    surface = live.surface_object(scene, source)

    def shown(**post):
        check(live.update(scene, render=True), f"live with {post or 'defaults'}: {s.error}")
        v, f = mesh_arrays(surface)
        want = splash_sph.reconstruct(positions, SPACING, cell="r", field="ssp07",
                                      normals="none", **post)  # fmt: skip
        same = np.array_equal(v, want.vertices) and np.array_equal(f, want.faces)
        check(same, f"live with {post}: the package's mesh ({len(f)} triangles)")
        check(closed(f), f"live with {post}: closed and manifold")
        bpy.context.evaluated_depsgraph_get()  # as a redraw would
        corners = np.array(surface.bound_box)
        check(
            np.allclose(corners.min(0), v.min(0), atol=1e-6)
            and np.allclose(corners.max(0), v.max(0), atol=1e-6),
            f"live with {post}: the object's bounds are the new mesh's",
        )
        return v, f

    q.raw = True
    v_raw, f_raw = shown(raw=True)
    q.raw = False
    v_def, f_def = shown()
    # The default keeps the engine's triangles (no refinement: it flickers in sequences) and
    # moves the vertices.
    check(np.array_equal(f_def, f_raw), f"post-processed: the engine's {len(f_raw)} faces kept")
    moved = np.linalg.norm(v_raw - v_def, axis=1)
    check(moved.max() > 0.05 * SPACING, f"post-processing moves the vertices ({moved.max():.2g})")
    # Dropping the parts under 0 r³ keeps them all: new settings, the same counts, so the mesh
    # is updated in place.
    q.use_min_component, q.min_component = True, 0.0
    _, f_kept = shown(min_component=0.0)
    check("in place" in s.status, f"the same counts: the mesh updated in place ({s.status})")
    check(np.array_equal(f_kept, f_def), "min_component 0 r³: every part kept")
    q.use_min_component = False

    q.use_decimate, q.decimate = True, 0.1
    _, f_dec = shown(decimate="0.1r")
    check(len(f_dec) < 0.9 * len(f_def), f"decimate 0.1 r: {len(f_def)} -> {len(f_dec)} faces")
    q.use_decimate = False

    def near_droplet(v):
        return int(np.sum(np.linalg.norm(v - droplet, axis=1) < 3 * SPACING))

    check(near_droplet(v_def) > 0, f"the droplet has a surface ({near_droplet(v_def)} vertices)")
    q.use_min_component, q.min_component = True, 2.0
    v_min, f_min = shown(min_component=2.0)
    check(near_droplet(v_min) == 0, "smallest component 2 r³: the lone droplet dropped")
    check(len(f_def) > len(f_min) > 0.9 * len(f_def), "... and the fluid kept")
    q.use_min_component = False

    centre = (lo + hi) / 2
    empty = bpy.data.objects.new("post_box", None)
    empty.empty_display_type = "CUBE"
    empty.empty_display_size = float(0.3 * (hi - lo).min())
    empty.location = Vector(centre.tolist()) + source.location
    scene.collection.objects.link(empty)
    bpy.context.view_layer.update()  # the objects' matrix_world
    s.clip_object = empty
    a = empty.empty_display_size
    box = live.clip_box(empty, source)
    check(
        np.allclose(box, (*(centre - a), *(centre + a)), atol=1e-6),
        "the clip box in the particles' space",
    )
    v_box, f_box = shown(mesh_aabb=box)
    inside = np.all((v_box >= np.array(box[:3]) - 1e-5) & (v_box <= np.array(box[3:]) + 1e-5))
    check(inside and 0 < len(f_box) < len(f_def), f"clip box: {len(f_box)} faces inside")

    # All of them at once, copied as a command line that the CLI runs on the same particles.
    q.use_decimate, q.use_min_component = True, True
    v_all, f_all = shown(decimate="0.1r", min_component=2.0, mesh_aabb=box)
    frame = os.path.join(WORK, "post_particles.ply")
    write_particles_ply(frame, positions, np.zeros_like(positions))
    s.input_path, s.output_path = frame, os.path.join(WORK, "cli", "post.ply")
    line = command.to_command(ui._settings(scene))
    check("--decimate 0.1r --min-component 2 --mesh-aabb" in line, f"copied: {line}")
    subprocess.run([SPLASH, *shlex.split(line)[1:], "-q"], check=True)
    table = ply_table(s.output_path)
    check(
        np.array_equal(v_all, np.stack([table[k] for k in "xyz"], 1)),
        "the copied command line with post-processing writes the live render surface",
    )
    parsed, ignored = command.from_command(line)
    check(
        (parsed.get("raw"), parsed["decimate"], parsed["min_component"]) == (None, 0.1, 2.0)
        and any(w.startswith("--mesh-aabb") for w in ignored),
        f"the line read back: decimate and smallest component, the box ignored ({ignored})",
    )
    check(
        abs(command.from_command("splash recon x --spacing 0.02 --decimate 0.004 --raw")[0]
            ["decimate"] - 0.2) < 1e-9,
        "a decimation length read back in spacings",
    )  # fmt: skip
    # A box without volume is an error in the panel.
    empty.scale.z = 0.0
    bpy.context.view_layer.update()
    check(not live.update(scene, render=True), "a flat clip box fails")
    check("flat" in s.error and "post_box" in s.error, f"... and says so ({s.error})")
    s.clip_object = None
    q.raw, q.use_decimate, q.use_min_component, q.normals = False, False, False, "field"
    s.source = None


class _Layout:
    """Records what a panel draws, refusing a property its data does not have (Blender only
    prints those)."""

    def __init__(self, drawn):
        self.drawn, self.alert, self.active = drawn, False, True

    def prop(self, data, name, **_):
        check(name in data.bl_rna.properties, f"the panel draws {type(data).__name__}.{name}")
        self.drawn.append(name)

    def box(self):
        return _Layout(self.drawn)

    column = row = lambda self, **_: _Layout(self.drawn)

    def label(self, **_):
        pass

    def operator(self, *_, **__):
        return type("Properties", (), {})()


def test_panel(ui):
    drawn = []
    panel = type("Panel", (), {"layout": _Layout(drawn)})()
    ui.VIEW3D_PT_splash.draw(panel, bpy.context)
    want = {"raw", "use_decimate", "decimate", "use_min_component", "min_component", "clip_object",
            "correct", "volume_scope", "temporal"}  # fmt: skip
    check(want <= set(drawn), f"the panel shows the post-processing options ({sorted(want)})")


def test_errors(sequence):
    bad = os.path.join(WORK, "bad")
    os.makedirs(bad, exist_ok=True)
    with open(os.path.join(bad, "frame_0001.ply"), "wb") as f:
        f.write(b"ply\nformat binary_little_endian 1.0\nelement vertex 100\nproperty float x\n")
    try:
        sequence.import_sequence(bpy.context, bad, "Y", name="bad")
        check(False, "a broken file fails the import")
    except sequence.SequenceError as e:
        check("frame_0001.ply" in str(e), f"the import error names the file ({e})")
    check("bad" not in bpy.data.objects, "a failed import leaves no object behind")
    # Called from a script, an operator's error report arrives as a RuntimeError.
    try:
        bpy.ops.splash.import_sequence(directory=os.path.join(WORK, "nowhere"))
        check(False, "the import operator fails on a missing directory")
    except RuntimeError as e:
        check("cannot list" in str(e) and "nowhere" in str(e), f"the operator's report: {e}")


def test_command(command, ui):
    scene = bpy.context.scene
    s = scene.splash
    s.spacing, s.velocity, s.input_path, s.output_path = 0.014, True, "sim/", "mesh/"
    s.render.cell, s.render.field = "r/2", "ssp07"
    check(bpy.ops.splash.copy_command() == {"FINISHED"}, "copy as CLI command")
    # Headless Blender has no clipboard: the operator copies what this gives.
    line = command.to_command(ui._settings(scene))
    check(
        line == "splash recon sim/ --spacing 0.014 --cell r/2 --field ssp07 --normals field "
        "--attributes velocity --format ply -o mesh/",
        f"copy as CLI command: {line}",
    )
    other = "splash recon 'my sim/' --particle-radius 0.01 --cell 2r --field zb05 -o out/ -v"
    check(bpy.ops.splash.paste_command(line=other) == {"FINISHED"}, "paste a command line")
    check(
        (s.input_path, abs(s.spacing - 0.02) < 1e-7, s.render.cell, s.render.field, s.output_path)
        == ("'my sim/'", True, "2r", "zb05", "out/"),
        "the pasted line sets the panel",
    )
    post = "splash recon x --raw --decimate 0.2r --min-component 3 --mesh-aabb 0,0,0,1,1,1"
    check(bpy.ops.splash.paste_command(line=post) == {"FINISHED"}, "paste post-processing")
    q = s.render
    check(
        (q.raw, q.use_decimate, abs(q.decimate - 0.2) < 1e-6, q.use_min_component,
         q.min_component, s.clip_object) == (True, True, True, True, 3.0, None),
        "the pasted line sets raw, decimate and the smallest component, not the box",
    )  # fmt: skip
    bpy.ops.splash.paste_command(line=other)
    check(
        (q.raw, q.use_decimate, q.use_min_component) == (False, False, False),
        "a line without them turns them off",
    )
    try:
        bpy.ops.splash.paste_command(line="ls -l")
        check(False, "a line that is not splash recon is refused")
    except RuntimeError as e:
        check("splash recon" in str(e), f"the paste operator's report: {e}")
    parsed, _ = command.from_command(command.to_command(
        {"input": "a b/", "spacing": 0.5, "cell": "r", "field": "density", "normals": "grid",
         "engine": "slices", "velocity": False, "output": "o/"}))  # fmt: skip
    check(parsed["input"] == "'a b/'" and parsed["engine"] == "slices", "command round trip")
    line = "splash recon x --correct=2 --volume-scope component --temporal"
    check(bpy.ops.splash.paste_command(line=line) == {"FINISHED"}, "paste correct, volume scope")
    check((q.correct, q.volume_scope, q.temporal) == (2, "component", True), "the pasted line sets them")
    copied = command.to_command(ui._settings(scene))
    check("--correct=2 --volume-scope component --temporal" in copied, f"and copies them: {copied}")
    bpy.ops.splash.paste_command(line=other)
    check((q.correct, q.volume_scope, q.temporal) == (0, "frame", False), "a line without them resets them")


def camera_on(obj, scale_margin=1.3):
    scene = bpy.context.scene
    corners = np.array([obj.matrix_world @ Vector(c) for c in obj.bound_box])
    lo, hi = corners.min(0), corners.max(0)
    centre = (lo + hi) / 2
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    scene.collection.objects.link(cam)
    cam.data.type = "ORTHO"
    cam.data.ortho_scale = float(max(hi[0] - lo[0], hi[2] - lo[2])) * scale_margin
    cam.location = (centre[0], lo[1] - 2.0, centre[2])
    cam.rotation_euler = (np.pi / 2, 0.0, 0.0)  # looks along +y
    scene.camera = cam
    return cam


def render(path, engine, size):
    scene = bpy.context.scene
    scene.render.engine = engine
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.render.filepath = path
    scene.render.image_settings.file_format = "PNG"
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(path)
    pixels = np.array(image.pixels[:], np.float32).reshape(size[1], size[0], -1)
    bpy.data.images.remove(image)
    return pixels


def test_renders(seqs):
    scene = bpy.context.scene
    for obj in scene.objects:
        obj.hide_render = obj.type == "MESH" and obj != seqs["ply"]
    scene.frame_set(2)
    camera_on(seqs["ply"])
    img = render(os.path.join(WORK, "workbench.png"), "BLENDER_WORKBENCH", (96, 64))
    rgb = img[..., :3]
    background = np.median(np.concatenate([rgb[0], rgb[-1]]), axis=0)
    covered = np.mean(np.abs(rgb - background).sum(-1) > 0.05)
    check(covered > 0.1, f"workbench: the fluid covers {covered:.0%} of the image")
    # Cycles, frame 3: the ball moves along +x at 3 m/s; its velocity attribute blurs it.
    scene.frame_set(3)
    scene.camera.location.x = 0.6
    scene.camera.location.z = 0.3  # the ball's centre: (0.6, 0.3, 0.4) Y-up
    scene.camera.data.ortho_scale = 0.6
    scene.render.fps = 24
    scene.render.use_motion_blur = True
    scene.render.motion_blur_shutter = 1.0
    scene.cycles.samples = 8
    scene.cycles.use_denoising = False
    scene.cycles.device = "CPU"
    blurred = render(os.path.join(WORK, "cycles_blur.png"), "CYCLES", (64, 48))
    vel = seqs["ply"].data.attributes["velocity"]
    vel.data.foreach_set("vector", np.zeros(3 * len(vel.data), np.float32))
    still = render(os.path.join(WORK, "cycles_still.png"), "CYCLES", (64, 48))

    def extent(img):
        # Columns where the ball covers any pixel at all: blur widens it along x.
        bg = np.median(img[0, :, :3], axis=0)
        return int((np.abs(img[..., :3] - bg).sum(-1) > 0.02).any(0).sum())

    check(extent(still) > 5, f"cycles: the ball is in the picture ({extent(still)} columns)")
    check(
        extent(blurred) >= extent(still) + 3,
        f"cycles: velocity blurs the ball along x ({extent(still)} -> {extent(blurred)} columns)",
    )


def test_follow(live, sequence, splash_sph):
    """Render settings that follow the fluid: an imported particle sequence whose files carry
    ids follows its neighbours where it has both (the package's reconstruct with ids and
    neighbours), and its first frame is post-processed alone, saying why."""
    scene = bpy.context.scene
    directory = os.path.join(WORK, "follow")
    os.makedirs(directory, exist_ok=True)
    k = np.arange(-6, 7) * SPACING
    lattice = np.stack(np.meshgrid(k, k, k, indexing="ij"), -1).reshape(-1, 3)
    ball = lattice[np.linalg.norm(lattice, axis=1) <= 6 * SPACING].astype(np.float32)
    ids = np.arange(len(ball), dtype=np.float32)
    frames = []
    for n in range(3):
        # Moving and swelling a little, so that the neighbours do not quite agree.
        xyz = (ball * (1 + 0.01 * n) + [0.3 * SPACING * n, 0, 0]).astype(np.float32)
        frames.append(xyz)
        header = (
            f"ply\nformat binary_little_endian 1.0\nelement vertex {len(xyz)}\n"
            + "".join(f"property float {c}\n" for c in ("x", "y", "z", "id"))
            + "end_header\n"
        )
        with open(f"{directory}/frame_{n + 1:04d}.ply", "wb") as f:
            f.write(header.encode())
            f.write(np.column_stack([xyz, ids]).astype("<f4").tobytes())
    obj, _ = sequence.import_sequence(bpy.context, directory, "Z", name="follow", particles=True)
    got = obj.data.attributes.get("id")
    check(
        got is not None and got.data_type == "INT",
        "particle ids become Blender's own id attribute (INT), which takes no other type",
    )
    s = scene.splash
    s.source, s.spacing, s.render.temporal = obj, SPACING, True
    s.render.cell, s.render.field, s.render.normals = "r/2", "ssp07", "field"
    surface = live.surface_object(scene, obj)
    scene.frame_set(2)
    check(live.update(scene, render=True), f"following: frame 2 ({s.error})")
    check("following the fluid" in s.status, f"following: frame 2 follows ({s.status})")
    i = ids.astype(np.int64)
    want = splash_sph.reconstruct(
        frames[1], SPACING, ids=i, neighbours=((frames[0], i), (frames[2], i)),
        cell="r/2", field="ssp07", normals="field",
    )  # fmt: skip
    alone = splash_sph.reconstruct(frames[1], SPACING, cell="r/2", field="ssp07")
    v, f = mesh_arrays(surface)
    check(
        np.array_equal(v, want.vertices) and np.array_equal(f, want.faces),
        "following: the package's surface that follows the fluid",
    )
    check(not np.array_equal(v, alone.vertices), "following: not the frame alone's surface")
    scene.frame_set(1)
    check(live.update(scene, render=True), f"following: frame 1 ({s.error})")
    check(
        "alone: no file before or after it" in s.status,
        f"following: the first frame alone, saying why ({s.status})",
    )
    s.render.temporal = False
    s.enabled = False


def install():
    """Installs and enables the zip: an extension (it has blender_manifest.toml) through the
    extensions platform into the local repository, whose Python package is
    bl_ext.user_default.splash_blender and which installs the bundled wheel itself; a legacy
    add-on as `splash_blender`. Returns the add-on's modules and where splash_sph must come
    from."""
    with zipfile.ZipFile(ZIP) as z:
        extension = "blender_manifest.toml" in z.namelist()
    if extension:
        result = bpy.ops.extensions.package_install_files(
            filepath=ZIP, repo="user_default", enable_on_install=True
        )
        check(result == {"FINISHED"}, f"extension installed ({result})")
        package = "bl_ext.user_default.splash_blender"
        check(package in bpy.context.preferences.addons, "extension enabled")
        # Blender unpacks the extensions' wheels into a site-packages of its own.
        origin = bpy.utils.user_resource("EXTENSIONS", path=".local")
    else:
        bpy.ops.preferences.addon_install(filepath=ZIP)
        bpy.ops.preferences.addon_enable(module="splash_blender")
        package = "splash_blender"
        origin = None
    modules = [importlib.import_module(f"{package}.{m}") for m in MODULES]
    print(f"splash: installed {os.path.basename(ZIP)} as {package}")
    return modules, origin or os.path.dirname(modules[1].__file__)


MODULES = ("command", "live", "sequence", "ui", "vendor")


def main():
    (command, live, sequence, ui, vendor), origin = install()
    splash_sph = vendor.splash_sph()
    check(splash_sph.__file__.startswith(origin), f"the bundled package ({splash_sph.__file__})")
    particles = make_particles()
    seqs = test_sequences(sequence, particles)
    test_vdb(particles, seqs, sequence)
    test_errors(sequence)
    test_live(live, splash_sph, command, ui)
    test_post(live, splash_sph, command, ui)
    test_panel(ui)
    test_command(command, ui)
    test_renders(seqs)
    test_follow(live, sequence, splash_sph)


try:
    main()
    print(f"blender add-on tests: {len(checks)} checks passed")
except Exception:
    traceback.print_exc()
    print(f"blender add-on tests: FAILED at: {checks[-1] if checks else 'setup'}")
    sys.stdout.flush()
    os._exit(1)
sys.stdout.flush()
if not bpy.app.binary_path:
    # The bpy module, not Blender: 4.2's frees the registered panels after Python has shut
    # down and crashes there (any add-on with a panel does), which Blender itself never does.
    os._exit(0)
