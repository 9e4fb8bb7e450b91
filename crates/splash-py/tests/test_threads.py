"""The GIL is released: two Python threads reconstruct at once and agree."""

import threading
import time

import numpy as np

import splash_sph
from conftest import FRAME_SPACING


def test_two_threads_overlap_and_agree(frame):
    barrier = threading.Barrier(2)
    results = [None, None]

    def work(i):
        barrier.wait()
        start = time.perf_counter()
        mesh = splash_sph.reconstruct(frame.positions, spacing=FRAME_SPACING, threads=1)
        results[i] = (start, time.perf_counter(), mesh)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    (start_a, end_a, a), (start_b, end_b, b) = results
    np.testing.assert_array_equal(a.vertices, b.vertices)
    np.testing.assert_array_equal(a.faces, b.faces)
    np.testing.assert_array_equal(a.normals, b.normals)
    assert max(start_a, start_b) < min(end_a, end_b), "one finished before the other started"
    # Held GIL: the calls would run one after the other, for at least the sum of their
    # native times. Released: they share the wall time (on one core as on two).
    native = a.report["times"]["total"] + b.report["times"]["total"]
    wall = max(end_a, end_b) - min(start_a, start_b)
    assert wall < 0.8 * native, f"{wall:.3f} s for {native:.3f} s of native work"
