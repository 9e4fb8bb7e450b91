# SPDX-License-Identifier: GPL-2.0-or-later
"""Live mode: the scene's particle object reconstructed on every frame change.

The viewport settings apply in the viewport, the render settings from `render_init` to
`render_complete`/`render_cancel` (and for the frame a render starts on, `render_pre`).
Surfaces are cached by frame, settings and a checksum of the particles, so that scrubbing
back, or rendering a frame already seen, costs no reconstruction. Errors go to the panel
(`scene.splash.error`) and to the log, never to a traceback dialog.
"""

import logging
import os
import time
from collections import OrderedDict

import numpy as np

import bpy
from bpy.app.handlers import persistent
from mathutils import Vector

from . import ahead, meshdata, sequence, vendor

log = logging.getLogger("splash_blender")

SURFACE_TAG = "splash_surface_of"

_state = {"rendering": False}
_cache = OrderedDict()


class LiveError(Exception):
    """A problem to show the user (no particles, bad settings, a failing frame)."""


def quality(scene, render):
    """The settings group in force: render or viewport."""
    return scene.splash.render if render else scene.splash.viewport


def surface_object(scene, source):
    """The object showing `source`'s surface, created beside it the first time."""
    for obj in scene.objects:
        if obj.get(SURFACE_TAG) == source.name:
            return obj
    mesh = bpy.data.meshes.new(source.name + "_surface")
    obj = bpy.data.objects.new(source.name + "_surface", mesh)
    obj[SURFACE_TAG] = source.name
    collection = source.users_collection[0] if source.users_collection else scene.collection
    collection.objects.link(obj)
    return obj


def post_options(settings, q, source):
    """The package's post-processing keywords for the settings group `q`: `raw`,
    `volume_scope`, `decimate` (a length in r), `min_component` (r³) and `mesh_aabb`, the clip
    box in `source`'s space."""
    # Blender keeps floats as float32: 7 digits, as the copied command line writes them.
    return {
        "raw": q.raw,
        "volume_scope": q.volume_scope,
        "decimate": f"{q.decimate:.7g}r" if q.use_decimate else None,
        "min_component": float(f"{q.min_component:.7g}") if q.use_min_component else None,
        "mesh_aabb": clip_box(settings.clip_object, source),
    }


def shows_normals(q):
    """Whether the settings group `q`'s normals from splash become the surface's custom
    normals. A post-processed or decimated mesh's are its own area-weighted vertex normals,
    which Blender's smooth shading all but reproduces (cbd-small at the render settings:
    0.1-0.3 degrees apart on average, 1-3 at the 99th percentile). Blender 4.5 takes them as one
    attribute; before it only as split normals, which cost Blender 3.4 about 2 s of CPU per
    million triangles (setting them and every evaluation after): there they are left to
    Blender, and the package does not compute them."""
    if q.normals == "none":
        return False
    return meshdata.FREE_NORMALS or (q.raw and not q.use_decimate)


def clip_box(box, source):
    """(min x, min y, min z, max x, max y, max z): the bounds in `source`'s space (the world's
    without a source) of the object `box`'s bounding box (an Empty's: its display cube), or
    None without one. Raises LiveError for a box without volume."""
    if box is None:
        return None
    if box.type == "EMPTY":
        a = box.empty_display_size
        corners = [(x, y, z) for x in (-a, a) for y in (-a, a) for z in (-a, a)]
    else:
        corners = [tuple(c) for c in box.bound_box]
    to_source = box.matrix_world
    if source is not None:
        to_source = source.matrix_world.inverted() @ to_source
    points = [to_source @ Vector(c) for c in corners]
    lo = tuple(float(f"{min(p[i] for p in points):.7g}") for i in range(3))
    hi = tuple(float(f"{max(p[i] for p in points):.7g}") for i in range(3))
    if not all(a < b for a, b in zip(lo, hi)):
        raise LiveError(f"the clip box '{box.name}' is flat: its bounds are {lo} to {hi}")
    return lo + hi


def particles(source, depsgraph):
    """Positions (N, 3) and velocities (N, 3) or None of the evaluated `source`."""
    evaluated = source.evaluated_get(depsgraph) if depsgraph is not None else source
    mesh = evaluated.to_mesh()
    try:
        return meshdata.positions(mesh), meshdata.vector_attribute(mesh, "velocity")
    finally:
        evaluated.to_mesh_clear()


