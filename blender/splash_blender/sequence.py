# SPDX-License-Identifier: GPL-2.0-or-later
"""Farm sequences: a directory of `splash recon` outputs as one object whose mesh follows
the frame; likewise a directory of particle frames as an object of vertices only (with
every particle attribute, `velocity` included), the source of live mode.

Files are numbered as `splash recon` numbers them, by the package's `frame_number` (the last
run of digits in the name);
scene frame F shows the file of the largest number <= F - offset (the first file before
it), so a sequence saved every 3rd frame holds each mesh for 3 frames. Of several
extensions in one directory the commonest is used. The files are read by
`splash_sph.read_mesh` (normals, and `velocity` from PLY `vx vy vz` or VTK point data), since
Blender's own PLY importer drops both. A few recent frames are kept in memory.
"""

import logging
import math
import os
from collections import Counter, OrderedDict

import bpy
import numpy as np
from bpy.app.handlers import persistent

from . import meshdata, vendor

log = logging.getLogger("splash_blender")

EXTENSIONS = (".obj", ".ply", ".vtu", ".vtp")
# Level sets (`--format vdb`): Blender's own Volume sequence shows them.
VOLUME_EXTENSION = ".vdb"
# What splash_sph.read_particles reads.
PARTICLE_EXTENSIONS = (".ply", ".csv", ".txt", ".bin", ".raw", ".vtk", ".vtu", ".vtp", ".bgeo",
                       ".bgeo.gz", ".xyz")  # fmt: skip
_files_cache = {}
_mesh_cache = OrderedDict()
_MESH_CACHE_FRAMES = 8


class SequenceError(Exception):
    """A problem to show the user."""


def _extension(name):
    """The extension, lower case, `.bgeo.gz` counting as one."""
    if name.lower().endswith(".bgeo.gz"):
        return ".bgeo.gz"
    return os.path.splitext(name)[1].lower()


def frame_files(directory, particles=False, extensions=None):
    """[(frame number, path)] of the mesh (or particle, or `extensions`) files in
    `directory`, in number order."""
    directory = bpy.path.abspath(directory)
    extensions = extensions or (PARTICLE_EXTENSIONS if particles else EXTENSIONS)
    try:
        stamp = os.stat(directory).st_mtime_ns
        names = os.listdir(directory)
    except OSError as e:
        raise SequenceError(f"cannot list '{directory}': {e.strerror}") from None
    cached = _files_cache.get((directory, particles, extensions))
    if cached and cached[0] == stamp:
        return cached[1]
    try:
        frame_number = vendor.splash_sph().frame_number
    except RuntimeError as e:
        raise SequenceError(str(e)) from None
    found = []
    for name in names:
        ext = _extension(name)
        if ext not in extensions or name.startswith("."):
            continue
        number = frame_number(name)
        if number is not None:
            found.append((number, ext, os.path.join(directory, name)))
    if not found:
        what = "particle" if particles else "mesh"
        raise SequenceError(f"'{directory}' has no numbered {what} files ({', '.join(extensions)})")
    ext = Counter(e for _, e, _ in found).most_common(1)[0][0]
    files = sorted((n, p) for n, e, p in found if e == ext)
    _files_cache[(directory, particles, extensions)] = (stamp, files)
    return files


def file_for_frame(files, frame):
    """The path shown at `frame` (see the module's docs)."""
    chosen = files[0][1]
    for number, path in files:
        if number > frame:
            break
        chosen = path
    return chosen


def read(path, particles=False):
    """(vertices, faces, normals or None, attributes, edges or None) of the mesh or particle
    file `path`, through a small cache keyed by size and time."""
    stat = os.stat(path)
    key = (path, particles, stat.st_size, stat.st_mtime_ns)
    mesh = _mesh_cache.get(key)
    if mesh is None:
        splash_sph = vendor.splash_sph()
        try:
            if particles:
                p = splash_sph.read_particles(path)
                mesh = (p.positions, np.zeros((0, 3), np.uint32), None, p.attributes, None)
            else:
                m = splash_sph.read_mesh(path)
                normals = m.normals if len(m.normals) else None
                edges = splash_sph.mesh_edges(m.faces, len(m.vertices))
                mesh = (m.vertices, m.faces, normals, m.attributes, edges)
        except ValueError as e:
            raise SequenceError(str(e)) from None
        _mesh_cache[key] = mesh
        while len(_mesh_cache) > _MESH_CACHE_FRAMES:
            _mesh_cache.popitem(last=False)
    else:
        _mesh_cache.move_to_end(key)
    return mesh


