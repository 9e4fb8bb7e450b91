# SPDX-License-Identifier: GPL-2.0-or-later
"""Live mode's read-ahead: while Blender shows a frame of a particle sequence, played
forward, the sequence's next file is read and reconstructed on one background thread (the
package releases the GIL while it works), so that the next frame change finds its surface
made. The thread touches no Blender data: it gets the file's path and the settings as plain
values. Its surface is used only for the same cache key (checksums of the particles Blender
then evaluates, the settings); anything else (a modifier on the particle object, a setting
changed meanwhile) makes live mode reconstruct the frame as without it.
"""

import zlib
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from . import vendor

_pool = None
_job = {}  # "path": the file being made, "settings", "future": its (key, arrays) or None
_last = None  # the future last submitted, taken or not


def key(name, positions, velocities, spacing, options):
    """The cache key of a surface: the particle object's name, the particles' count and
    checksums, the spacing and the package's keyword arguments."""
    return (
        name,
        len(positions),
        zlib.crc32(positions),
        None if velocities is None else zlib.crc32(velocities),
        round(spacing, 9),
        tuple(options.items()),
    )


def surface(positions, velocities, spacing, options, follow=None):
    """(vertices, faces, normals or None, attributes, edges) of the package's `reconstruct`,
    `edges` as `mesh_edges` gives them (which Blender would otherwise search for on the main
    thread). `follow`: the (positions, ids) of the frames before, at and after, for a surface
    that follows the fluid (`positions` are then the middle frame's)."""
    splash_sph = vendor.splash_sph()
    following = {}
    if follow is not None:
        following = {"ids": follow[1][1], "neighbours": (follow[0], follow[2])}
    mesh = splash_sph.reconstruct(
        positions,
        spacing,
        attributes=None if velocities is None else {"velocity": velocities},
        **following,
        **options,
    )
    normals = mesh.normals if len(mesh.normals) else None
    edges = splash_sph.mesh_edges(mesh.faces, len(mesh.vertices))
    return mesh.vertices, mesh.faces, normals, dict(mesh.attributes), edges


def start(path, name, velocity, spacing, options, known):
    """Reads and reconstructs the particle file `path` in the background (what live mode
    would make of it as object `name`), unless it is being made already. `velocity`: whether
    its `velocity` attribute is carried; `known(key)`: whether a surface is at hand already
    (then only the file is read)."""
    global _pool, _last
    if _job.get("path") == path or (_last is not None and not _last.done()):
        return  # one job at a time, never queued behind another
    if _pool is None:
        _pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="splash-ahead")

    def job():
        p = vendor.splash_sph().read_particles(path)
        # As Blender gives them back: float32 rows, velocity a float vector attribute.
        positions = np.ascontiguousarray(p.positions, dtype=np.float32)
        velocities = p.attributes.get("velocity") if velocity else None
        if velocities is not None:
            velocities = np.ascontiguousarray(velocities, dtype=np.float32)
            if velocities.shape != positions.shape:
                velocities = None
        k = key(name, positions, velocities, spacing, options)
        if known(k):
            return None
        return k, surface(positions, velocities, spacing, options)

    _job.update(path=path, settings=(name, round(spacing, 9), tuple(options.items())))
    _job["future"] = _last = _pool.submit(job)


def take(path, k):
    """The surface made ahead for the particle file `path` if its key is `k` (waiting for it
    while it is being made, when its settings are `k`'s), else None. Either way the job is
    done with."""
    if path is None or _job.get("path") != path:
        return None
    same_settings = _job["settings"] == (k[0], k[4], k[5])
    future = _job.pop("future")
    _job.clear()
    if not same_settings:
        return None  # not waited for: it runs on, unused
    try:
        made = future.result()
    except Exception:  # the frame is reconstructed again, which reports the error
        return None
    return made[1] if made is not None and made[0] == k else None


def wait():
    """Waits for the job in flight, if any, drops it and ends the thread."""
    global _pool, _last
    _job.clear()
    _last = None
    if _pool is not None:
        _pool.shutdown(wait=True)
        _pool = None
