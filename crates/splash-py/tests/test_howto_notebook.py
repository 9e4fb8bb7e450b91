"""docs/howto/notebook.md runs as written: every ```python cell, in order, in one namespace,
from a directory holding the repository's fixtures (as a checkout would), with matplotlib
drawing off-screen."""

import re

import pytest

from conftest import REPO

HOWTO = REPO / "docs" / "howto" / "notebook.md"


def test_every_cell_of_the_notebook_howto_runs(tmp_path, monkeypatch, capsys):
    matplotlib = pytest.importorskip("matplotlib", reason="the how-to draws with matplotlib")
    matplotlib.use("Agg")
    cells = re.findall(r"```python\n(.*?)```", HOWTO.read_text(encoding="utf-8"), re.S)
    assert len(cells) >= 5, "the how-to lost its cells"
    (tmp_path / "fixtures").symlink_to(REPO / "fixtures")
    monkeypatch.chdir(tmp_path)
    namespace = {}
    for number, cell in enumerate(cells, 1):
        exec(compile(cell, f"{HOWTO.name}, cell {number}", "exec"), namespace)
    printed = capsys.readouterr().out
    # The outputs the page shows in its comments.
    assert "44064 ['density', 'velocity']" in printed
    assert printed.rstrip().endswith("2 []")
    assert sorted(p.name for p in (tmp_path / "out" / "seq").iterdir()) == [
        "fluid_0010.ply",
        "fluid_0040.ply",
    ]
