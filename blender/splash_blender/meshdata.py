# SPDX-License-Identifier: GPL-2.0-or-later
"""numpy arrays into a Blender mesh and out of it, in bulk (no Python loop per vertex).

`foreach_set`/`foreach_get` copy in one C loop only when the buffer's type is the one the
property stores, unsigned for vertex and loop indices (3.4: uint32 indices 30x faster than
int32), and Blender 3.5+ stores positions and corners as attributes, which take them in one
copy (4.5: 0.1 ms instead of 24-57 ms for 250 k triangles through `co`/`vertex_index`).
The edges come from the package where it gives them (Blender's own search for them took more
time than the rest of the filling). A mesh whose triangles are the ones it shows already (a
new frame of a particle sequence of the same count, the same frame raw or post-processed) only
gets its positions, normals and attributes rewritten. Smooth-shaded, with the file's or the
field's vertex normals as custom normals (Blender 4.5: a `custom_normal` point attribute, one
copy; before, split normals, which cost Blender about 4 s per million triangles), and every
per-vertex attribute as a point
attribute (`velocity` a FLOAT_VECTOR, which Cycles blurs by when motion blur is on).
"""

import bpy
import numpy as np
from mathutils import Matrix

_POSITION_ATTRIBUTE = bpy.app.version >= (3, 5, 0)
_CORNER_VERT_ATTRIBUTE = bpy.app.version >= (3, 6, 0)
FREE_NORMALS = bpy.app.version >= (4, 5, 0)
# Blender < 4.0 keeps each polygon's size; later ones derive it from the offsets.
_LOOP_TOTAL = not bpy.types.MeshPolygon.bl_rna.properties["loop_total"].is_readonly
_INTERNAL = ("position", "custom_normal")
_IDENTITY = Matrix.Identity(4)


def fill(mesh, vertices, faces, normals=None, attributes=None, edges=None):
    """Makes `mesh` show `vertices` (V, 3), `faces` (F, 3) indices, optional unit `normals`
    (V, 3), `attributes` name -> (V, 3) or (V,) arrays and `edges` as the package's
    `mesh_edges` gives them (else Blender finds them); in place when the triangles are the
    mesh's already. Returns whether it was in place."""
    vertices = np.ascontiguousarray(vertices, dtype=np.float32).reshape(-1, 3)
    faces = np.ascontiguousarray(faces, dtype=np.uint32).reshape(-1, 3)
    attributes = attributes or {}
    custom = normals is not None and len(normals) == len(vertices) and len(faces) > 0
    in_place = mesh.has_custom_normals == custom and _same_topology(mesh, len(vertices), faces)
    if in_place:
        _set_positions(mesh, vertices)
    else:
        _rebuild(mesh, vertices, faces, edges)
    if hasattr(mesh, "use_auto_smooth"):
        # Blender < 4.1 uses custom normals only with it, and splits sharp edges with it.
        mesh.use_auto_smooth = custom
    if custom:
        _set_normals(mesh, np.ascontiguousarray(normals, dtype=np.float32).reshape(-1, 3))
    for a in [a for a in mesh.attributes if _ours(a) and a.name not in attributes]:
        mesh.attributes.remove(a)
    for name, values in attributes.items():
        _set_attribute(mesh, name, np.ascontiguousarray(values, dtype=np.float32))
    mesh.update()
    return in_place


def _same_topology(mesh, count, faces):
    """Whether `mesh` has `count` vertices and exactly the triangles `faces`."""
    if (len(mesh.vertices), len(mesh.polygons), len(mesh.loops)) != (
        count, len(faces), 3 * len(faces)
    ):  # fmt: skip
        return False
    if len(faces) == 0:
        return len(mesh.edges) == 0
    return np.array_equal(_corner_verts(mesh), faces.ravel())


