"""Renders one frame of a splash recon sequence with Cycles motion blur by velocity.

    splash recon sim/ --spacing 0.014 --attributes velocity --format ply -o mesh/
    blender -b --factory-startup --python examples/blender_motion_blur.py -- \
        --addon target/splash_blender.zip --meshes mesh/ --frame 22 --fps 40 -o blur.png

The add-on imports the directory as one object (Y-up data turned upright, the files' normals,
`velocity` as a point attribute); Cycles blurs each vertex along its velocity over the
shutter (`--shutter`, in frames). The default camera is POV-Ray's of examples/scene.pov
(<0.6, 0.9, -1.3> looking at <0.6, 0.2, 0.4>), turned to Blender's Z-up axes. Without `--addon`, the add-on must already be installed.
"""

import argparse
import math
import sys

import bpy

args = argparse.ArgumentParser()
args.add_argument("--addon")
args.add_argument("--meshes", required=True)
args.add_argument("--frame", type=int, default=22)
args.add_argument("--fps", type=int, default=40, help="the simulation's frames per second")
args.add_argument("--shutter", type=float, default=1.0, help="in frames; 0: no blur")
args.add_argument("--camera", default="0.6,1.3,0.9", help="Blender (Z-up) coordinates")
args.add_argument("--look-at", default="0.6,-0.4,0.2")
args.add_argument("--size", default="640x360")
args.add_argument("--samples", type=int, default=32)
args.add_argument("-o", "--output", required=True)
args = args.parse_args(sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else [])

if args.addon:
    bpy.ops.preferences.addon_install(filepath=args.addon)
bpy.ops.preferences.addon_enable(module="splash_blender")
from splash_blender import sequence  # noqa: E402

scene = bpy.context.scene
for obj in list(scene.objects):
    bpy.data.objects.remove(obj)
scene.frame_set(args.frame)
fluid, _ = sequence.import_sequence(bpy.context, args.meshes, "Y", name="fluid")

water = bpy.data.materials.new("water")
water.use_nodes = True
bsdf = water.node_tree.nodes["Principled BSDF"]
bsdf.inputs["Base Color"].default_value = (0.12, 0.35, 0.85, 1.0)
bsdf.inputs["Roughness"].default_value = 0.25
fluid.data.materials.append(water)

# The floor and the two far walls of the 1.2 x 1.0 x 0.8 m box (Y-up z in [0, 0.8] is
# Blender's y in [-0.8, 0]).
for size, location, rotation in (
    ((1.2, 0.8), (0.6, -0.4, 0.0), (0, 0, 0)),
    ((1.2, 1.0), (0.6, -0.8, 0.5), (math.pi / 2, 0, 0)),
    ((0.8, 1.0), (1.2, -0.4, 0.5), (math.pi / 2, 0, math.pi / 2)),
):
    bpy.ops.mesh.primitive_plane_add(location=location, rotation=rotation)
    bpy.context.object.scale = (size[0] / 2, size[1] / 2, 1)

sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
sun.data.energy = 3.0
sun.rotation_euler = (math.radians(40), math.radians(-20), math.radians(-30))
scene.collection.objects.link(sun)
scene.world = scene.world or bpy.data.worlds.new("world")
scene.world.use_nodes = True
scene.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.6

camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
scene.collection.objects.link(camera)
camera.location = [float(x) for x in args.camera.split(",")]
target = bpy.data.objects.new("target", None)
target.location = [float(x) for x in args.look_at.split(",")]
scene.collection.objects.link(target)
track = camera.constraints.new("TRACK_TO")
track.target, track.track_axis, track.up_axis = target, "TRACK_NEGATIVE_Z", "UP_Y"
camera.data.angle = math.radians(67.4)  # POV-Ray's default horizontal angle
scene.camera = camera

width, height = (int(x) for x in args.size.split("x"))
render = scene.render
render.engine = "CYCLES"
render.resolution_x, render.resolution_y, render.resolution_percentage = width, height, 100
render.fps = args.fps
render.use_motion_blur = args.shutter > 0  # --shutter 0: a still, to compare
render.motion_blur_shutter = max(args.shutter, 0.01)
scene.cycles.samples = args.samples
scene.cycles.use_denoising = False  # Debian's Blender has no denoiser
scene.cycles.device = "CPU"
render.filepath = args.output
render.image_settings.file_format = "PNG"
render.image_settings.color_mode = "RGB"
bpy.ops.render.render(write_still=True)
