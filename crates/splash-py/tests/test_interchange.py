"""read_particles on the interchange formats (VTK, VTU, BGEO, XYZ): the files in
fixtures/formats, written by VTK's Python package, splashsurf and in partio's BGEO layout, hold
every 23rd particle of fixtures/frame_0010.ply (1 916) with velocity, density and id."""

import numpy as np
import pytest

import splash_sph
from conftest import REPO

FORMATS = REPO / "fixtures" / "formats"


@pytest.fixture(scope="module")
def reference():
    frame = splash_sph.read_particles(str(REPO / "fixtures" / "frame_0010.ply"))
    keep = np.arange(0, len(frame), 23)
    return frame.positions[keep], {k: frame[k][keep] for k in frame.attributes}, keep


@pytest.mark.parametrize(
    "name",
    ["xml_appended_raw_zlib_uint64.vtu", "splishsplash.vtk", "partio_attributes.bgeo.gz"],
)
def test_interchange_files_read_like_the_ply(reference, name):
    frame = splash_sph.read_particles(str(FORMATS / name))
    expected_positions, expected, keep = reference
    np.testing.assert_array_equal(frame.positions, expected_positions)
    assert sorted(frame.attributes) == ["density", "id", "velocity"]
    np.testing.assert_array_equal(frame["velocity"], expected["velocity"])
    np.testing.assert_array_equal(frame["density"], expected["density"])
    np.testing.assert_array_equal(frame["id"], keep.astype(np.float32))


def test_raw_xyz_has_positions_only(reference):
    frame = splash_sph.read_particles(str(FORMATS / "raw.xyz"), "xyz")
    np.testing.assert_array_equal(frame.positions, reference[0])
    assert len(frame.attributes) == 0
