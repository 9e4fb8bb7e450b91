"""Library errors as Python exceptions, with the messages the CLI prints."""

import errno
import os
import subprocess

import numpy as np
import pytest

import splash_sph
from conftest import FRAME, ball

SPACING = 0.1


def cli_error(splash_bin, *args):
    """What the CLI prints on stderr for `splash recon ARGS`, which must fail."""
    run = subprocess.run([splash_bin, "recon", *args], capture_output=True, text=True)
    assert run.returncode != 0
    return run.stderr


def test_missing_file(splash_bin, tmp_path):
    path = tmp_path / "nothing.ply"
    with pytest.raises(FileNotFoundError) as e:
        splash_sph.read_particles(path)
    assert str(path) in str(e.value)
    assert str(e.value) in cli_error(splash_bin, path, "--spacing", "0.1", "-o", tmp_path / "x.obj")
    # The operating system's reason, once (it used to be printed twice by the CLI).
    reason = os.strerror(errno.ENOENT)
    assert str(e.value).count(reason) == 1, str(e.value)
    for log in ("plain", "json"):
        stderr = cli_error(splash_bin, path, "--spacing", "0.1", "--log-format", log)
        lines = [line for line in stderr.splitlines() if reason in line]
        assert lines and all(line.count(reason) == 1 for line in lines), stderr


def test_truncated_ply(splash_bin, tmp_path):
    path = tmp_path / "truncated.ply"
    path.write_bytes(FRAME.read_bytes()[:5000])
    with pytest.raises(ValueError, match="truncated") as e:
        splash_sph.read_particles(path)
    assert str(path) in str(e.value)
    assert str(e.value) in cli_error(splash_bin, path, "--spacing", "0.1", "-o", tmp_path / "x.obj")


def test_format_argument(tmp_path):
    path = tmp_path / "frame.dat"
    path.write_bytes(np.arange(12, dtype="<f4").tobytes())
    with pytest.raises(ValueError, match="cannot tell the particle format"):
        splash_sph.read_particles(path)
    p = splash_sph.read_particles(path, format="raw")
    np.testing.assert_array_equal(p.positions, np.arange(12, dtype=np.float32).reshape(4, 3))
    with pytest.raises(ValueError, match="unknown input format 'pts'"):
        splash_sph.read_particles(path, format="pts")


def test_particles_object(frame):
    assert len(frame) == 44064 == frame.positions.shape[0]
    assert frame.positions.dtype == np.float32
    assert "no such attribute" not in frame
    with pytest.raises(KeyError):
        frame["no such attribute"]
    for name, values in frame.attributes.items():
        assert name in frame
        assert values.shape[0] == len(frame)


def test_spacing_is_required():
    with pytest.raises(ValueError, match="spacing is not set: pass spacing=r"):
        splash_sph.reconstruct(ball(SPACING))


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"field": "sph"}, "unknown field 'sph'"),
        ({"engine": "fast"}, "unknown engine 'fast'"),
        ({"normals": "flat"}, "unknown normals 'flat'"),
        ({"cell": "half"}, "'half' is not a length"),
        ({"cell": -1.0}, "cell must be a positive length"),
        ({"threads": 0}, "threads must be at least 1"),
        ({"max_memory": "lots"}, "'lots' is not a size"),
        ({"spacing": -0.1}, "spacing must be a positive length"),
    ],
)
def test_bad_settings(kwargs, message):
    kwargs = {"spacing": SPACING, **kwargs}
    with pytest.raises(ValueError, match=message):
        splash_sph.reconstruct(ball(SPACING), **kwargs)


@pytest.mark.parametrize(
    "config, key",
    [
        ({"cel": "r"}, "cel"),
        ({"field": {"kind": "ssp07", "t_lo": 0.3}}, "t_lo"),
        ({"band": {"half_width": "2r", "extra": 1}}, "extra"),
    ],
)
def test_unknown_config_keys_are_named(config, key, tmp_path):
    with pytest.raises(ValueError, match=f"unknown field `{key}`"):
        splash_sph.reconstruct(ball(SPACING), spacing=SPACING, config=config)


def test_bad_config_file(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('cell = "r"\nthreds = 2\n')
    with pytest.raises(ValueError, match="unknown field `threds`") as e:
        splash_sph.reconstruct(ball(SPACING), spacing=SPACING, config=path)
    assert str(path) in str(e.value)
    with pytest.raises(FileNotFoundError, match="cannot read the config file"):
        splash_sph.reconstruct(ball(SPACING), spacing=SPACING, config=tmp_path / "none.toml")


def test_config_of_the_wrong_type():
    with pytest.raises(TypeError, match="config must be a TOML file's path or a dict"):
        splash_sph.reconstruct(ball(SPACING), spacing=SPACING, config=3)
    with pytest.raises(ValueError, match=r"cell = \[1, 2\]"):
        splash_sph.reconstruct(ball(SPACING), spacing=SPACING, config={"cell": [1, 2]})


def test_memory_limit():
    with pytest.raises(ValueError, match="memory"):
        splash_sph.reconstruct(
            ball(SPACING), spacing=SPACING, engine="full-gather", max_memory=1000
        )


def test_write_errors(tmp_path):
    mesh = splash_sph.reconstruct(ball(SPACING), spacing=SPACING)
    (tmp_path / "file").write_text("")
    with pytest.raises(OSError, match="cannot write"):
        mesh.write(tmp_path / "file" / "mesh.obj")
    with pytest.raises(ValueError, match="does not match the file name's .obj extension"):
        mesh.write(tmp_path / "mesh.obj", format="ply")
    with pytest.raises(ValueError, match="unknown mesh format 'stl'"):
        mesh.write(tmp_path / "mesh.stl", format="stl")
    with pytest.raises(ValueError, match="unknown up axis 'x'"):
        mesh.write(tmp_path / "mesh.obj", up_axis="x")
    assert not list(tmp_path.glob("mesh*"))
