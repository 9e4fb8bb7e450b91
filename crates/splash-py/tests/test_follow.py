"""reconstruct(ids=..., neighbours=...): one frame's surface following the fluid from the frames
before and after it (issue 38), as recon_sequence(temporal=True) does for files."""

import shutil
from pathlib import Path

import numpy as np
import pytest

import splash_sph
from conftest import REPO, ball

DENSE = REPO.parent / "shared" / "data" / "dense-dambreak"


def frame(positions):
    return positions, np.arange(len(positions), dtype=np.int64)


def test_a_fluid_at_rest_does_not_move():
    p = ball(0.1, 0.5)
    alone = splash_sph.reconstruct(p, 0.1)
    ids = np.arange(len(p))
    still = splash_sph.reconstruct(p, 0.1, ids=ids, neighbours=(frame(p), frame(p)))
    assert still.report["followed"]["moved"] == 0
    assert np.array_equal(still.vertices, alone.vertices)
    assert np.array_equal(still.faces, alone.faces)
    assert "followed" not in alone.report


def test_a_ball_in_steady_motion_stays_where_its_particles_put_it():
    # Translating 0.37 cell per frame: the neighbours carried to this frame's time agree with
    # its own surface, so the surface barely moves (the sequence test's figures: < 0.01 r).
    p = ball(0.1, 0.5)
    step = np.float32(0.37 * 0.05)
    shifted = lambda k: np.ascontiguousarray(p + k * step * np.array([1, 0.5, 0], np.float32))
    ids = np.arange(len(p))
    mesh = splash_sph.reconstruct(
        shifted(0), 0.1, ids=ids, neighbours=(frame(shifted(-1)), frame(shifted(1)))
    )
    followed = mesh.report["followed"]
    assert followed["moved"] > 0
    assert followed["rms"] < 0.01 * 0.1, followed
    assert followed["max"] < 0.05 * 0.1, followed


def test_ids_match_particles_in_any_order():
    # The neighbours' particles shuffled with their ids: the same matches, the same mesh but
    # for the rounding of sums taken in another order (a wrong match would move it by ~0.01).
    p = ball(0.1, 0.5)
    q = np.ascontiguousarray(p + np.float32(0.01))
    ids = np.arange(len(p))
    order = np.random.default_rng(7).permutation(len(p))
    plain = splash_sph.reconstruct(p, 0.1, ids=ids, neighbours=(frame(q), frame(q)))
    shuffled = splash_sph.reconstruct(
        p, 0.1, ids=ids, neighbours=((q[order], ids[order]), (q[order], ids[order]))
    )
    assert plain.report["followed"]["moved"] > 0
    assert np.allclose(plain.vertices, shuffled.vertices, rtol=0, atol=1e-6)


def test_the_same_surface_as_a_temporal_sequence(tmp_path):
    if not DENSE.is_dir():
        pytest.skip(f"skipped: {DENSE} (../shared/data/dense-dambreak) is absent")
    names = ["frame_0130.vtk", "frame_0131.vtk", "frame_0132.vtk"]
    sim = tmp_path / "sim"
    sim.mkdir()
    for name in names:
        shutil.copy(DENSE / name, sim / name)
    splash_sph.recon_sequence(sim, f"{tmp_path}/out/", spacing=0.04, format="ply", temporal=True)
    written = splash_sph.read_mesh(tmp_path / "out" / "frame_0131.ply")
    frames = [splash_sph.read_particles(sim / n) for n in names]
    pick = lambda f: (f.positions, f["id"].astype(np.int64))
    mesh = splash_sph.reconstruct(
        frames[1].positions,
        0.04,
        ids=frames[1]["id"].astype(np.int64),
        neighbours=(pick(frames[0]), pick(frames[2])),
    )
    assert mesh.report["followed"]["moved"] > 0
    assert np.array_equal(mesh.vertices, written.vertices)
    assert np.array_equal(mesh.faces, written.faces)


def test_bad_ids_and_neighbours_are_refused_with_what_is_wrong():
    p = ball(0.1, 0.5)
    ids = np.arange(len(p))
    with pytest.raises(ValueError, match="ids and neighbours go together"):
        splash_sph.reconstruct(p, 0.1, ids=ids)
    with pytest.raises(ValueError, match="ids and neighbours go together"):
        splash_sph.reconstruct(p, 0.1, neighbours=(frame(p), frame(p)))
    with pytest.raises(TypeError, match="frames before and after"):
        splash_sph.reconstruct(p, 0.1, ids=ids, neighbours=frame(p)[0])
    with pytest.raises(ValueError, match="integer"):
        splash_sph.reconstruct(p, 0.1, ids=ids.astype(np.float64), neighbours=(frame(p),) * 2)
    twice = ids.copy()
    twice[1] = 0
    with pytest.raises(ValueError, match="the frame after: particle id 0 appears twice"):
        splash_sph.reconstruct(p, 0.1, ids=ids, neighbours=(frame(p), (p, twice)))
    with pytest.raises(ValueError, match=r"the frame before: \d+ ids for \d+ particles"):
        splash_sph.reconstruct(p, 0.1, ids=ids, neighbours=((p, ids[:-1]), frame(p)))
    with pytest.raises(ValueError, match=r"ids\[3\] is -1"):
        bad = ids.copy()
        bad[3] = -1
        splash_sph.reconstruct(p, 0.1, ids=bad, neighbours=(frame(p), frame(p)))
