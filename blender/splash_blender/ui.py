# SPDX-License-Identifier: GPL-2.0-or-later
"""The sidebar panel (3D Viewport > Sidebar > splash) and its operators. Operators report
errors in the status bar and the Info log (`self.report`), never as a traceback."""

import bpy
from bpy.props import BoolProperty, EnumProperty, StringProperty
from bpy_extras.io_utils import ImportHelper

from . import command, live, sequence


def _settings(scene):
    """The render settings as `command.to_command` takes them."""
    s = scene.splash
    q = s.render
    post = live.post_options(s, q, s.source)
    return {
        "input": s.input_path,
        "output": s.output_path,
        "spacing": s.spacing,
        "cell": q.cell,
        "field": q.field,
        "normals": q.normals,
        "engine": q.engine,
        "correct": q.correct,
        "velocity": s.velocity,
        "raw": q.raw,
        "volume_scope": q.volume_scope,
        "temporal": q.temporal,
        "decimate": q.decimate if q.use_decimate else None,
        "min_component": q.min_component if q.use_min_component else None,
        # The box is in the particle object's space, the files' coordinates.
        "mesh_aabb": post["mesh_aabb"],
    }


class SPLASH_OT_reconstruct(bpy.types.Operator):
    """Reconstruct the particle object at the current frame now"""

    bl_idname = "splash.reconstruct"
    bl_label = "Reconstruct"
    bl_options = {"REGISTER", "UNDO"}

    render: BoolProperty(name="Render settings", default=False)

    def execute(self, context):
        scene = context.scene
        if not live.update(scene, render=self.render):
            self.report({"ERROR"}, scene.splash.error)
            return {"CANCELLED"}
        self.report({"INFO"}, scene.splash.status)
        return {"FINISHED"}


class SPLASH_OT_clear_cache(bpy.types.Operator):
    """Forget the cached surfaces"""

    bl_idname = "splash.clear_cache"
    bl_label = "Clear cache"

    def execute(self, context):
        live.clear_cache()
        return {"FINISHED"}


class SPLASH_OT_copy_command(bpy.types.Operator):
    """Copy the splash recon command line of the render settings to the clipboard"""

    bl_idname = "splash.copy_command"
    bl_label = "Copy as CLI command"

    def execute(self, context):
        try:
            line = command.to_command(_settings(context.scene))
        except live.LiveError as e:
            self.report({"ERROR"}, f"splash: {e}")
            return {"CANCELLED"}
        context.window_manager.clipboard = line
        self.report({"INFO"}, line)
        return {"FINISHED"}


class SPLASH_OT_paste_command(bpy.types.Operator):
    """Set the panel from a splash recon command line (the clipboard's, by default)"""

    bl_idname = "splash.paste_command"
    bl_label = "Paste CLI command"
    bl_options = {"REGISTER", "UNDO"}

    line: StringProperty(name="Command line", default="")

    def execute(self, context):
        line = self.line or context.window_manager.clipboard
        try:
            parsed, ignored = command.from_command(line)
        except command.CommandError as e:
            self.report({"ERROR"}, f"splash: {e}")
            return {"CANCELLED"}
        s = context.scene.splash
        for key, target in (("input", "input_path"), ("output", "output_path")):
            if key in parsed:
                setattr(s, target, parsed[key])
        if "spacing" in parsed:
            s.spacing = parsed["spacing"]
        if "velocity" in parsed:
            s.velocity = parsed["velocity"]
        for key in ("cell", "field", "normals", "engine"):
            if key in parsed:
                setattr(s.render, key, parsed[key])
        # The correction and the post-processing options are at their defaults unless the
        # line names them, as in the CLI.
        q = s.render
        q.correct = parsed.get("correct", 0)
        q.raw = parsed.get("raw", False)
        q.volume_scope = parsed.get("volume_scope", "frame")
        q.temporal = parsed.get("temporal", False)
        q.use_decimate = "decimate" in parsed
        q.use_min_component = "min_component" in parsed
        if q.use_decimate:
            q.decimate = parsed["decimate"]
        if q.use_min_component:
            q.min_component = parsed["min_component"]
        if ignored:
            self.report({"WARNING"}, "splash: not in the panel, ignored: " + ", ".join(ignored))
        else:
            self.report({"INFO"}, "splash: render settings set from the command line")
        return {"FINISHED"}


