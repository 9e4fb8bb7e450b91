"""recon_sequence runs a sequence as `splash recon` does: same frames, names, shards, restarts
and bytes; frame_number numbers files as the CLI does."""

import shutil
import subprocess
from pathlib import Path

import pytest

import splash_sph
from conftest import REPO

FIXTURES = REPO / "fixtures"


@pytest.fixture
def sim(tmp_path):
    """Three frames, fluid_0001 … fluid_0003, from the fixture frames (spacing estimated)."""
    d = tmp_path / "sim"
    d.mkdir()
    for n, name in enumerate(["frame_0010.ply", "frame_0040.ply", "frame_0010.ply"], start=1):
        shutil.copy(FIXTURES / name, d / f"fluid_{n:04d}.ply")
    return d


def cli(splash_bin, *args):
    subprocess.run([splash_bin, "recon", *map(str, args), "-q"], check=True)


def files(directory):
    return {p.name: p.read_bytes() for p in sorted(Path(directory).iterdir())}


def test_a_sequence_equals_the_cli_and_reports_each_frame(sim, splash_bin, tmp_path):
    cli(splash_bin, sim, "--attributes", "velocity", "--format", "ply", "-o", f"{tmp_path}/cli/")
    calls = []
    report = splash_sph.recon_sequence(
        sim,
        f"{tmp_path}/py/",
        attributes=["velocity"],
        format="ply",
        progress=lambda done, total, frame: calls.append((done, total, frame)),
    )
    expected = files(tmp_path / "cli")
    assert list(expected) == ["fluid_0001.ply", "fluid_0002.ply", "fluid_0003.ply"]
    assert files(tmp_path / "py") == expected
    assert [(d, t, f["frame"], f["status"]) for d, t, f in calls] == [
        (1, 3, 1, "ok"),
        (2, 3, 2, "ok"),
        (3, 3, 3, "ok"),
    ]
    assert calls[1][2]["output"] == f"{tmp_path}/py/fluid_0002.ply"
    assert calls[1][2]["triangles"] > 1000
    assert report["ok"] and report["written"] == 3 and report["failed"] == []
    assert (report["selected"], report["assigned"], report["to_do"]) == (3, 3, 3)
    assert report["frames"] == [c[2] for c in calls]
    assert 0.01 < report["spacing"] < 0.02


def test_shards_and_restarts_write_the_cli_bytes(sim, splash_bin, tmp_path):
    cli(splash_bin, sim, "-o", f"{tmp_path}/cli/")
    out = f"{tmp_path}/py/"
    second = splash_sph.recon_sequence(sim, out, shard="2/2")
    assert second["shard"] == "2/2" and list(files(out)) == ["fluid_0002.obj"]
    first = splash_sph.recon_sequence(str(sim / "fluid_*.ply"), out, shard="1/2")
    assert [f["frame"] for f in first["frames"]] == [1, 3]
    # Shard 2 estimated the spacing on frame 1 too: one grid for the whole sequence.
    assert first["spacing"] == second["spacing"]
    assert files(out) == files(tmp_path / "cli")
    calls = []
    again = splash_sph.recon_sequence(
        sim, out, skip_existing=True, progress=lambda *a: calls.append(a)
    )
    assert again["ok"] and again["to_do"] == 0 and len(again["skipped"]) == 3 and calls == []


def test_frame_sets_and_patterns_name_outputs_as_the_cli(sim, splash_bin, tmp_path):
    pattern = "m_{frame:03}.ply"
    cli(splash_bin, sim, "--frames", "2-3", "-o", f"{tmp_path}/cli/{pattern}")
    report = splash_sph.recon_sequence([sim], f"{tmp_path}/py/{pattern}", frames="2-3")
    assert [Path(f["output"]).name for f in report["frames"]] == ["m_002.ply", "m_003.ply"]
    assert files(tmp_path / "py") == files(tmp_path / "cli")


