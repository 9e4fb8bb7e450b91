"""Configurations from TOML files, dicts and keyword arguments."""

import numpy as np
import pytest

import splash_sph
from conftest import REPO, ball, read_obj

SPACING = 0.1


@pytest.fixture(scope="module")
def particles():
    return ball(SPACING)


def same_mesh(a, b):
    np.testing.assert_array_equal(a.vertices, b.vertices)
    np.testing.assert_array_equal(a.faces, b.faces)


def test_file_dict_and_keywords_agree(particles, tmp_path):
    path = tmp_path / "c.toml"
    path.write_text('cell = "r"\nnormals = "grid"\n[field]\nkind = "density"\n')
    from_file = splash_sph.reconstruct(particles, spacing=SPACING, config=path)
    from_str = splash_sph.reconstruct(particles, spacing=SPACING, config=str(path))
    from_dict = splash_sph.reconstruct(
        particles,
        spacing=SPACING,
        config={"cell": "r", "normals": "grid", "field": {"kind": "density"}},
    )
    from_keywords = splash_sph.reconstruct(
        particles, spacing=SPACING, cell="r", normals="grid", field="density"
    )
    default = splash_sph.reconstruct(particles, spacing=SPACING)
    for mesh in (from_str, from_dict, from_keywords):
        same_mesh(from_file, mesh)
    assert from_file.report["cell"] == SPACING and from_file.report["field"] == "density"
    assert len(from_file.vertices) != len(default.vertices)


def test_keywords_override_the_config(particles):
    mesh = splash_sph.reconstruct(
        particles, config={"spacing": SPACING, "cell": "r", "threads": 1}, cell="2r", threads=2
    )
    assert mesh.report["spacing"] == SPACING
    assert mesh.report["cell"] == pytest.approx(2 * SPACING)
    assert mesh.report["threads"] == 2
    world = splash_sph.reconstruct(particles, spacing=SPACING, cell=0.05)
    assert world.report["cell"] == 0.05


def test_a_field_of_the_configs_kind_keeps_its_parameters():
    config = {"field": {"kind": "density", "iso": 0.5}}
    assert "iso = 0.5" in splash_sph.config_toml(config, field="density")
    assert "iso = 0.5" not in splash_sph.config_toml(config, field="zb05")


def test_default_config_round_trips(particles):
    d = splash_sph.default_config()
    assert d["cell"] == "r/2" and d["field"]["kind"] == "ssp07" and "spacing" not in d
    same_mesh(
        splash_sph.reconstruct(particles, spacing=SPACING, config=d),
        splash_sph.reconstruct(particles, spacing=SPACING),
    )
    assert splash_sph.config_toml(d) == splash_sph.config_toml()
    toml = splash_sph.config_toml(spacing=SPACING, engine="slices", max_memory="2G", threads=3)
    assert "spacing = 0.1\n" in toml and 'engine = "slices"' in toml
    assert 'max_memory = "2G"' in toml and "threads = 3" in toml


def test_repository_configs_are_accepted():
    for path in sorted((REPO / "configs").glob("*.toml")):
        assert "[field]" in splash_sph.config_toml(path), path


def test_output_settings_are_write_defaults(particles, tmp_path):
    mesh = splash_sph.reconstruct(
        particles, spacing=SPACING, config={"output": {"format": "ply-ascii", "up_axis": "z"}}
    )
    mesh.write(tmp_path / "m.ply")
    assert (tmp_path / "m.ply").read_bytes().startswith(b"ply\nformat ascii 1.0\n")
    mesh.write(tmp_path / "m.obj", format="obj", up_axis="y")
    vertices, _ = read_obj(tmp_path / "m.obj")
    v = mesh.vertices
    np.testing.assert_array_equal(vertices, np.stack([v[:, 0], v[:, 2], -v[:, 1]], axis=1))


def test_written_mesh_follows_edits_of_the_arrays(particles, tmp_path):
    mesh = splash_sph.reconstruct(particles, spacing=SPACING, normals="none")
    mesh.vertices[:] *= 2.0
    mesh.write(tmp_path / "scaled.obj")
    vertices, faces = read_obj(tmp_path / "scaled.obj")
    np.testing.assert_array_equal(vertices, mesh.vertices)
    np.testing.assert_array_equal(faces, mesh.faces)
    assert np.abs(vertices).max() > 0.9