class _ImportDirectory(ImportHelper):
    """A directory of numbered files as one object that follows the frame."""

    bl_options = {"REGISTER", "UNDO"}

    filename_ext = ""
    use_filter_folder = True
    directory: StringProperty(subtype="DIR_PATH")
    up_axis: EnumProperty(
        name="Files' up axis",
        items=[
            ("Y", "Y", "Y-up data, written without --up-axis: turned upright"),
            ("Z", "Z", "Written with --up-axis z: used as it is"),
        ],
        default="Y",
    )

    particles = False

    def execute(self, context):
        try:
            obj, files = sequence.import_sequence(
                context, self.directory, self.up_axis, particles=self.particles
            )
        except sequence.SequenceError as e:
            self.report({"ERROR"}, f"splash: {e}")
            return {"CANCELLED"}
        if self.particles and context.scene.splash.source is None:
            context.scene.splash.source = obj
        self.report({"INFO"}, f"splash: {obj.name}: {len(files)} frames")
        return {"FINISHED"}


class SPLASH_OT_import_sequence(_ImportDirectory, bpy.types.Operator):
    """Import a directory of splash recon meshes (OBJ, PLY, VTU, VTP) as one object whose
    mesh follows the frame, or of level sets (VDB) as a Volume sequence"""

    bl_idname = "splash.import_sequence"
    bl_label = "Import splash sequence"
    particles = False


class SPLASH_OT_import_particles(_ImportDirectory, bpy.types.Operator):
    """Import a directory of particle frames (PLY, CSV, VTK, VTU, BGEO, …) as one object of
    vertices that follows the frame, with the particles' attributes (velocity): a source
    for live mode"""

    bl_idname = "splash.import_particles"
    bl_label = "Import particle sequence"
    particles = True


class VIEW3D_PT_splash(bpy.types.Panel):
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "splash"
    bl_label = "splash"

    def draw(self, context):
        layout = self.layout
        s = context.scene.splash
        box = layout.box()
        box.prop(s, "enabled", text="Live reconstruction")
        box.prop(s, "source")
        box.prop(s, "spacing")
        box.prop(s, "velocity")
        for title, q in (("Viewport", s.viewport), ("Render", s.render)):
            col = box.column(align=True)
            col.label(text=title)
            for key in ("cell", "field", "normals", "engine", "correct", "raw", "volume_scope"):
                col.prop(q, key)
            col.prop(q, "temporal")
            for use, key in (("use_decimate", "decimate"), ("use_min_component", "min_component")):
                row = col.row(align=True)
                row.prop(q, use)
                sub = row.row(align=True)
                sub.active = getattr(q, use)
                sub.prop(q, key, text="")
        box.prop(s, "clip_object")
        row = box.row(align=True)
        row.operator("splash.reconstruct").render = False
        row.operator("splash.reconstruct", text="Render settings").render = True
        row = box.row(align=True)
        row.prop(s, "cache_mb")
        row.operator("splash.clear_cache", text="", icon="TRASH")
        if s.status:
            box.label(text=s.status, icon="INFO")
        if s.error:
            box.alert = True
            box.label(text=s.error, icon="ERROR")
        box = layout.box()
        box.label(text="Farm command line")
        box.prop(s, "input_path")
        box.prop(s, "output_path")
        row = box.row(align=True)
        row.operator("splash.copy_command", icon="COPYDOWN")
        row.operator("splash.paste_command", icon="PASTEDOWN")
        box = layout.box()
        box.operator("splash.import_particles", icon="IMPORT")
        box.operator("splash.import_sequence", icon="IMPORT")
        obj = context.active_object
        if obj is not None and obj.type == "MESH" and obj.splash_sequence.directory:
            group = obj.splash_sequence
            box.prop(group, "directory")
            box.prop(group, "up_axis")
            box.prop(group, "frame_offset")
            box.label(text=bpy.path.basename(group.file) or "no file")
            if group.error:
                box.alert = True
                box.label(text=group.error, icon="ERROR")


def _menu_import(self, _context):
    self.layout.operator(SPLASH_OT_import_sequence.bl_idname, text="splash mesh sequence")
    self.layout.operator(SPLASH_OT_import_particles.bl_idname, text="splash particle sequence")


_classes = (
    SPLASH_OT_reconstruct,
    SPLASH_OT_clear_cache,
    SPLASH_OT_copy_command,
    SPLASH_OT_paste_command,
    SPLASH_OT_import_sequence,
    SPLASH_OT_import_particles,
    VIEW3D_PT_splash,
)


def register():
    for cls in _classes:
        bpy.utils.register_class(cls)
    bpy.types.TOPBAR_MT_file_import.append(_menu_import)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(_menu_import)
    for cls in reversed(_classes):
        bpy.utils.unregister_class(cls)
