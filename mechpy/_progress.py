"""Progress of long work told in stages (deriving a system, printing its C,
compiling it; a portrait's overlays): silent for the first second, in which most
calls end, then a ``tqdm.auto`` bar over the stages (a widget in a notebook, a
line on a terminal) or, without tqdm, one line on stderr per stage.  The same
rule as ``solve_many(progress=True)``'s bar, with no argument to ask for it:
``MECHPY_PROGRESS=0`` in the environment keeps it silent.

A timer thread shows the bar when the first second passes inside a stage (a
SymPy derivation of 10 s is one stage): it only draws, it never touches the
work.
"""
from __future__ import annotations

import os
import sys
import threading
import time

#: seconds of silence before progress shows
AFTER = 1.0


class Stages:
    """Progress of ``what`` through ``stages`` (names, in order).

    Use as a context manager; ``stage(name)`` enters the next stage.  Nothing is
    drawn unless the work is still running ``after`` seconds after it began.
    """

    def __init__(self, what: str, stages, after: float | None = None):
        self.what = what
        self.stages = list(stages)
        self.after = AFTER if after is None else after
        self.current = None
        self.done = 0
        self.bar = None
        self.shown = False
        self.t0 = time.perf_counter()
        self.lock = threading.Lock()
        self.timer = None
        self.silent = os.environ.get("MECHPY_PROGRESS", "1").strip() in ("0", "false", "no")

    def __enter__(self):
        if not self.silent and self.after <= 0.0:
            self._show()            # at once (no timer: deterministic)
        elif not self.silent:
            self.timer = threading.Timer(self.after, self._show)
            self.timer.daemon = True
            self.timer.start()
        return self

    def __exit__(self, *exc):
        if self.timer is not None:
            self.timer.cancel()
        with self.lock:
            if self.bar is not None:
                if exc[0] is None:
                    self.bar.update(len(self.stages) - self.bar.n)
                self.bar.close()
            elif self.shown and exc[0] is None:
                self._line("done")
        return False

    def stage(self, name: str) -> None:
        """Enter stage ``name`` (the stages before it are done)."""
        with self.lock:
            if self.current is not None:
                self.done += 1
            self.current = name
            if self.bar is not None:
                self.bar.set_description(f"{self.what}: {name}", refresh=False)
                self.bar.update(self.done - self.bar.n)
            elif self.shown:
                self._line(name)

    def _show(self) -> None:
        """The first second has passed: draw the bar (or the first line)."""
        with self.lock:
            self.shown = True
            try:
                from tqdm.auto import tqdm
            except ImportError:
                self._line(self.current or "working")
                return
            try:
                self.bar = tqdm(total=len(self.stages), desc=f"{self.what}: {self.current}",
                                unit="stage", leave=False)
                self.bar.update(self.done)
            except Exception:       # a bar that cannot draw never stops the work
                self.bar = None
                self._line(self.current or "working")

    def _line(self, name: str) -> None:
        elapsed = time.perf_counter() - self.t0
        print(f"{self.what}: {name} ({elapsed:.1f} s)", file=sys.stderr, flush=True)