def reconstruct(scene, render, depsgraph=None):
    """Reconstructs the live source at the current frame into its surface object; returns
    the surface object. Raises LiveError with a message for the user."""
    settings = scene.splash
    source = settings.source
    frame = scene.frame_current
    if source is None:
        raise LiveError("choose the particle object in the splash panel")
    if depsgraph is None:
        try:
            depsgraph = bpy.context.evaluated_depsgraph_get()
        except (AttributeError, RuntimeError):
            depsgraph = None
    positions, velocities = particles(source, depsgraph)
    if len(positions) == 0:
        raise LiveError(f"'{source.name}' has no vertices (particles) at frame {frame}")
    if not settings.velocity:
        velocities = None
    splash_sph = vendor.splash_sph()
    try:
        if settings.spacing <= 0.0:
            settings.spacing = splash_sph.estimate_spacing(positions)
            log.info("splash: estimated spacing r = %g from frame %d", settings.spacing, frame)
        q = quality(scene, render)
        options = {
            "cell": _length(q.cell),
            "field": q.field,
            "normals": q.normals if shows_normals(q) else "none",
            "engine": q.engine,
            "correct": q.correct,
            **post_options(settings, q, source),
        }
        follow, alone = None, None
        if q.temporal and not q.raw:
            follow = neighbour_frames(source, positions)
            if isinstance(follow, str):
                follow, alone = None, follow
                log.warning("splash: frame %d post-processed alone: %s", frame, alone)
        # The frame is not part of the key: a sequence saved every n-th frame holds each
        # surface for n frames.
        key = ahead.key(
            source.name,
            positions,
            velocities,
            settings.spacing,
            options if follow is None else {**options, "temporal": True},
        )
        surface = surface_object(scene, source)
        if _state.get("shown") == (surface.name, key) and len(surface.data.vertices):
            # Already showing it (a render's frame_change_post, then its render_pre).
            surface.matrix_world = source.matrix_world
            settings.error = ""
            return surface
        started = time.perf_counter()
        arrays = _cache.get(key)
        cached, made_ahead = arrays is not None, False
        if cached:
            _cache.move_to_end(key)
        else:
            arrays = ahead.take(_sequence_file(source), key)
            made_ahead = arrays is not None
            if not made_ahead:
                arrays = ahead.surface(positions, velocities, settings.spacing, options, follow)
            _remember(key, arrays, settings.cache_mb * 1e6)
    except ValueError as e:
        raise LiveError(f"frame {frame}: {e}") from None
    in_place = meshdata.fill(surface.data, *arrays)
    _state["shown"] = (surface.name, key)
    surface.matrix_world = source.matrix_world
    seconds = time.perf_counter() - started
    settings.status = (
        f"frame {frame}: {len(positions)} particles, {len(arrays[1])} triangles, "
        f"{seconds:.2f} s ({'render' if render else 'viewport'}"
        f"{', cached' if cached else ''}{', read ahead' if made_ahead else ''}"
        f"{', in place' if in_place else ''}"
        f"{', following the fluid' if follow is not None else ''}"
        f"{f', alone: {alone}' if alone else ''})"
    )
    settings.error = ""
    if follow is None:
        # A surface made ahead would not follow its own neighbours.
        _read_ahead(source, frame, settings, options)
    return surface


def neighbour_frames(source, positions):
    """The (positions, ids) of the particle files before, at and after the one `source`
    shows, for a surface that follows the fluid; or why it cannot: not an imported particle
    sequence, a modifier or shape key changing its particles, the first or last file, a gap in
    the frame numbers, a file without particle ids or that cannot be read."""
    path = _sequence_file(source)
    if path is None:
        return "the particle object is not an imported particle sequence"
    if len(source.modifiers) or source.data.shape_keys is not None:
        return "a modifier or shape key changes the particles"
    group = source.splash_sequence
    try:
        files = sequence.frame_files(group.directory, particles=True)
    except sequence.SequenceError as e:
        return str(e)
    paths = [p for _, p in files]
    if path not in paths:
        return "its file is no longer in the sequence"
    i = paths.index(path)
    if i == 0 or i + 1 == len(paths):
        return "no file before or after it"
    numbers = [n for n, _ in files]
    steps = [b - a for a, b in zip(numbers, numbers[1:]) if b > a]
    if steps and max(numbers[i] - numbers[i - 1], numbers[i + 1] - numbers[i]) > min(steps):
        return "a gap in the frame numbers beside it"
    frames = []
    for p in paths[i - 1 : i + 2]:
        # Through the sequence's cache: frames rendered in order read each file once.
        try:
            xyz, _, _, attributes, _ = sequence.read(p, particles=True)
        except (sequence.SequenceError, OSError) as e:
            return f"cannot read '{os.path.basename(p)}': {e}"
        if "id" not in attributes:
            return f"'{os.path.basename(p)}' has no particle ids"
        ids = attributes["id"].astype(np.int64)
        frames.append((np.ascontiguousarray(xyz, dtype=np.float32), ids))
    if not np.array_equal(frames[1][0], positions):
        return "the object's particles are not its file's"
    return frames


