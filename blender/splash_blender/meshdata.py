# SPDX-License-Identifier: GPL-2.0-or-later
"""numpy arrays into a Blender mesh, in bulk (`foreach_set`: no Python loop per vertex).

Smooth-shaded, with the file's or the field's vertex normals as custom split normals, and
every per-vertex attribute as a point attribute (`velocity` a FLOAT_VECTOR, which Cycles
blurs by when motion blur is on).
"""

import numpy as np


def fill(mesh, vertices, faces, normals=None, attributes=None):
    """Replaces `mesh`'s geometry: `vertices` (V, 3), `faces` (F, 3) indices, optional unit
    `normals` (V, 3) and `attributes` name -> (V, 3) or (V,) arrays."""
    vertices = np.ascontiguousarray(vertices, dtype=np.float32).reshape(-1, 3)
    faces = np.ascontiguousarray(faces, dtype=np.int32).reshape(-1, 3)
    mesh.clear_geometry()
    for name in [a.name for a in mesh.attributes if a.name in (attributes or {})]:
        mesh.attributes.remove(mesh.attributes[name])
    if len(vertices) == 0:
        mesh.update()
        return
    mesh.vertices.add(len(vertices))
    mesh.vertices.foreach_set("co", vertices.ravel())
    mesh.loops.add(3 * len(faces))
    mesh.loops.foreach_set("vertex_index", faces.ravel())
    mesh.polygons.add(len(faces))
    mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * len(faces), 3, dtype=np.int32))
    try:
        # Blender 3.x; in 4.x the offsets alone define the polygons.
        mesh.polygons.foreach_set("loop_total", np.full(len(faces), 3, dtype=np.int32))
    except (AttributeError, TypeError, RuntimeError):
        pass
    mesh.update(calc_edges=True)
    mesh.polygons.foreach_set("use_smooth", np.ones(len(faces), dtype=bool))
    custom = normals is not None and len(normals) == len(vertices)
    if hasattr(mesh, "use_auto_smooth"):
        # Blender < 4.1 uses custom normals only with it, and splits sharp edges with it.
        mesh.use_auto_smooth = custom
    if custom:
        # Blender's own cost, about 4 s per million triangles (lnor spaces), not the call's.
        mesh.normals_split_custom_set_from_vertices(np.ascontiguousarray(normals, dtype=np.float32))
    for name, values in (attributes or {}).items():
        values = np.ascontiguousarray(values, dtype=np.float32)
        if values.ndim == 2 and values.shape[1] == 3:
            attribute = mesh.attributes.new(name, "FLOAT_VECTOR", "POINT")
            attribute.data.foreach_set("vector", values.ravel())
        elif values.ndim == 1:
            attribute = mesh.attributes.new(name, "FLOAT", "POINT")
            attribute.data.foreach_set("value", values)
    mesh.update()


def positions(mesh):
    """The vertices of `mesh` as an (N, 3) float32 array."""
    out = np.empty(3 * len(mesh.vertices), dtype=np.float32)
    mesh.vertices.foreach_get("co", out)
    return out.reshape(-1, 3)


def vector_attribute(mesh, name):
    """The point attribute `name` of `mesh` as an (N, 3) float32 array, or None."""
    attribute = mesh.attributes.get(name)
    if attribute is None or attribute.domain != "POINT" or attribute.data_type != "FLOAT_VECTOR":
        return None
    out = np.empty(3 * len(mesh.vertices), dtype=np.float32)
    attribute.data.foreach_get("vector", out)
    return out.reshape(-1, 3)
