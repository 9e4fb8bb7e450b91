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


def independent_read(path):
    """Positions and point data of `path` as VTK's own readers (or meshio) read them."""
    if path.suffix == ".vtk":
        vtk = pytest.importorskip("vtk")
        from vtk.util.numpy_support import vtk_to_numpy

        reader = vtk.vtkUnstructuredGridReader()
        reader.SetFileName(str(path))
        reader.ReadAllFieldsOn()
        reader.ReadAllScalarsOn()
        reader.ReadAllVectorsOn()
        reader.Update()
        out = reader.GetOutput()
        data = out.GetPointData()
        arrays = {
            data.GetArrayName(i): vtk_to_numpy(data.GetArray(i))
            for i in range(data.GetNumberOfArrays())
        }
        return vtk_to_numpy(out.GetPoints().GetData()), arrays
    meshio = pytest.importorskip("meshio")
    m = meshio.read(path)
    return m.points, dict(m.point_data)


@pytest.mark.parametrize("name", ["legacy_binary.vtk", "splishsplash.vtk", "xml_binary_zlib.vtu"])
def test_attributes_by_name_equal_an_independent_readers(name):
    path = FORMATS / name
    frame = splash_sph.read_particles(path)
    points, arrays = independent_read(path)
    np.testing.assert_array_equal(frame.positions, points.astype(np.float32))
    assert frame.attribute_names == sorted(arrays) == ["density", "id", "velocity"]
    velocity = frame.attributes["velocity"]
    assert velocity.shape == (len(frame), 3) and velocity.dtype == np.float32
    np.testing.assert_array_equal(velocity, arrays["velocity"])
    np.testing.assert_array_equal(frame.attributes["density"], arrays["density"])
    np.testing.assert_array_equal(frame.attributes["id"], arrays["id"].astype(np.float32))
    # Any usual spelling finds the attribute, through the library's alias table.
    for spelling in ["velocity", "v", "vel", "Velocities"]:
        np.testing.assert_array_equal(frame.attribute(spelling), arrays["velocity"])
    np.testing.assert_array_equal(frame.attribute("rho"), arrays["density"])
    np.testing.assert_array_equal(frame.attribute("particle_id"), frame["id"])


def test_velocity_components_come_as_one_vector(tmp_path):
    path = tmp_path / "components.csv"
    path.write_text("x,y,z,velocity_x,velocity_y,velocity_z,temperature\n"
                    "0,0,0,1,2,3,300\n1,0,0,4,5,6,310\n")
    frame = splash_sph.read_particles(path)
    assert "temperature" in frame.attribute_names
    v = frame.attribute("v")
    assert v.shape == (2, 3) and v.dtype == np.float32
    np.testing.assert_array_equal(v, [[1, 2, 3], [4, 5, 6]])
    np.testing.assert_array_equal(frame.attribute("temperature"), [300, 310])
    with pytest.raises(KeyError, match="no attribute 'pressure'.*temperature"):
        frame.attribute("pressure")
