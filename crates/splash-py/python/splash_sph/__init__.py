"""Closed triangle meshes from SPH particle frames.

The narrow-band surface reconstruction of Akinci et al. 2012 with six scalar fields (SSP07 by
default), as the ``splash`` command line runs it, on numpy arrays::

    import splash_sph

    p = splash_sph.read_particles("frame_0040.ply")
    mesh = splash_sph.reconstruct(p.positions, spacing=0.014, cell="r/2")
    mesh.write("frame_0040.obj")
    back = splash_sph.read_mesh("frame_0040.obj")   # numpy arrays of a written mesh
    rho = splash_sph.iso(p, "density", 1000.0, spacing=0.014)   # isosurface of a quantity

Lengths are multiples of the particle spacing r (``"2r"``, ``"r"``, ``"r/2"``) or plain
numbers in world units. Library errors raise OSError (files) or ValueError (data, settings)
with the message the command line prints.
"""

from ._native import (
    Mesh,
    MeshArrays,
    Particles,
    config_toml,
    default_config,
    estimate_spacing,
    iso,
    preview,
    read_mesh,
    read_particles,
    reconstruct,
)

__all__ = [
    "Mesh",
    "MeshArrays",
    "Particles",
    "config_toml",
    "default_config",
    "estimate_spacing",
    "iso",
    "preview",
    "read_particles",
    "read_mesh",
    "reconstruct",
]
