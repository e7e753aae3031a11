"""Every notebook in notebooks/ runs top to bottom without error, from cleared
outputs, and its own cells take under a minute.

The time of a notebook is read from the execution timestamps nbclient records
in each cell's metadata: from the first code cell's start to the last one's
reply, so the kernel's start-up is not counted.  The bound is a safety net
(the notebooks take a few seconds each; docs/course.md lists the measured
times), not a benchmark: run with ``-rP`` (or ``-s``) to see each notebook's time.
"""
from datetime import datetime
from pathlib import Path

import pytest

NB_DIR = Path(__file__).resolve().parent.parent / "notebooks"
NOTEBOOKS = sorted(NB_DIR.glob("*.ipynb"))
MAX_SECONDS = 60.0     # what users asked for, top to bottom


def _stamp(text):
    """A datetime from nbclient's ISO 8601 timestamps (with a trailing Z)."""
    return datetime.fromisoformat(text.replace("Z", "+00:00"))


def cells_seconds(nb):
    """Seconds from the first code cell's start to the last code cell's reply."""
    code = [c for c in nb.cells if c.cell_type == "code"]
    start = _stamp(code[0].metadata["execution"]["iopub.execute_input"])
    end = _stamp(code[-1].metadata["execution"]["shell.execute_reply"])
    return (end - start).total_seconds()


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs(path, tmp_path, monkeypatch):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    monkeypatch.setenv("MPLBACKEND", "Agg")
    nb = nbformat.read(path, as_version=4)
    for cell in nb.cells:
        if cell.cell_type == "code":
            assert not cell.get("outputs"), f"{path.name}: outputs must be cleared in git"
            assert cell.get("execution_count") is None, \
                f"{path.name}: execution counts must be cleared in git"
    client = nbclient.NotebookClient(nb, timeout=300, kernel_name="python3", record_timing=True,
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    seconds = cells_seconds(nb)
    n_code = sum(c.cell_type == "code" for c in nb.cells)
    print(f"{path.name}: {n_code} code cells of {len(nb.cells)}, {seconds:.1f} s")
    assert seconds < MAX_SECONDS, \
        f"{path.name} took {seconds:.1f} s top to bottom (bound {MAX_SECONDS:g} s)"
