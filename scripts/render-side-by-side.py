"""Renders PLY meshes (and VDB level sets, meshed by Blender's Volume to Mesh at the grid's
resolution) side by side, left to right, with Blender's Workbench engine (orthographic camera,
studio light, smooth shading with each file's normals), for the pictures in docs/rendering.md
and docs/reference/vdb.md:

    blender -b --factory-startup --python scripts/render-side-by-side.py -- \
        --size 1200x400 -o out.png raw.ply default.ply peer.ply

The meshes keep their file coordinates and are shifted along x by the width of the widest one
(plus a gap), so that every panel shows the same part of the scene at the same scale. The
orthographic camera looks along --direction (x, y, z; it should be mostly across x) and frames
all of them.
"""

import argparse
import sys

import bpy
from mathutils import Vector


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="render-side-by-side.py")
    parser.add_argument("meshes", nargs="+", help="PLY or VDB files, left to right")
    parser.add_argument("-o", "--output", required=True, help="PNG to write")
    parser.add_argument("--size", default="1200x400", help="WIDTHxHEIGHT in pixels")
    parser.add_argument("--direction", default="0,-1,-0.5", help="view direction x,y,z")
    parser.add_argument("--gap", type=float, default=0.05, help="gap between panels, as a share")
    return parser.parse_args(argv)


def import_ply(path):
    before = set(bpy.data.objects)
    if bpy.app.version >= (4, 0, 0):
        bpy.ops.wm.ply_import(filepath=path)
    else:
        bpy.ops.import_mesh.ply(filepath=path)
    (obj,) = set(bpy.data.objects) - before
    for polygon in obj.data.polygons:
        polygon.use_smooth = True
    return obj


def import_vdb(path):
    """The zero level of the file's `surface` grid as a mesh object, as an artist gets it:
    File > Import > OpenVDB, then a Volume to Mesh modifier at the grid's own resolution."""
    bpy.ops.object.volume_import(filepath=path)
    volume = bpy.context.selected_objects[0]
    host = bpy.data.objects.new("vdb", bpy.data.meshes.new("vdb"))
    bpy.context.scene.collection.objects.link(host)
    mod = host.modifiers.new("level set", "VOLUME_TO_MESH")
    mod.object, mod.grid_name, mod.threshold, mod.resolution_mode = volume, "surface", 0.0, "GRID"
    evaluated = host.evaluated_get(bpy.context.evaluated_depsgraph_get())
    obj = bpy.data.objects.new("vdb mesh", bpy.data.meshes.new_from_object(evaluated))
    bpy.context.scene.collection.objects.link(obj)
    bpy.data.objects.remove(host)
    bpy.data.objects.remove(volume)
    for polygon in obj.data.polygons:
        polygon.use_smooth = True
    return obj


def bounds(obj):
    corners = [obj.matrix_world @ Vector(c) for c in obj.bound_box]
    low = Vector(tuple(min(c[i] for c in corners) for i in range(3)))
    high = Vector(tuple(max(c[i] for c in corners) for i in range(3)))
    return low, high


def main():
    args = arguments()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    objects = [import_vdb(p) if p.endswith(".vdb") else import_ply(p) for p in args.meshes]
    direction = Vector(tuple(float(v) for v in args.direction.split(","))).normalized()
    # Panels go toward the camera's right (direction × up), along ±x: left to right on screen.
    right = 1.0 if direction.cross(Vector((0.0, 0.0, 1.0))).x >= 0.0 else -1.0
    width = max(bounds(o)[1].x - bounds(o)[0].x for o in objects)
    for k, obj in enumerate(objects):
        obj.location.x += right * k * width * (1.0 + args.gap)
    bpy.context.view_layer.update()
    low = Vector(tuple(min(bounds(o)[0][i] for o in objects) for i in range(3)))
    high = Vector(tuple(max(bounds(o)[1][i] for o in objects) for i in range(3)))
    centre, size = (low + high) / 2, (high - low).length

    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    camera.data.type = "ORTHO"
    camera.location = centre - direction * size * 2
    camera.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
    scene.camera = camera
    bpy.context.view_layer.update()
    # Orthographic scale: the scene's extent across the view, corners projected.
    inverse = camera.matrix_world.inverted()
    extent = [inverse @ Vector((x, y, z)) for x in (low.x, high.x) for y in (low.y, high.y) for z in (low.z, high.z)]
    w, h = (int(v) for v in args.size.split("x"))
    across = max(c.x for c in extent) - min(c.x for c in extent)
    up = max(c.y for c in extent) - min(c.y for c in extent)
    camera.data.ortho_scale = 1.05 * max(across, up * w / h)

    scene.render.engine = "BLENDER_WORKBENCH"
    scene.display.shading.light = "STUDIO"
    scene.display.shading.color_type = "SINGLE"
    scene.display.shading.single_color = (0.55, 0.7, 0.9)
    scene.render.resolution_x, scene.render.resolution_y = w, h
    scene.render.film_transparent = False
    scene.render.filepath = args.output
    bpy.ops.render.render(write_still=True)


main()
