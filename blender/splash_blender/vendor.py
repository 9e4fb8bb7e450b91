# SPDX-License-Identifier: GPL-2.0-or-later
"""Finds the `splash_sph` package for Blender's Python.

`scripts/build-blender-addon` unpacks the package's abi3 wheel into `vendor/` beside this
file: one build serves every Python from 3.9 on, so the same zip works in Debian's Blender
(the system Python 3.11, where pip is refused) and in official builds (their own Python).
`vendor/` goes first on sys.path; without it, an installed `splash_sph` is used. numpy comes
from Blender (official builds) or the system (Debian: `apt-get install python3-numpy`).
"""

import os
import sys

VENDOR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "vendor")


def splash_sph():
    """The `splash_sph` module; RuntimeError saying what to install when it cannot load."""
    if os.path.isdir(VENDOR) and VENDOR not in sys.path:
        sys.path.insert(0, VENDOR)
    try:
        import numpy  # noqa: F401
    except ImportError:
        raise RuntimeError(
            "splash needs numpy in Blender's Python: official Blender builds include it; for "
            "Debian's blender run 'apt-get install python3-numpy'"
        ) from None
    try:
        import splash_sph
    except ImportError as e:
        raise RuntimeError(
            f"cannot load the splash_sph package ({e}): install the add-on from the zip that "
            "scripts/build-blender-addon builds (it bundles the package for this platform)"
        ) from None
    return splash_sph
