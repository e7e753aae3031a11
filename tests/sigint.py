"""Shared by the tests of Ctrl-C: run a call in a child interpreter, send it
SIGINT after a delay, and report how late KeyboardInterrupt arrived."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import mechpy

CHILD = r'''
import os, signal, sys, threading, time
import numpy as np
import scipy.sparse  # imported lazily by mechpy.modes: not inside the timed call
import mechpy as mp
setup, call, delay = sys.argv[1], sys.argv[2], float(sys.argv[3])
signal.signal(signal.SIGINT, signal.default_int_handler)
env = {"np": np, "mp": mp}
exec(setup, env)
# a function, not eval(call): a KeyboardInterrupt leaving eval's code marks the process
# to end by SIGINT even when it is caught
exec("def _call():\n    return " + call, env)
sent = {}
def fire():
    sent["t"] = time.perf_counter()
    os.kill(os.getpid(), signal.SIGINT)
threading.Timer(delay, fire).start()
t0 = time.perf_counter()
try:
    env["_call"]()
    print(f"FINISHED {time.perf_counter() - t0:.3f}")
except KeyboardInterrupt:
    print(f"INTERRUPTED {time.perf_counter() - sent['t']:.3f}")
'''


def interrupt_delay(setup: str, call: str, delay: float = 0.3, timeout: float = 120.0) -> float:
    """Seconds from SIGINT to KeyboardInterrupt for ``eval(call)`` after ``exec(setup)``
    in a fresh interpreter (names np and mp are defined); raises AssertionError if the
    call finished first or failed otherwise."""
    env = dict(os.environ)
    root = str(Path(mechpy.__file__).resolve().parent.parent)
    env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    r = subprocess.run([sys.executable, "-c", CHILD, setup, call, str(delay)],
                       capture_output=True, text=True, timeout=timeout, env=env)
    out = r.stdout.strip().splitlines()
    assert r.returncode == 0 and out, r.stderr[-3000:]
    assert out[-1].startswith("INTERRUPTED"), f"the call was not interrupted: {out[-1]}"
    return float(out[-1].split()[1])