def orient(obj):
    """Turns Y-up files upright in Blender's Z-up world: +90 degrees about X, which maps
    (x, y, z) to (x, -z, y) as `--up-axis z` does."""
    turn = math.pi / 2 if obj.splash_sequence.up_axis == "Y" else 0.0
    obj.rotation_euler = (turn, 0.0, 0.0)


def load(obj, frame):
    """Shows the file of `frame` in `obj`; errors go to its panel and the log."""
    group = obj.splash_sequence
    try:
        files = frame_files(group.directory, group.particles)
        path = file_for_frame(files, frame - group.frame_offset)
        if path == group.file and len(obj.data.vertices):
            return True
        meshdata.fill(obj.data, *read(path, group.particles))
        group.file = path
        group.error = ""
        return True
    except (SequenceError, RuntimeError, OSError) as e:
        group.error = f"frame {frame}: {e}"
    except Exception as e:  # a handler must never raise into Blender
        group.error = f"frame {frame}: unexpected error: {e!r}"
        log.exception("splash sequence")
    log.error("splash: %s: %s", obj.name, group.error)
    return False


def _has_volumes(directory):
    """Whether `directory` holds level sets (`.vdb`) and no meshes."""
    try:
        names = os.listdir(bpy.path.abspath(directory))
    except OSError:
        return False
    extensions = {_extension(n) for n in names if not n.startswith(".")}
    return VOLUME_EXTENSION in extensions and not extensions & set(EXTENSIONS)


def import_volumes(context, directory, up_axis="Y", name=None):
    """A new Volume object showing the level sets (`splash recon --format vdb`) in
    `directory` as Blender's own sequence, turned upright like a mesh sequence; raises
    SequenceError."""
    files = frame_files(directory, extensions=(VOLUME_EXTENSION,))
    folder = os.path.dirname(files[0][1])
    names = [os.path.basename(p) for _, p in files]
    result = bpy.ops.object.volume_import(
        filepath=files[0][1], directory=folder, files=[{"name": n} for n in names],
        use_sequence_detection=len(names) > 1,
    )  # fmt: skip
    obj = context.view_layer.objects.active
    if "FINISHED" not in result or obj is None or obj.type != "VOLUME":
        raise SequenceError(f"Blender could not import the level sets in '{folder}'")
    obj.name = name or os.path.basename(os.path.normpath(folder)) or "fluid"
    obj.splash_sequence.up_axis = up_axis
    orient(obj)
    return obj, files


def import_sequence(context, directory, up_axis="Y", name=None, particles=False):
    """A new object showing the sequence of meshes (or of particles: vertices only; or of
    level sets: a Volume) in `directory`; raises SequenceError."""
    if not particles and _has_volumes(directory):
        return import_volumes(context, directory, up_axis, name)
    files = frame_files(directory, particles)
    name = name or os.path.basename(os.path.normpath(bpy.path.abspath(directory))) or "fluid"
    obj = bpy.data.objects.new(name, bpy.data.meshes.new(name))
    context.collection.objects.link(obj)
    group = obj.splash_sequence
    group.directory = directory
    group.particles = particles
    group.up_axis = up_axis
    orient(obj)
    if not load(obj, context.scene.frame_current):
        error = group.error
        mesh = obj.data
        bpy.data.objects.remove(obj)
        bpy.data.meshes.remove(mesh)
        raise SequenceError(error)
    return obj, files


def sequences(scene):
    return [o for o in scene.objects if o.type == "MESH" and o.splash_sequence.directory]


@persistent
def _frame_change_pre(scene, *_):
    # Before the depsgraph evaluates the frame, and before live mode (frame_change_post)
    # reads a particle sequence's new frame.
    # Subframes (Cycles' motion steps) keep the frame's mesh: its velocity blurs it.
    if scene.frame_subframe != 0.0:
        return
    for obj in sequences(scene):
        load(obj, scene.frame_current)


def register():
    if _frame_change_pre not in bpy.app.handlers.frame_change_pre:
        bpy.app.handlers.frame_change_pre.append(_frame_change_pre)


def unregister():
    if _frame_change_pre in bpy.app.handlers.frame_change_pre:
        bpy.app.handlers.frame_change_pre.remove(_frame_change_pre)
    _mesh_cache.clear()
    _files_cache.clear()
