# SPDX-License-Identifier: GPL-2.0-or-later
"""The add-on's settings: the scene's live reconstruction and each sequence object's files."""

import bpy
from bpy.props import (
    BoolProperty,
    EnumProperty,
    FloatProperty,
    IntProperty,
    PointerProperty,
    StringProperty,
)

FIELDS = [
    ("ssp07", "SSP07", "Solenthaler et al. 2007 signed distance (support 4r): the paper's field"),
    ("zb05", "ZB05", "Zhu & Bridson 2005 signed distance (support 4r)"),
    ("density", "Density", "SPH colour field (support 2r): the fastest, splashsurf's field"),
    ("blobby", "Blobby", "Blinn 1982 Gaussian blobbies"),
    ("metaball", "Metaball", "Metaballs (cut-off 1.5r)"),
    ("anisotropic", "Anisotropic", "Yu & Turk 2010 stretched kernels: thin sheets; slowest"),
]
NORMALS = [
    ("field", "Field", "The field's analytic gradient"),
    ("grid", "Grid", "Central differences of the grid: faster, smoothed over a cell"),
    ("none", "Blender's", "No normals from splash: Blender's smooth vertex normals (fast)"),
]
ENGINES = [
    ("narrow-band", "Narrow band", "Akinci et al. 2012 (default)"),
    ("full-gather", "Full gather", "Every grid vertex: the paper's baseline"),
    ("scatter", "Scatter", "Every grid vertex, particle by particle"),
    ("slices", "Slices", "Marching Slices in blocks: little memory"),
]
VOLUME_SCOPES = [
    ("frame", "Frame", "One offset for the whole mesh: a frame's surface moves as its neighbours'"),
    ("component", "Component", "Each closed part to its own particles' volume"),
]

# splash's defaults, which the render settings keep: the options of splash_sph.OPTIONS
# (crates/splash-sph/src/overrides.rs), whose names, defaults and help texts (the first words of
# each description) the options_table test of the splash command compares with these.
RENDER_DEFAULTS = {
    "cell": "r/2",
    "field": "ssp07",
    "normals": "field",
    "engine": "narrow-band",
    "correct": 0,
    "raw": False,
    "volume_scope": "frame",
    "temporal": False,
}
# Custom split normals cost Blender about 4 s per million triangles to set up (Blender 3.4):
# the viewport shades smooth with Blender's own vertex normals instead. Post-processing
# adds a third to the package's time at the viewport's settings (cbd-small, CPU 0.051 ->
# 0.068 s/frame), which 24 fps cannot spare: the viewport shows the raw isosurface by
# default, renders the post-processed one.
VIEWPORT_DEFAULTS = {
    **RENDER_DEFAULTS,
    "cell": "r",
    "field": "density",
    "normals": "none",
    "raw": True,
}


def _quality(defaults):
    """A settings group with its own defaults (viewport and render differ)."""
    d = defaults
    return type(
        f"SPLASH_PG_quality_{d['field']}_{d['cell'].replace('/', '_')}",
        (bpy.types.PropertyGroup,),
        {
            "__annotations__": {
                "cell": StringProperty(
                    name="Cell",
                    default=d["cell"],
                    description="Marching Cubes cell size: 2r, r, r/2, r/N, Kr or a length; at "
                    "most 4r. A length is in scene units",
                ),
                "field": EnumProperty(
                    name="Field",
                    items=FIELDS,
                    default=d["field"],
                    description="Scalar field: ssp07, zb05, density, blobby, metaball or "
                    "anisotropic, with its default parameters unless the configuration gives "
                    "the same kind",
                ),
                "normals": EnumProperty(
                    name="Normals",
                    items=NORMALS,
                    default=d["normals"],
                    description="Vertex normals: field (the field's gradient), grid (differences "
                    "of the sampled grid: faster) or none",
                ),
                "engine": EnumProperty(
                    name="Engine",
                    items=ENGINES,
                    default=d["engine"],
                    description="Reconstruction engine: narrow-band, full-gather, scatter or "
                    "slices",
                ),
                "correct": IntProperty(
                    name="Correct",
                    default=d["correct"],
                    min=0,
                    max=32,
                    description="Newton steps moving each vertex along its cube edge onto the "
                    "field's exact isosurface (Marching Correctors); 0 keeps Marching Cubes' "
                    "linear interpolation (--correct)",
                ),
                "raw": BoolProperty(
                    name="Raw isosurface",
                    default=d["raw"],
                    description="Keep the field's exact isosurface: no smoothing and no volume "
                    "restoration (--raw). Off: smoothed, each part given its particles' volume "
                    "(at the viewport's coarse settings a third more time per frame)",
                ),
                "volume_scope": EnumProperty(
                    name="Volume",
                    items=VOLUME_SCOPES,
                    default=d["volume_scope"],
                    description="What the volume restoration brings to N·r³: frame (the whole "
                    "mesh, one offset) or component (each closed part to its own particles)",
                ),
                "temporal": BoolProperty(
                    name="Follow the fluid",
                    default=d["temporal"],
                    description="In a sequence, average each frame's field and surface with "
                    "its neighbouring frames' carried by the fluid's motion (experimental). "
                    "--temporal. Live mode does it for an imported particle sequence whose "
                    "files carry particle ids, reading the files before and after the frame: "
                    "about three times the work per frame",
                ),
                "use_decimate": BoolProperty(
                    name="Decimate",
                    default=False,
                    description="Fewer triangles (--decimate): quadric edge collapses keeping "
                    "the mesh within the tolerance of the full surface, closed and manifold",
                ),
                "decimate": FloatProperty(
                    name="Tolerance (r)",
                    default=0.1,
                    min=1e-4,
                    soft_max=1.0,
                    precision=3,
                    description="Decimate with quadric edge collapses, keeping every vertex and "
                    "triangle centre within this distance of the full surface; in spacings r",
                ),
                "use_min_component": BoolProperty(
                    name="Drop droplets",
                    default=False,
                    description="Drop the parts of the surface enclosing less than the volume "
                    "below (--min-component)",
                ),
                "min_component": FloatProperty(
                    name="Smallest volume (r³)",
                    default=2.0,
                    min=0.0,
                    soft_max=100.0,
                    precision=2,
                    description="Drop the parts of the mesh enclosing less than this many "
                    "particle volumes r³: after the volume restoration a droplet of n particles "
                    "holds n r³; a raw lone particle's SSP07 sphere about 3.6 r³",
                ),
            }
        },
    )