def test_a_bad_frame_is_reported_and_bad_settings_raise(sim, tmp_path):
    (sim / "fluid_0002.ply").write_text("ply\nnot a ply file\n")
    report = splash_sph.recon_sequence(sim, f"{tmp_path}/out/")
    assert not report["ok"] and report["written"] == 2
    [bad] = report["failed"]
    assert bad["frame"] == 2 and "fluid_0002.ply" in bad["error"]
    stopped = splash_sph.recon_sequence(sim, f"{tmp_path}/stop/", fail_fast=True)
    assert stopped["written"] == 1 and stopped["not_attempted"] == 1
    with pytest.raises(ValueError, match="--shard 3/2"):
        splash_sph.recon_sequence(sim, f"{tmp_path}/x/", shard="3/2")
    with pytest.raises(ValueError, match="names one file for 3 inputs"):
        splash_sph.recon_sequence(sim, tmp_path / "one.obj")
    with pytest.raises(ValueError, match="matches no file"):
        splash_sph.recon_sequence(str(sim / "nothing_*.ply"), f"{tmp_path}/x/")
    with pytest.raises(ValueError, match="no input has one of these frame numbers"):
        splash_sph.recon_sequence(sim, f"{tmp_path}/x/", frames="7-9")
    with pytest.raises(ValueError, match="needs PLY, VTK, VTU, VTP, USD or VDB output"):
        splash_sph.recon_sequence(sim, f"{tmp_path}/x/", attributes="velocity")


def test_an_exception_in_progress_stops_the_run(sim, tmp_path):
    def progress(done, total, frame):
        raise KeyError("stop here")

    with pytest.raises(KeyError, match="stop here"):
        splash_sph.recon_sequence(sim, f"{tmp_path}/out/", progress=progress)
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["fluid_0001.obj"]


def test_frame_numbers_are_the_last_digits_of_the_name():
    assert splash_sph.frame_number("sim/frame_0042.ply") == 42
    assert splash_sph.frame_number(Path("run2/fluid.0007.bgeo.gz")) == 7
    assert splash_sph.frame_number("mesh/f10b.obj") == 10
    assert splash_sph.frame_number("fluid.ply") is None


def test_frames_report_their_stage_times_post_among_them(sim, tmp_path):
    for raw in (False, True):
        report = splash_sph.recon_sequence(sim, f"{tmp_path}/{raw}/", raw=raw, threads=2)
        for f in report["frames"]:
            t = f["times"]
            assert set(t) == {"read", "reconstruction", "post", "write"}
            assert all(v >= 0 for v in t.values())
            assert t["post"] <= t["reconstruction"]
            assert sum(t[k] for k in ("read", "reconstruction", "write")) == pytest.approx(
                f["seconds"], rel=1e-9
            )
            # --raw alone runs no post-processing: its stage takes no time.
            assert (t["post"] == 0) == raw, t


def test_temporal_follows_the_fluid_where_the_particles_can_be_carried(sim, tmp_path):
    # The fixture frames have velocities but no ids: without post.frame_time nothing can be
    # carried, and every frame is post-processed alone, with a warning and the same bytes.
    alone = splash_sph.recon_sequence(sim, f"{tmp_path}/a/", format="ply")
    kept = splash_sph.recon_sequence(sim, f"{tmp_path}/k/", format="ply", temporal=True)
    assert files(tmp_path / "k") == files(tmp_path / "a")
    assert alone["warnings"] == []
    assert sum("post-processed alone" in w for w in kept["warnings"]) == 3, kept["warnings"]
    # Carried by velocity x frame_time, the middle frame follows its neighbours; the ends,
    # with one neighbour each, stay as they were.
    config = {"post": {"frame_time": 0.005}}
    carried = splash_sph.recon_sequence(
        sim, f"{tmp_path}/c/", format="ply", temporal=True, config=config
    )
    a, c = files(tmp_path / "a"), files(tmp_path / "c")
    assert c["fluid_0001.ply"] == a["fluid_0001.ply"]
    assert c["fluid_0003.ply"] == a["fluid_0003.ply"]
    assert c["fluid_0002.ply"] != a["fluid_0002.ply"]
    assert sum("post-processed alone" in w for w in carried["warnings"]) == 2, carried["warnings"]
    assert carried["ok"] and carried["written"] == 3
