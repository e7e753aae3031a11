"""The README's Python blocks run, in order, as a user pasting them would run them.

Every ```python block of README.md is one script (the blocks build on each other: the
first imports numpy and mechpy), run in a fresh interpreter from an empty folder (files
the examples save land there).  The README's own promises are checked on what the
blocks print where it states a figure: the first block's pendulum against SciPy's
solve_ivp, the closed forms the comments name.
"""
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

# the source tree: under dev.sh's sdist pass the tests run from a copy (README.md beside
# them, not docs/ or mechpy/), and dev.sh names the checkout in MECHPY_SOURCE_DIR
SOURCE = Path(os.environ.get("MECHPY_SOURCE_DIR") or Path(__file__).resolve().parent.parent)
README = SOURCE / "README.md"
SANITIZED = bool(os.environ.get("MECHPY_SANITIZED"))


def python_blocks(text: str) -> list:
    """The ```python fenced blocks of a Markdown text, in order."""
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.M | re.S)


def test_python_blocks_are_found():
    text = "a\n```python\nx = 1\n```\n```sh\nls\n```\n```python\ny = 2\n```\n"
    assert python_blocks(text) == ["x = 1\n", "y = 2\n"]


def _readme():
    if not README.is_file():
        pytest.skip("needs the README beside tests/")
    return README.read_text()


@pytest.mark.skipif(SANITIZED, reason="numba and matplotlib: not under the sanitizers")
def test_readme_blocks_run_in_order(tmp_path):
    blocks = python_blocks(_readme())
    assert len(blocks) >= 10, "the README has an example per topic"
    # each block's output after a marker line, to tell the blocks' prints apart
    script = "".join(f"print('@@block {i}')\n{b}" for i, b in enumerate(blocks))
    (tmp_path / "readme.py").write_text(script)
    env = dict(os.environ, MECHPY_CACHE_DIR=str(tmp_path / "cache"), MPLBACKEND="Agg")
    env.pop("PYTHONPATH", None)
    # budget: the blocks took 25 s here (compiled systems built, the live page's overlays)
    r = subprocess.run([sys.executable, "readme.py"], cwd=tmp_path, env=env,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    out = dict(re.findall(r"^@@block (\d+)\n(.*?)(?=^@@block |\Z)", r.stdout, flags=re.M | re.S))
    assert len(out) == len(blocks)
    # the first solve: the pendulum at t = 10 as SciPy's DOP853 gives it at a tighter rtol
    scipy = pytest.importorskip("scipy.integrate")
    ref = scipy.solve_ivp(lambda t, y: [y[1], -9.81 * np.sin(y[0])], (0, 10), [2.5, 0.0],
                          method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]
    first = np.array(re.findall(r"[-+]?\d+\.\d+(?:e[-+]?\d+)?", out["0"]), dtype=float)
    # measured: 1e-9 apart (the README's rtol 1e-10 over ten seconds)
    np.testing.assert_allclose(first, ref, atol=1e-7)
    # the files the examples save
    assert (tmp_path / "vanderpol.html").stat().st_size > 10_000
    assert (tmp_path / "pendulum-phase.png").stat().st_size > 1_000


def test_readme_installs_by_the_distribution_name():
    """Install lines name the PyPI distribution, mechpy-classical, and its extras."""
    text = _readme()
    lines = [ln for ln in text.splitlines() if "pip install" in ln]
    assert lines
    for ln in lines:
        assert not re.search(r"pip install \"?mechpy(\[|\s|\"|$)", ln), ln
    for extra in ("live", "plot", "jit"):
        assert f"`{extra}`" in text, extra
    # the two set-up commands, exactly as CI and users run them
    assert "bash scripts/dev.sh tour     # set up, then: python -m mechpy tour" in text
    assert "bash scripts/dev.sh test     # set up, then: the test suite (pytest)" in text


def test_readme_picture_is_committed_and_small():
    text = _readme()
    pics = re.findall(r"!\[[^\]]*\]\(([^)]+\.png)\)", text)
    assert pics, "the README shows a picture"
    for p in pics:
        path = README.parent / p
        assert path.is_file(), p
        assert path.stat().st_size < 200_000, (p, path.stat().st_size)
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_messages_name_the_distribution():
    """Messages that tell a user what to pip install name mechpy-classical, not mechpy
    (another project's name on PyPI)."""
    pkg = README.parent / "mechpy"
    if not pkg.is_dir():
        pytest.skip("needs the source tree's mechpy/")
    bad = []
    for f in pkg.rglob("*.py"):
        for i, ln in enumerate(f.read_text().splitlines(), 1):
            if re.search(r"pip install \W*mechpy(?!-classical)\b", ln) or "extra of mechpy" in ln:
                bad.append(f"{f.relative_to(pkg)}:{i}: {ln.strip()}")
    assert bad == []
