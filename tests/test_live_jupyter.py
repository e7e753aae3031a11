"""End to end: a real JupyterLab server on localhost, a notebook that shows a
live phase portrait, headless Chromium running it in JupyterLab; the page's
particles read back and checked against a float64 RK4, and the kernel's
answers (a dropped trajectory integrated by mechpy in the kernel) against
mp.solve."""
import json
import os
import socket
import subprocess
import sys
import time
import urllib.request

import numpy as np
import pytest

import mechpy as mp

sys.path.insert(0, os.path.dirname(__file__))
from live_browser import driver, wait_for  # noqa: E402,F401
from ref_ode import rk4_fixed  # noqa: E402

pytest.importorskip("jupyterlab", reason="the test extra installs JupyterLab")
# the kernel is a third interpreter, as the notebooks' are: the normal pass only
pytestmark = pytest.mark.skipif(bool(os.environ.get("MECHPY_SANITIZED")),
                                reason="a Jupyter kernel under ASan: run in the normal pass")

CELL = """\
import mechpy as mp
w = mp.live.phase_portrait(mp.scenes.VanDerPol(mu=1.0), (-4, 4), (-6, 6), particles=1000,
                           play=False, overlays=False, path_steps=300)
w
"""


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    root = tmp_path_factory.mktemp("lab")
    nb = {"cells": [{"cell_type": "code", "metadata": {}, "execution_count": None,
                     "outputs": [], "source": CELL}],
          "metadata": {"kernelspec": {"name": "python3", "display_name": "Python 3",
                                      "language": "python"}},
          "nbformat": 4, "nbformat_minor": 5}
    (root / "live.ipynb").write_text(json.dumps(nb))
    port, token = _free_port(), "mechpy-test"
    env = dict(os.environ, JUPYTER_CONFIG_DIR=str(root / "cfg"), JUPYTER_DATA_DIR=str(root / "data"),
               JUPYTER_RUNTIME_DIR=str(root / "run"))
    # the kernel is this interpreter (the environment under test)
    subprocess.run([sys.executable, "-m", "ipykernel", "install", "--prefix", str(root / "k"),
                    "--name", "python3"], check=True, capture_output=True, env=env)
    env["JUPYTER_PATH"] = str(root / "k" / "share" / "jupyter")
    log = open(root / "lab.log", "w")
    proc = subprocess.Popen(
        [sys.executable, "-m", "jupyterlab", "--no-browser", f"--port={port}", "--ip=127.0.0.1",
         f"--IdentityProvider.token={token}", f"--ServerApp.root_dir={root}",
         "--LabApp.expose_app_in_browser=True", "--ServerApp.open_browser=False",
         "--allow-root"],
        stdout=log, stderr=subprocess.STDOUT, env=env)
    url = f"http://127.0.0.1:{port}"
    t0 = time.monotonic()
    while True:
        try:
            urllib.request.urlopen(f"{url}/api/status?token={token}", timeout=2)
            break
        except OSError:
            if proc.poll() is not None or time.monotonic() - t0 > 90:
                proc.kill()
                raise RuntimeError("JupyterLab did not start: " + (root / "lab.log").read_text()[-2000:])
            time.sleep(0.3)
    try:
        yield url, token, root
    finally:
        proc.terminate()
        try:
            proc.wait(20)
        except subprocess.TimeoutExpired:
            proc.kill()
        log.close()


def test_live_phase_portrait_in_jupyterlab(lab, driver):
    url, token, root = lab
    driver.get(f"{url}/lab/tree/live.ipynb?token={token}")
    wait_for(driver, "window.jupyterapp && window.jupyterapp.shell && "
             "window.jupyterapp.shell.currentWidget && "
             "window.jupyterapp.shell.currentWidget.sessionContext && "
             "window.jupyterapp.shell.currentWidget.sessionContext.session && "
             "window.jupyterapp.shell.currentWidget.sessionContext.session.kernel && "
             "window.jupyterapp.shell.currentWidget.sessionContext.session.kernel.status === 'idle'",
             timeout=120)
    driver.execute_script("window.jupyterapp.commands.execute('notebook:run-all-cells')")
    wait_for(driver, "window.mechpyLive && window.mechpyLive.ready", timeout=120)
    live = "window.mechpyLive"
    seeds = np.array(driver.execute_script(f"return Array.from({live}.seeds())")).reshape(-1, 2)
    assert seeds.shape == (1000, 2)
    driver.execute_script(f"{live}.step(50)")
    got = np.array(driver.execute_script(f"return Array.from({live}.particles())")).reshape(-1, 2)

    def f(t, y):
        return np.stack([y[:, 1], (1 - y[:, 0]**2) * y[:, 1] - y[:, 0]], axis=1)
    ref = rk4_fixed(f, 0.0, seeds, 0.01, 50)
    assert np.abs(got - ref).max() / np.abs(ref).max() < 1e-4
    # a click's trajectory comes from the kernel: mp.solve's 2001 output points
    driver.execute_script(f"{live}.dropPath(1.0, 0.5)")
    wait_for(driver, f"{live}.paths().length > 0", timeout=60)
    path = np.array(driver.execute_script(f"return {live}.paths()[0]"))
    assert path.shape == (2001, 2)
    t_end = 0.5 + 300 * 0.01
    end = mp.solve(mp.scenes.VanDerPol(mu=1.0), (0.5, t_end), [1.0, 0.5], rtol=1e-12,
                   atol=1e-12).y[:, -1]
    np.testing.assert_allclose(path[-1], end, atol=1e-7)