def _sequence_file(source):
    """The particle file `source` shows, when it is an imported particle sequence."""
    group = source.splash_sequence
    return group.file if group.particles and group.directory and group.file else None


def _read_ahead(source, frame, settings, options):
    """Starts making the surface of the sequence's next file when frames go forward (played,
    stepped or rendered in order) and `source` shows its files as they are (no modifier
    or shape key changes its vertices)."""
    previous = _state.get("frame")
    _state["frame"] = (source.name, frame)
    path = _sequence_file(source)
    if (
        path is None
        or previous is None
        or previous[0] != source.name
        or previous[1] >= frame
        or len(source.modifiers)
        or source.data.shape_keys is not None
    ):
        return
    group = source.splash_sequence
    try:
        files = [p for _, p in sequence.frame_files(group.directory, particles=True)]
    except sequence.SequenceError:
        return
    if path in files and files.index(path) + 1 < len(files):
        ahead.start(
            files[files.index(path) + 1],
            source.name,
            settings.velocity,
            settings.spacing,
            options,
            known=lambda k: k in _cache,
        )


def _remember(key, arrays, limit):
    """Caches `arrays`, dropping the least recently used surfaces above `limit` bytes."""
    _cache[key] = arrays
    total = sum(_nbytes(a) for a in _cache.values())
    while _cache and total > limit:
        _, dropped = _cache.popitem(last=False)
        total -= _nbytes(dropped)


def _nbytes(arrays):
    vertices, faces, normals, attributes, edges = arrays
    extra = sum(a.nbytes for a in attributes.values()) + sum(a.nbytes for a in edges)
    return vertices.nbytes + faces.nbytes + (0 if normals is None else normals.nbytes) + extra


def _length(text):
    """A cell as the package takes it: "r/2" stays text, "0.01" becomes a number."""
    text = text.strip()
    try:
        return float(text)
    except ValueError:
        return text


def update(scene, render=None, depsgraph=None):
    """`reconstruct` for handlers and buttons: errors go to the panel and the log."""
    if render is None:
        render = _state["rendering"]
    try:
        reconstruct(scene, render, depsgraph)
        return True
    except (LiveError, RuntimeError, OSError) as e:
        scene.splash.error = str(e)
    except Exception as e:  # a handler must never raise into Blender
        scene.splash.error = f"unexpected error: {e!r}"
        log.exception("splash live mode")
    log.error("splash: %s", scene.splash.error)
    return False


def clear_cache():
    ahead.wait()
    _cache.clear()
    _state.pop("shown", None)
    _state.pop("frame", None)


def on_settings_changed(scene):
    if scene.splash.enabled:
        # Handlers change the mesh while a render thread may read the scene.
        scene.render.use_lock_interface = True
        update(scene, render=False)


def _live(scene):
    return scene.splash.enabled and scene.splash.source is not None


@persistent
def _frame_change_post(scene, depsgraph=None):
    # Cycles steps to subframes for motion blur: the surface stays the frame's, blurred by
    # its velocity attribute.
    if _live(scene) and not (_state["rendering"] and scene.frame_subframe != 0.0):
        update(scene, depsgraph=depsgraph)


@persistent
def _render_init(scene, *_):
    _state["rendering"] = True


@persistent
def _render_pre(scene, *_):
    _state["rendering"] = True
    if _live(scene):
        update(scene, render=True)


@persistent
def _render_done(scene, *_):
    _state["rendering"] = False
    if _live(scene):
        update(scene, render=False)


_handlers = (
    (bpy.app.handlers.frame_change_post, _frame_change_post),
    (bpy.app.handlers.render_init, _render_init),
    (bpy.app.handlers.render_pre, _render_pre),
    (bpy.app.handlers.render_complete, _render_done),
    (bpy.app.handlers.render_cancel, _render_done),
)


def register():
    for handlers, handler in _handlers:
        if handler not in handlers:
            handlers.append(handler)


def unregister():
    for handlers, handler in _handlers:
        if handler in handlers:
            handlers.remove(handler)
    clear_cache()
