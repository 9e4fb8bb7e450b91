# SPDX-License-Identifier: GPL-2.0-or-later
"""splash for Blender: surfaces of SPH particles, live or from a farm's mesh sequence.

- Live: the object whose vertices are particles is reconstructed by the `splash_sph` package
  on every frame change, with the viewport settings in the viewport and the render settings
  when rendering, through a frame cache.
- Farm sequences: a directory of `splash recon` outputs (OBJ, PLY, VTU, VTP) becomes one
  object whose mesh follows the frame, with the files' normals and `velocity`.

The package comes from the wheel bundled under `vendor/` (see `vendor.py`).
"""

bl_info = {
    "name": "splash: SPH fluid surfaces",
    "author": "splash authors",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "3D Viewport > Sidebar > splash",
    "description": "Reconstructs SPH particle objects on frame change; imports splash recon sequences",
    "category": "Import-Export",
}

from . import live, sequence, settings, ui  # noqa: E402

_modules = (settings, live, sequence, ui)


def register():
    for module in _modules:
        module.register()


def unregister():
    for module in reversed(_modules):
        module.unregister()
