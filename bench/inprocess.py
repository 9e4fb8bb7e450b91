"""One in-process reconstruction's wall time and the memory it takes above the loaded positions,
for `bench/python.sh`: splash_sph.reconstruct or pysplashsurf.reconstruction_pipeline with the
same parameters (density field, compact support 2r, iso 0.6, cell r/2, raw mesh, no normals).

    python bench/inprocess.py [--pin CPUS] splash|pysplashsurf POSITIONS.npy SPACING

Prints `name seconds extra_MiB triangles`. The peak resident set is reset after loading
(/proc/self/clear_refs), so extra_MiB is the call's peak above the process with its positions.
--pin CPUS (as bench/pin.sh: default 0,1, "none" unpinned) sets the process's CPU affinity
(os.sched_setaffinity) before numpy and the package are imported, so every thread they start
inherits it; a malformed list or a CPU not available to the process exits 2.
"""

import os
import re
import sys
import time


def rss_kib(field):
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    raise RuntimeError(f"no {field} in /proc/self/status")


def pin(cpus):
    """Restricts this process (its one thread so far, and so every thread started later) to the
    CPUs of a list such as 0,1 or 0-3,6; "none" leaves it as it is."""
    if cpus == "none":
        return
    wanted = set()
    for part in cpus.split(","):
        m = re.fullmatch(r"([0-9]+)(?:-([0-9]+))?", part)
        if not m or int(m[1]) > int(m[2] or m[1]):
            sys.stderr.write(f"--pin {cpus}: not a CPU list (e.g. 0,1 or 0-3; none for unpinned)\n")
            sys.exit(2)
        wanted.update(range(int(m[1]), int(m[2] or m[1]) + 1))
    available = os.sched_getaffinity(0)
    missing = sorted(wanted - available)
    if missing:
        sys.stderr.write(
            f"--pin {cpus}: CPU {missing[0]} does not exist or is not available to this process "
            f"(available: {','.join(map(str, sorted(available)))})\n"
        )
        sys.exit(2)
    os.sched_setaffinity(0, wanted)


def main():
    args, cpus = sys.argv[1:], "0,1"
    if args[:1] == ["--pin"] and len(args) >= 2:
        cpus, args = args[1], args[2:]
    if len(args) != 3:
        sys.stderr.write(
            "usage: python bench/inprocess.py [--pin CPUS] splash|pysplashsurf "
            "POSITIONS.npy SPACING\n"
        )
        sys.exit(2)
    pin(cpus)
    import numpy as np

    name, path, spacing = args[0], args[1], float(args[2])
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