ViewportQuality = _quality(VIEWPORT_DEFAULTS)
RenderQuality = _quality(RENDER_DEFAULTS)


def _poll_particles(_self, obj):
    return obj.type == "MESH" and "splash_surface_of" not in obj


def _live_changed(self, context):
    from . import live

    live.on_settings_changed(context.scene)


class SPLASH_PG_live(bpy.types.PropertyGroup):
    enabled: BoolProperty(
        name="Live",
        description="Reconstruct the particle object on every frame change",
        update=_live_changed,
    )
    source: PointerProperty(
        name="Particles",
        type=bpy.types.Object,
        poll=_poll_particles,
        description="The object whose vertices are the particles",
    )
    spacing: FloatProperty(
        name="Spacing r",
        default=0.0,
        min=0.0,
        precision=4,
        description="Particle spacing r, the simulator's equilibrium distance between "
        "particles, in the object's units; 0: estimated once from the current frame and kept, "
        "so that every frame shares one grid",
    )
    velocity: BoolProperty(
        name="Velocity",
        default=True,
        description="Carry the particles' 'velocity' attribute onto the surface (motion blur)",
    )
    cache_mb: IntProperty(
        name="Cache (MB)",
        default=1024,
        min=0,
        description="Memory for surfaces already reconstructed, by frame and settings; the "
        "least recently used go first (0: no cache)",
    )
    viewport: PointerProperty(type=ViewportQuality)
    render: PointerProperty(type=RenderQuality)
    clip_object: PointerProperty(
        name="Clip box",
        type=bpy.types.Object,
        description="Keep only the surface inside this object's bounding box (--mesh-aabb), "
        "its cuts capped so that it stays closed; an Empty with the Cube display shows the box. "
        "The box is axis-aligned in the particle object's space: the bounds of this object's "
        "box there. Viewport and render alike; none: no clipping",
    )
    input_path: StringProperty(
        name="Particle files",
        default="",
        description="The particle files on disk (for the command line only): a directory, "
        "file or pattern",
    )
    output_path: StringProperty(
        name="Mesh output", default="mesh/", description="-o of the command line"
    )
    status: StringProperty(name="Status", default="")
    error: StringProperty(name="Error", default="")


def _up_axis_changed(group):
    from . import sequence

    sequence.orient(group.id_data)


class SPLASH_PG_sequence(bpy.types.PropertyGroup):
    directory: StringProperty(name="Directory", subtype="DIR_PATH")
    particles: BoolProperty(name="Particles", description="Particle files, not meshes")
    up_axis: EnumProperty(
        name="Files' up axis",
        items=[
            ("Y", "Y", "Y-up data (SPlisHSPlasH, written without --up-axis): turned upright"),
            ("Z", "Z", "Written with --up-axis z (or a Z-up simulation): used as it is"),
        ],
        default="Y",
        update=lambda self, _context: _up_axis_changed(self),
    )
    frame_offset: IntProperty(
        name="Frame offset",
        default=0,
        description="The file numbered F shows at scene frame F + offset",
    )
    file: StringProperty(name="Current file", default="")
    error: StringProperty(name="Error", default="")


_classes = (ViewportQuality, RenderQuality, SPLASH_PG_live, SPLASH_PG_sequence)


def register():
    for cls in _classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.splash = PointerProperty(type=SPLASH_PG_live)
    bpy.types.Object.splash_sequence = PointerProperty(type=SPLASH_PG_sequence)


def unregister():
    del bpy.types.Object.splash_sequence
    del bpy.types.Scene.splash
    for cls in reversed(_classes):
        bpy.utils.unregister_class(cls)
