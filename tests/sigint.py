"""Shared by the tests of Ctrl-C: run a call in a child interpreter, send it
SIGINT after a delay, and report how late KeyboardInterrupt arrived.

The clocks start at the signal, not at the child's start: the child reports
the moment it sends SIGINT, and from then on it has ``lost_after`` seconds to
report KeyboardInterrupt.  Starting an interpreter, importing mechpy and
running ``setup`` may take long (minutes under ASan on a loaded machine, where
a whole-run timeout of 120 s failed a test whose interrupt was fine); only a
lost or very late interrupt fails, and says so."""
from __future__ import annotations

import os
import queue
import subprocess
import sys
import threading
import time
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
    # SENT first, in one write: printed after the kill it raced the main thread's report
    # (two threads' prints interleave) and the parent read "SENTINTERRUPTED ..."
    sys.stdout.write("SENT\n")
    sys.stdout.flush()
    sent["t"] = time.perf_counter()
    sent["cpu"] = time.process_time()
    os.kill(os.getpid(), signal.SIGINT)
threading.Timer(delay, fire).start()
t0 = time.perf_counter()
try:
    env["_call"]()
    print(f"FINISHED {time.perf_counter() - t0:.3f}", flush=True)
except KeyboardInterrupt:
    print(f"INTERRUPTED {time.perf_counter() - sent['t']:.3f} "
          f"{time.process_time() - sent['cpu']:.3f}", flush=True)
'''


def run_child(argv, *, cwd=None, timeout: float = 900.0, lost_after: float = 60.0,
              what: str = "the call"):
    """Run ``python -c argv...`` (the child prints a line ``SENT`` when it sends itself
    SIGINT) and return (exit status, stdout lines but SENT, stderr).

    ``timeout`` bounds the child's start and set-up (a hang there), ``lost_after`` the
    time from SIGINT to the child's exit: beyond it the interrupt counts as lost, the
    child is killed and AssertionError is raised."""
    env = dict(os.environ)
    root = str(Path(mechpy.__file__).resolve().parent.parent)
    env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    p = subprocess.Popen([sys.executable, "-c", *argv], cwd=cwd, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, env=env)
    lines: queue.Queue = queue.Queue()
    err: list = []

    def read(stream, sink, end):
        for line in stream:
            sink(line.rstrip("\n"))
        if end:
            sink(None)                  # end of output: the child closed stdout

    threading.Thread(target=read, args=(p.stdout, lines.put, True), daemon=True).start()
    te = threading.Thread(target=read, args=(p.stderr, err.append, False), daemon=True)
    te.start()
    out, deadline, sent_at = [], time.monotonic() + timeout, None
    try:
        while True:
            limit = deadline if sent_at is None else sent_at + lost_after
            try:
                line = lines.get(timeout=max(0.0, limit - time.monotonic()))
            except queue.Empty:
                if sent_at is None:
                    raise AssertionError(f"the child did not reach {what} within {timeout} s "
                                         "(start-up and set-up)") from None
                raise AssertionError(f"KeyboardInterrupt was lost: the child had not ended "
                                     f"{lost_after} s after SIGINT ({what})") from None
            if line is None:
                break
            if line == "SENT":
                sent_at = time.monotonic()
            else:
                out.append(line)
        p.wait(max(1.0, (sent_at or time.monotonic()) + lost_after - time.monotonic()))
    except subprocess.TimeoutExpired:
        raise AssertionError(f"KeyboardInterrupt was lost: the child had not exited "
                             f"{lost_after} s after SIGINT ({what})") from None
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
        te.join(5.0)
    return p.returncode, out, "\n".join(err)


def interrupt_delay(setup: str, call: str, delay: float = 0.3, timeout: float = 900.0,
                    lost_after: float = 60.0) -> float:
    """CPU seconds the child spent from SIGINT to KeyboardInterrupt for ``eval(call)``
    after ``exec(setup)`` in a fresh interpreter (names np and mp are defined).

    The latency of an interrupt is the work done before the next check for it: counted
    in the child's CPU time it is the same on a quiet machine and on one at load 10
    (where the wall clock, a tenth of a core's, made 0.06 s into 1.1 s).  The wall clock
    bounds hangs only: ``timeout`` the child's start and set-up, ``lost_after`` the time
    from SIGINT to its report (see :func:`run_child`).  Raises AssertionError if the
    interrupt was lost, the call finished first or the child failed otherwise."""
    rc, res, stderr = run_child([CHILD, setup, call, str(delay)], timeout=timeout,
                                lost_after=lost_after, what=call)
    assert rc == 0 and res, f"exit status {rc}: {stderr[-3000:]}"
    assert res[-1].startswith("INTERRUPTED"), f"the call was not interrupted: {res[-1]}"
    return float(res[-1].split()[2])


def interrupt_delays(setup: str, call: str, delay: float = 0.3) -> tuple:
    """(wall seconds, CPU seconds) from SIGINT to KeyboardInterrupt, as
    :func:`interrupt_delay` measures them."""
    rc, res, stderr = run_child([CHILD, setup, call, str(delay)], what=call)
    assert rc == 0 and res and res[-1].startswith("INTERRUPTED"), stderr[-3000:]
    return float(res[-1].split()[1]), float(res[-1].split()[2])
