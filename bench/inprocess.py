"""One in-process reconstruction's wall time and the memory it takes above the loaded positions,
for `bench/python.sh`: splash_sph.reconstruct or pysplashsurf.reconstruction_pipeline with the
same parameters (density field, compact support 2r, iso 0.6, cell r/2, raw mesh, no normals).

    python bench/inprocess.py splash|pysplashsurf POSITIONS.npy SPACING

Prints `name seconds extra_MiB triangles`. The peak resident set is reset after loading
(/proc/self/clear_refs), so extra_MiB is the call's peak above the process with its positions.
"""

import sys
import time

import numpy as np


def rss_kib(field):
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    raise RuntimeError(f"no {field} in /proc/self/status")


def main():
    name, path, spacing = sys.argv[1], sys.argv[2], float(sys.argv[3])
    if name == "splash":
        import splash_sph

        def run(x):
            mesh = splash_sph.reconstruct(
                x, spacing, field="density", cell="r/2", normals="none", raw=True
            )
            return len(mesh.faces)
    elif name == "pysplashsurf":
        import pysplashsurf

        def run(x):
            # splashsurf's lengths are multiples of its particle radius, r/2 here: smoothing
            # length 2 (support 4 radii = 2r), cube 1 radius (r/2).
            result = pysplashsurf.reconstruction_pipeline(
                x,
                particle_radius=spacing / 2,
                smoothing_length=2.0,
                cube_size=1.0,
                iso_surface_threshold=0.6,
            )
            mesh = result[0] if isinstance(result, tuple) else result
            mesh = getattr(mesh, "mesh", mesh)
            return len(mesh.triangles)
    else:
        sys.exit(f"unknown reconstructor {name!r} (splash or pysplashsurf)")
    positions = np.load(path)
    positions = positions.astype(np.float32 if name == "splash" else positions.dtype)
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")
    before = rss_kib("VmRSS")
    started = time.perf_counter()
    triangles = run(positions)
    seconds = time.perf_counter() - started
    extra = (rss_kib("VmHWM") - before) / 1024
    print(f"{name} {seconds:.3f} {extra:.1f} {triangles}")


main()