def _rebuild(mesh, vertices, faces, edges):
    mesh.clear_geometry()
    mesh.vertices.add(len(vertices))
    _set_positions(mesh, vertices)
    if len(faces) == 0:
        return
    corners = 3 * len(faces)
    mesh.loops.add(corners)
    if _CORNER_VERT_ATTRIBUTE:
        mesh.attributes[".corner_vert"].data.foreach_set("value", faces.view(np.int32).ravel())
    else:
        mesh.loops.foreach_set("vertex_index", faces.ravel())
    mesh.polygons.add(len(faces))
    mesh.polygons.foreach_set("loop_start", np.arange(0, corners, 3, dtype=np.uint32))
    if _LOOP_TOTAL:
        mesh.polygons.foreach_set("loop_total", np.full(len(faces), 3, dtype=np.uint32))
    if edges is None:
        mesh.update(calc_edges=True)
    else:
        _set_edges(mesh, *edges)
    if hasattr(mesh, "shade_smooth"):
        mesh.shade_smooth()  # Blender 4.1+: drops the sharp_face attribute
    else:
        mesh.polygons.foreach_set("use_smooth", np.ones(len(faces), dtype=bool))


def _set_edges(mesh, pairs, corner_edges):
    """The package's edges and each corner's (for 280 k triangles Blender 4.5's `calc_edges`
    took 35 ms and 3.4's 68; this 3 and 8)."""
    pairs = np.ascontiguousarray(pairs, dtype=np.uint32).ravel()
    corner_edges = np.ascontiguousarray(corner_edges, dtype=np.uint32)
    mesh.edges.add(len(pairs) // 2)
    verts = mesh.attributes.get(".edge_verts")  # Blender 4.0+
    if verts is not None:
        verts.data.foreach_set("value", pairs.view(np.int32))
    else:
        mesh.edges.foreach_set("vertices", pairs)
    corners = mesh.attributes.get(".corner_edge")  # Blender 3.6+
    if corners is not None:
        corners.data.foreach_set("value", corner_edges.view(np.int32))
    else:
        mesh.loops.foreach_set("edge_index", corner_edges)


def _corner_verts(mesh):
    if _CORNER_VERT_ATTRIBUTE:
        out = np.empty(len(mesh.loops), dtype=np.int32)
        mesh.attributes[".corner_vert"].data.foreach_get("value", out)
        return out.view(np.uint32)
    out = np.empty(len(mesh.loops), dtype=np.uint32)
    mesh.loops.foreach_get("vertex_index", out)
    return out


def _set_positions(mesh, vertices):
    if len(vertices) == 0:
        return  # Blender 4.x: an empty mesh has no position attribute
    if _POSITION_ATTRIBUTE:
        mesh.attributes["position"].data.foreach_set("vector", vertices.ravel())
        # Writing the attribute leaves the bounds cached for the old positions (4.5: the
        # viewport would cull by them); a transform tags them changed (1 ms per 125 k
        # vertices, the identity leaves every coordinate as it is).
        mesh.transform(_IDENTITY)
    else:
        mesh.vertices.foreach_set("co", vertices.ravel())


def _set_normals(mesh, normals):
    if FREE_NORMALS:
        # Blender 4.5's "free" custom normals: a float vector attribute, no lnor spaces.
        _set_attribute(mesh, "custom_normal", normals)
    else:
        mesh.normals_split_custom_set_from_vertices(normals)


def _set_attribute(mesh, name, values):
    """`values` (V, 3) as a FLOAT_VECTOR or (V,) as a FLOAT point attribute `name`, reusing
    the mesh's own when it has that type. Particle ids go to Blender's own `id`, an INT
    attribute (geometry nodes' stable ids), which takes no other type."""
    if values.ndim == 2 and values.shape[1] == 3:
        kind, key = "FLOAT_VECTOR", "vector"
    elif values.ndim == 1 and name == "id":
        kind, key = "INT", "value"
        values = values.astype(np.int32)
    elif values.ndim == 1:
        kind, key = "FLOAT", "value"
    else:
        return
    attribute = mesh.attributes.get(name)
    if attribute is not None and (attribute.data_type, attribute.domain) != (kind, "POINT"):
        mesh.attributes.remove(attribute)
        attribute = None
    if attribute is None:
        attribute = mesh.attributes.new(name, kind, "POINT")
    attribute.data.foreach_set(key, values.ravel())


def _ours(attribute):
    """A point attribute `fill` sets, not one of Blender's own."""
    return (
        attribute.domain == "POINT"
        and not attribute.name.startswith(".")
        and attribute.name not in _INTERNAL
    )


def positions(mesh):
    """The vertices of `mesh` as an (N, 3) float32 array."""
    out = np.empty(3 * len(mesh.vertices), dtype=np.float32)
    if len(out) == 0:
        pass
    elif _POSITION_ATTRIBUTE:
        mesh.attributes["position"].data.foreach_get("vector", out)
    else:
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
