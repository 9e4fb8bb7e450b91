# SPDX-License-Identifier: GPL-2.0-or-later
"""Farm sequences: a directory of `splash recon` outputs as one object whose mesh follows
the frame.

Files are numbered as `splash recon` numbers them (the last run of digits in the name);
scene frame F shows the file of the largest number <= F - offset (the first file before
it), so a sequence saved every 3rd frame holds each mesh for 3 frames. Of several
extensions in one directory the commonest is used. The files are read by
`splash_sph.read_mesh` (normals, and `velocity` from PLY `vx vy vz` or VTK point data), since
Blender's own PLY importer drops both. A few recent frames are kept in memory.
"""

import logging
import math
import os
import re
from collections import Counter, OrderedDict

import bpy
from bpy.app.handlers import persistent

from . import meshdata, vendor

log = logging.getLogger("splash_blender")

EXTENSIONS = (".obj", ".ply", ".vtu", ".vtp")
_NUMBER = re.compile(r"(\d+)(?!.*\d)")
_files_cache = {}
_mesh_cache = OrderedDict()
_MESH_CACHE_FRAMES = 8


class SequenceError(Exception):
    """A problem to show the user."""


def frame_files(directory):
    """[(frame number, path)] of the mesh files in `directory`, in number order."""
    directory = bpy.path.abspath(directory)
    try:
        stamp = os.stat(directory).st_mtime_ns
        names = os.listdir(directory)
    except OSError as e:
        raise SequenceError(f"cannot list '{directory}': {e.strerror}") from None
    cached = _files_cache.get(directory)
    if cached and cached[0] == stamp:
        return cached[1]
    found = []
    for name in names:
        stem, ext = os.path.splitext(name)
        match = _NUMBER.search(stem)
        if ext.lower() in EXTENSIONS and match and not name.startswith("."):
            found.append((int(match.group(1)), ext.lower(), os.path.join(directory, name)))
    if not found:
        raise SequenceError(f"'{directory}' has no numbered mesh files ({', '.join(EXTENSIONS)})")
    ext = Counter(e for _, e, _ in found).most_common(1)[0][0]
    files = sorted((n, p) for n, e, p in found if e == ext)
    _files_cache[directory] = (stamp, files)
    return files


def file_for_frame(files, frame):
    """The path shown at `frame` (see the module's docs)."""
    chosen = files[0][1]
    for number, path in files:
        if number > frame:
            break
        chosen = path
    return chosen


def read(path):
    """The mesh arrays of `path`, through a small cache keyed by size and time."""
    stat = os.stat(path)
    key = (path, stat.st_size, stat.st_mtime_ns)
    mesh = _mesh_cache.get(key)
    if mesh is None:
        try:
            mesh = vendor.splash_sph().read_mesh(path)
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
        path = file_for_frame(frame_files(group.directory), frame - group.frame_offset)
        if path == group.file and len(obj.data.vertices):
            return True
        mesh = read(path)
        normals = mesh.normals if len(mesh.normals) else None
        meshdata.fill(obj.data, mesh.vertices, mesh.faces, normals, mesh.attributes)
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


def import_sequence(context, directory, up_axis="Y", name=None):
    """A new object showing the sequence in `directory`; raises SequenceError."""
    files = frame_files(directory)
    name = name or os.path.basename(os.path.normpath(bpy.path.abspath(directory))) or "fluid"
    obj = bpy.data.objects.new(name, bpy.data.meshes.new(name))
    context.collection.objects.link(obj)
    group = obj.splash_sequence
    group.directory = directory
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
def _frame_change_post(scene, *_):
    # Subframes (Cycles' motion steps) keep the frame's mesh: its velocity blurs it.
    if scene.frame_subframe != 0.0:
        return
    for obj in sequences(scene):
        load(obj, scene.frame_current)


def register():
    if _frame_change_post not in bpy.app.handlers.frame_change_post:
        bpy.app.handlers.frame_change_post.append(_frame_change_post)


def unregister():
    if _frame_change_post in bpy.app.handlers.frame_change_post:
        bpy.app.handlers.frame_change_post.remove(_frame_change_post)
    _mesh_cache.clear()
    _files_cache.clear()
