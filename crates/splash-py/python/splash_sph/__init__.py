"""Closed triangle meshes from SPH particle frames.

The narrow-band surface reconstruction of Akinci et al. 2012 with six scalar fields (SSP07 by
default), as the ``splash`` command line runs it, on numpy arrays::

    import splash_sph

    p = splash_sph.read_particles("frame_0040.ply")
    mesh = splash_sph.reconstruct(p.positions, spacing=0.014, cell="r/2")
    mesh.write("frame_0040.obj")
    back = splash_sph.read_mesh("frame_0040.obj")   # numpy arrays of a written mesh
    rho = splash_sph.iso(p, "density", 1000.0, spacing=0.014)   # isosurface of a quantity
    run = splash_sph.recon_sequence("sim/", "mesh/fluid_{frame:04}.ply", shard="auto/16",
                                    skip_existing=True)   # a farm job, as `splash recon` runs it

Lengths are multiples of the particle spacing r (``"2r"``, ``"r"``, ``"r/2"``) or plain
numbers in world units. Library errors raise OSError (files) or ValueError (data, settings)
with the message the command line prints.
"""

from ._native import (
    LevelSetArrays,
    Mesh,
    MeshArrays,
    Particles,
    config_toml,
    default_config,
    estimate_spacing,
    frame_number,
    iso,
    level_set,
    mesh_edges,
    postprocess,
    preview,
    read_mesh,
    read_particles,
    recon_sequence,
    reconstruct,
    write_vdb,
)

__all__ = [
    "LevelSetArrays",
    "Mesh",
    "MeshArrays",
    "Particles",
    "config_toml",
    "default_config",
    "estimate_spacing",
    "frame_number",
    "iso",
    "level_set",
    "mesh_edges",
    "postprocess",
    "preview",
    "read_particles",
    "read_mesh",
    "recon_sequence",
    "reconstruct",
    "write_vdb",
]
