#!/usr/bin/env python3
"""Mutation testing for mechpy: do the tests notice a small wrong change?

    python scripts/mutate.py                      # every module, 12 mutants each
    python scripts/mutate.py -m ode -m modes.c -n 20 --seed 3
    python scripts/mutate.py --list               # the modules and their tests
    python scripts/mutate.py --only ode:7 --only modes.py:2   # rerun chosen mutants
    python scripts/mutate.py --edit 'csrc/ode/lanes.c:165:g->dir * g->t[l]=>g->t[l]'

A mutant is one small edit of one source line: a sign flip (``a + b`` ->
``a - b``), a constant's last digit (``0.5`` -> ``0.6``; the sixth significant
digit of a longer literal), an off-by-one (``i < n`` -> ``i <= n``, ``k + 1``
-> ``k + 2``), a condition turned (``==`` <-> ``!=``, ``and`` <-> ``or``), an
operator swapped (``a * b`` <-> ``a / b``) or a dropped term (``a + b * c`` ->
``a``).  The candidates of a module are listed in a fixed
order and drawn at random with a fixed seed, so a run is repeatable and a
mutant has a stable name (``module:index``).

The working tree is never touched: the tracked files are copied to a
temporary directory and the C extension is built there once by meson
(``meson setup`` with this interpreter's meson, ninja and numpy, a release
build as meson-python's); for a C mutant ``ninja`` recompiles only the
mutated file and relinks ``_core``, which goes into the copy's package.
Each mutant runs the tests that cover its module (``-x``: the first failure kills
it; a timeout kills it too).  A mutant that does not compile (or whose Python
does not parse), or that falls inside a Python string (a docstring, a doctest,
a message), is not counted and another is drawn.

The interpreter is the one running this script (it needs numpy, meson,
ninja and the test extra, as the .venv of scripts/dev.sh has):
``.venv/bin/python scripts/mutate.py``.  The report is printed as a table
and written as JSON (``--out``).
"""
from __future__ import annotations

import argparse
import ast
import json
import os
import random
import re
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

FAST = "not ctrl_c and not interrupt"   # the Ctrl-C cases wait seconds on purpose
# test_scipy_ivp_port.py: SciPy's own solve_ivp cases (with SciPy's nfev/njev/nlu
# bounds where the method is SciPy's) run through mp.solve; it calls the engine
# as the others do
ENGINE_TESTS = ["tests/test_integrate.py", "tests/test_engine_regressions.py",
                "tests/test_hard_cases.py", "tests/test_ensemble.py", "tests/test_detest.py",
                "tests/test_scipy_ivp_port.py"]
SCENE_TESTS = ["tests/test_scenes.py", "tests/test_scene_values.py", "tests/test_chain.py",
               "tests/test_frames.py", "tests/test_rigid.py"]
#: The SIMD lane driver and its fixed-step blocks: their own entry, so that the
#: rest of csrc/ode/ (a glob: a file added there is in "ode" at once) keeps
#: its own figures.
LANES = ["csrc/ode/lanes.c", "csrc/ode/lanes.h", "csrc/ode/fixed.h"]
# module -> (source files or globs, the tests that cover them; extra pytest
# arguments allowed).  The tests of a module are the test files that import it
# or call what it defines (a C file: the Python calls that reach it).  Every
# csrc/**/*.c|h and mechpy/**/*.py belongs to exactly one module or to
# EXCLUDED (tests/test_mutate_modules.py checks it against the tree).
MODULES = {
    "ode": (["csrc/ode/*.c", "csrc/ode/*.h"],
            ENGINE_TESTS + ["tests/test_tableaux.py", "tests/test_ode_contracts.py",
                            "tests/test_rigid.py", "tests/test_lanes.py",
                            "tests/test_events.py",
                            "tests/test_events_gsl.py", "tests/test_events_pins.py",
                            "tests/test_widths.py", "-k", FAST]),
    # fixed.h's kick-drift-kick steps run in the method rows too (verlet, yoshida):
    # test_integrate.py holds their tests
    "lanes": (LANES, ["tests/test_lanes.py", "tests/test_ensemble.py", "tests/test_integrate.py",
                      "tests/test_events.py", "-k", FAST]),
    "integrate.py": (["mechpy/integrate.py", "mechpy/_callbacks.py", "mechpy/_solution.py",
                      "mechpy/_system.py"],
                     ENGINE_TESTS + ["tests/test_lanes.py", "tests/test_widths.py",
                                     "tests/test_events.py", "tests/test_events_pins.py",
                                     "-k", FAST]),
    "events.py": (["mechpy/events.py"], ["tests/test_events.py", "tests/test_events_pins.py",
                                         "tests/test_tangent_events.py"]),
    "models": (["csrc/models/*.c", "csrc/models/*.h"], SCENE_TESTS),
    "scenes.py": (["mechpy/scenes.py"], SCENE_TESTS),
    # (the Ctrl-C cases time a SIGINT in wall-clock seconds: they fail on a loaded machine)
    "inertia.c": (["csrc/inertia.c", "csrc/inertia.h"], ["tests/test_inertia.py", "-k", FAST]),
    "rotation.c": (["csrc/rotation.c", "csrc/rotation.h"],
                   ["tests/test_rotation.py", "tests/test_rigid.py"]),
    "modes.c": (["csrc/modes.c", "csrc/modes.h"],
                ["tests/test_modes.py", "tests/test_chain.py", "-k", FAST]),
    "variational.c": (["csrc/variational.c", "csrc/variational.h"],
                      ["tests/test_variational.py", "-k", FAST]),
    # py_events.c (events and impacts, the lanes' restitution rows) is tested through
    # solve and solve_many in test_events.py; py_ode.c's ensemble options in test_ensemble.py
    "binding": (["csrc/py/*.c", "csrc/py/*.h", "csrc/mp_status.c", "csrc/mp_status.h"],
                ["tests/test_errors.py", "tests/test_integrate.py",
                 "tests/test_engine_regressions.py", "tests/test_scenes.py",
                 "tests/test_events.py", "tests/test_ensemble.py",
                 "tests/test_inertia.py", "tests/test_rotation.py", "tests/test_modes.py",
                 "tests/test_compiled.py", "-k", FAST]),
    "inertia.py": (["mechpy/inertia.py"], ["tests/test_inertia.py", "-k", FAST]),
    # to_scipy and from_scipy are tested against SciPy's Rotation in test_conventions.py
    "rotation.py": (["mechpy/rotation.py"], ["tests/test_rotation.py", "tests/test_rigid.py",
                                             "tests/test_conventions.py"]),
    "modes.py": (["mechpy/modes.py"], ["tests/test_modes.py", "tests/test_chain.py", "-k", FAST]),
    "variational.py": (["mechpy/variational/*.py"], ["tests/test_variational.py", "-k", FAST]),
    "symbolic": (["mechpy/symbolic/derive.py", "mechpy/symbolic/codegen.py", "csrc/gen/*.h"],
                 ["tests/test_compiled.py", "tests/test_lanes.py", "-k", "compiled or lane_rhs"]),
    "symbolic.build": (["mechpy/symbolic/__init__.py", "mechpy/symbolic/build.py",
                        "mechpy/symbolic/scene.py"], ["tests/test_compiled.py"]),
    "mechanics": (["mechpy/symbolic/multibody.py", "mechpy/symbolic/models.py",
                   "mechpy/symbolic/_sympy_private.py"],
                  ["tests/test_mechanics.py"]),
    "kinematics": (["mechpy/symbolic/kinematics.py"], ["tests/test_live_bodies.py"]),
    "symbolic.jit": (["mechpy/symbolic/jit.py", "mechpy/symbolic/_jit_rt.py"],
                     ["tests/test_install.py", "-k", "numba or compiler"]),
    "cluster.py": (["mechpy/cluster.py"], ["tests/test_cluster.py"]),
    "phase.py": (["mechpy/phase.py"], ["tests/test_phase.py"]),
    # the sensitivities' jumps at events (impacts, Python actions) are tested in
    # test_tangent_events.py
    "tangent.py": (["mechpy/tangent.py"], ["tests/test_tangent.py",
                                           "tests/test_tangent_events.py"]),
    "frames.py": (["mechpy/frames.py", "mechpy/particles.py"],
                  ["tests/test_frames.py", "tests/test_particles.py"]),
    "rigid.py": (["mechpy/rigid.py"], ["tests/test_rigid.py"]),
    "stress.py": (["mechpy/stress.py"], ["tests/test_stress.py"]),
    "plot.py": (["mechpy/plot.py", "mechpy/_motion.py", "mechpy/_series.py"],
                ["tests/test_plot.py", "tests/test_live_plots.py"]),
    "live": (["mechpy/live/*.py"], ["tests/test_live.py", "tests/test_live_motion.py",
                                    "tests/test_live_bodies.py", "tests/test_live_fields.py",
                                    "tests/test_live_plots.py", "tests/test_live_simulate.py",
                                    "tests/test_live_simulate_bodies.py",
                                    "tests/test_views_jumps.py"]),
    "progress": (["mechpy/_progress.py"], ["tests/test_progress.py"]),
    "support": (["mechpy/_validate.py", "mechpy/errors.py", "mechpy/__init__.py"],
                ["tests/test_validate.py", "tests/test_errors.py", "tests/test_integrate.py",
                 "tests/test_imports.py", "-k", FAST]),
}

#: Files of the package that no module mutates, and why.
EXCLUDED = {
    "mechpy/__main__.py": "the command line's dispatch to the tours and benches "
                          "(test_build runs it; no result of its own to assert)",
    "mechpy/bench.py": "the bench harness: it times and prints, it computes nothing "
                       "that a test could compare with a reference",
    "mechpy/_timing.py": "timers of the benches and tours (wall-clock figures only)",
    "mechpy/benches/*.py": "benchmarks: timings of the modules above against other "
                           "libraries, their correctness is the modules' own (the tests import "
                           "problems.py's reference problems and values, published ones)",
    "mechpy/tours/*.py": "the printed demonstrations of `python -m mechpy tour`: they call "
                         "the modules above and print; test_course runs them for errors only",
}


def _glob(patterns):
    """The files of ``patterns`` (paths or globs relative to the root), sorted."""
    out = []
    for pat in patterns:
        hits = sorted(str(p.relative_to(ROOT)) for p in ROOT.glob(pat) if p.is_file())
        out += [h for h in hits if h not in out]
    return out


def module_files(name):
    """The source files of one module: its globs, less what another module
    names explicitly (lanes.c is in "lanes", not in the glob of "ode")."""
    explicit = {f for other, (pats, _) in MODULES.items() if other != name
                for f in pats if not any(ch in f for ch in "*?[")}
    return [f for f in _glob(MODULES[name][0]) if f not in explicit]


def package_sources():
    """Every file that belongs to some module or to EXCLUDED: the C sources
    and headers under csrc/ and the Python files under mechpy/."""
    return sorted(_glob(["csrc/**/*.c", "csrc/**/*.h", "mechpy/**/*.py"]))


NUM = r"(?<![\w.])(\d+\.\d*(?:[eE][+-]?\d+)?|\d*\.\d+(?:[eE][+-]?\d+)?|\d+[eE][+-]?\d+)(?![\w.])"
INT = r"(?<![\w.])(\d+)(?![\w.])"


def _string_spans(line):
    """Character ranges of string and char literals in one line (never mutated)."""
    return [m.span() for m in re.finditer(r'"(?:\\.|[^"\\])*"|\'(?:\\.|[^\'\\])*\'', line)]


def _code_lines(path, text):
    """(line number, code part) of the lines worth mutating: statements inside
    function bodies, with comments, preprocessor lines and docstrings left out."""
    out = []
    c = path.endswith((".c", ".h"))
    in_block = False   # inside /* */ (C) or a triple-quoted string (Python)
    for no, line in enumerate(text.splitlines()):
        if c:
            code = line
            if in_block:
                if "*/" not in code:
                    continue
                code = " " * (code.index("*/") + 2) + code[code.index("*/") + 2:]
                in_block = False
            code = re.sub(r"/\*.*?\*/", lambda m: " " * len(m.group()), code)
            if "/*" in code:
                code = code[:code.index("/*")]
                in_block = True
            code = code.split("//")[0]
            if code.lstrip().startswith("#") or not code.startswith((" ", "\t")):
                continue
        else:
            head = line
            if "#" in line and not re.search("['\"]", line[:line.index("#")]):
                head = line[:line.index("#")]   # f'''(u) in a comment opens no string
            n3 = head.count('"""') + head.count("'''")
            if in_block or n3:
                if n3 % 2 == 1:
                    in_block = not in_block
                continue
            code = line.split("#")[0] if "#" in line and "'" not in line and '"' not in line \
                else line
            s = code.lstrip()
            if not code.startswith((" ", "\t")) or s.startswith(("raise ", "def ", "class ",
                                                                  "@", "import ", "from ",
                                                                  "assert ")):
                continue
        if code.strip():
            out.append((no, code))
    return out


def _candidates(path, text):
    """Every mutant of one file, in a fixed order: (line, start, end, new, kind)."""
    c = path.endswith((".c", ".h"))
    cands = []
    for no, code in _code_lines(path, text):
        spans = _string_spans(code)

        def add(start, end, new, kind):
            if not any(a <= start < b for a, b in spans):
                cands.append((no, start, end, new, kind))

        for m in re.finditer(r"(?<=[\w)\]]) ([+-]) (?=[\w(.])", code):
            add(m.start(1), m.end(1), "-" if m.group(1) == "+" else "+", "sign")
        for m in re.finditer(NUM, code):
            s = m.group(1)
            mant = re.match(r"[\d.]+", s).group()
            # the last digit, or the sixth significant one of a longer literal (a
            # tableau's 17-digit coefficient moved in its last digit is round-off)
            sig = [k for k, ch in enumerate(mant) if ch.isdigit()
                   and (ch != "0" or any(c2 not in "0." for c2 in mant[:k]))]
            i = sig[5] if len(sig) > 6 else max(k for k, ch in enumerate(mant) if ch.isdigit())
            new = s[:i] + str((int(s[i]) + 1) % 10) + s[i + 1:]
            add(m.start(1), m.end(1), new, "constant")
        for m in re.finditer(r"(?<![<>=!-])(<=|>=|<|>)(?![<>=])", code):
            op = m.group(1)
            if op in ("<", ">") and not re.search(r"\s$", code[:m.start()]):
                continue  # template-like or arrow tokens; relational ops are spaced here
            add(m.start(1), m.end(1), {"<": "<=", "<=": "<", ">": ">=", ">=": ">"}[op],
                "off-by-one")
        for m in re.finditer(r"(?<=[+-] )" + INT, code):
            add(m.start(1), m.end(1), str(int(m.group(1)) + 1), "off-by-one")
        for m in re.finditer(r"\[" + INT + r"\]", code):
            k = int(m.group(1))
            add(m.start(1), m.end(1), str(k + 1 if k == 0 else k - 1), "off-by-one")
        for m in re.finditer(r" (==|!=) ", code):
            add(m.start(1), m.end(1), "!=" if m.group(1) == "==" else "==", "condition")
        for m in re.finditer(r" (and|or|&&|\|\|) ", code):
            add(m.start(1), m.end(1), {"and": "or", "or": "and", "&&": "||",
                                       "||": "&&"}[m.group(1)], "condition")
        for m in re.finditer(r"(?<=[\w)\]]) ([*/]) (?=[\w(.])", code):
            add(m.start(1), m.end(1), "/" if m.group(1) == "*" else "*", "operator")
        # a dropped term: " + X" or " - X" up to the next +/- at depth 0, ')' or ';'
        for m in re.finditer(r"(?<=[\w)\]]) [+-] (?=[\w(.])", code):
            depth, j = 0, m.end()
            while j < len(code):
                ch = code[j]
                if ch in "([":
                    depth += 1
                elif ch in ")]":
                    if depth == 0:
                        break
                    depth -= 1
                elif depth == 0 and (ch in ";,:" or (ch in "+-" and code[j - 1] == " "
                                                     and code[j + 1:j + 2] == " ")):
                    break
                j += 1
            end = j
            while end > m.end() and code[end - 1] == " ":
                end -= 1
            if end > m.end():
                add(m.start(), end, "", "dropped term")
    if not c:  # a Python mutant must parse and change the tree
        tree0 = ast.dump(ast.parse(text))
        lines = text.splitlines(keepends=True)
        keep = []
        for cand in cands:
            no, a, b, new, _ = cand
            mutated = lines[:no] + [lines[no][:a] + new + lines[no][b:]] + lines[no + 1:]
            try:
                if ast.dump(ast.parse("".join(mutated))) != tree0:
                    keep.append(cand)
            except SyntaxError:
                pass
        cands = keep
    return cands


def _string_cells(text):
    """(line, column) cells covered by Python string tokens (docstrings, doctests,
    messages): a mutant there changes no behaviour the tests can reach."""
    import io
    import tokenize
    cells = set()
    for tok in tokenize.generate_tokens(io.StringIO(text).readline):
        if tok.type == tokenize.STRING or tok.type == getattr(tokenize, "FSTRING_MIDDLE", -1):
            (r0, c0), (r1, c1) = tok.start, tok.end
            for r in range(r0, r1 + 1):
                a = c0 if r == r0 else 0
                b = c1 if r == r1 else 10 ** 6
                cells.add((r - 1, a, b))
    return cells


def _in_string(cells, cand):
    no, a = cand[0], cand[1]
    return any(r == no and lo <= a < hi for r, lo, hi in cells)


def _apply(text, cand):
    no, a, b, new, _ = cand
    lines = text.splitlines(keepends=True)
    lines[no] = lines[no][:a] + new + lines[no][b:]
    return "".join(lines)


class Tree:
    """A copy of the tracked files with the extension built by meson beside it.

    ``meson setup`` configures a build directory (``build/mut``) in the copy with
    the interpreter's own meson, ninja and numpy (as scripts/sanitize.sh and the
    editable install do); ``ninja`` then recompiles only what changed and
    relinks ``_core``, which is copied into the copy's ``mechpy/``.  The tests
    import that package: a ``sitecustomize`` on ``PYTHONPATH`` removes the
    editable install's import hook (it would load the working tree's build).
    """

    def __init__(self, py, keep=False):
        self.py = py
        self.dir = Path(tempfile.mkdtemp(prefix="mechpy-mutate-"))
        self.keep = keep
        files = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, check=True,
                               capture_output=True).stdout.decode().split("\0")
        for f in filter(None, files):
            src, dst = ROOT / f, self.dir / f
            if src.is_file():
                dst.parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(src, dst)
        bindir = Path(py).parent
        meson = bindir / "meson"
        meson = str(meson) if meson.exists() else shutil.which("meson")
        if meson is None:
            sys.exit("mutate: meson not found beside the interpreter or on PATH "
                     "(pip install meson ninja)")
        path = os.environ.get("PATH", "")
        self.benv = dict(os.environ, PATH=f"{bindir}{os.pathsep}{path}")
        self.build_dir = self.dir / "build" / "mut"
        # the options of meson-python's wheel build: a release build, asserts off
        r = subprocess.run([meson, "setup", str(self.build_dir), "--buildtype=release",
                            "-Db_ndebug=if-release"], cwd=self.dir, env=self.benv,
                           capture_output=True, text=True)
        if r.returncode:
            sys.exit(f"mutate: meson setup failed\n{r.stdout[-3000:]}{r.stderr[-3000:]}")
        self.ninja = [meson, "compile", "-C", str(self.build_dir)]
        if not self.build():
            sys.exit(f"mutate: the unmutated build failed\n{self.last_log[-3000:]}")
        site = self.dir / "build" / "site"
        site.mkdir(parents=True, exist_ok=True)
        (site / "sitecustomize.py").write_text(
            "import sys\n"
            "sys.meta_path[:] = [f for f in sys.meta_path\n"
            "                    if not (type(f).__module__.startswith('_mechpy')\n"
            "                            and type(f).__module__.endswith('_editable_loader'))]\n")
        self.env = dict(os.environ, PYTHONPATH=f"{self.dir}{os.pathsep}{site}",
                        PYTHONDONTWRITEBYTECODE="1", PYTHONSAFEPATH="1")
        self.env.pop("MECHPY_SANITIZED", None)
        where = subprocess.run([py, "-c", "import mechpy._core as c; print(c.__file__)"],
                               cwd=self.dir, env=self.env, capture_output=True, text=True)
        if not where.stdout.startswith(str(self.dir / "mechpy")):
            sys.exit(f"mutate: the copy does not import its own build: {where.stdout}"
                     f"{where.stderr}")

    def build(self, src=None):
        """Rebuild what changed (ninja: the mutated file, then the link) and put
        the new ``_core`` into the copy's package; True when it compiled."""
        r = subprocess.run(self.ninja, cwd=self.dir, env=self.benv, capture_output=True,
                           text=True)
        self.last_log = r.stdout + r.stderr
        if r.returncode:
            return False
        for so in self.build_dir.glob("_core*.so"):
            for old in (self.dir / "mechpy").glob("_core*.so"):
                old.unlink()
            shutil.copyfile(so, self.dir / "mechpy" / so.name)
        # csrc/gen/*.h's text, generated by the build as mechpy.symbolic._ctext
        # (csrc/meson.build); the package imports it (codegen.py)
        for py in self.build_dir.glob("csrc/_ctext.py"):
            shutil.copyfile(py, self.dir / "mechpy" / "symbolic" / py.name)
        return True

    def pytest(self, tests, timeout):
        """(exit code or 'timeout', seconds) of the tests in this copy."""
        t0 = time.monotonic()
        try:
            r = subprocess.run([self.py, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider",
                                "-o", "addopts=", "--no-header", *tests],
                               cwd=self.dir, env=self.env, capture_output=True, text=True,
                               timeout=timeout)
            rc = r.returncode
        except subprocess.TimeoutExpired:
            rc = "timeout"
        return rc, time.monotonic() - t0

    def close(self):
        if not self.keep:
            shutil.rmtree(self.dir, ignore_errors=True)


def _run_module(tree, name, n, seed, only, log):
    files, tests = module_files(name), MODULES[name][1]
    tests = [t for t in tests if not t.startswith("tests/") or (tree.dir / t).exists()]
    pool = []
    for f in files:
        text = (tree.dir / f).read_text()
        pool += [(f, cand) for cand in _candidates(f, text)]
    order = list(range(len(pool)))
    random.Random(f"{seed}:{name}").shuffle(order)
    rc, base = tree.pytest(tests, timeout=1800)
    if rc != 0:
        sys.exit(f"mutate: {name}: the tests fail on the unmutated copy (exit {rc})")
    timeout = 3 * base + 60
    log(f"== {name}: {len(pool)} candidates in {len(files)} file(s); tests {base:.0f} s")
    results = []
    strings = {}
    for index, k in enumerate(order):
        tag = f"{name}:{index}"
        if only is not None and tag not in only:
            continue
        if only is None and len(results) >= n:
            break
        f, cand = pool[k]
        path = tree.dir / f
        text = path.read_text()
        if f.endswith(".py"):
            if f not in strings:
                strings[f] = _string_cells(text)
            if _in_string(strings[f], cand):
                log(f"   {tag} is inside a string (a docstring, a message), drawn again")
                continue
        path.write_text(_apply(text, cand))
        try:
            ok = tree.build() if f.endswith((".c", ".h")) else True
            if not ok:
                log(f"   {tag} does not compile, drawn again")
                continue
            rc, secs = tree.pytest(tests, timeout)
        finally:
            path.write_text(text)
        no, a, b, new, kind = cand
        line = text.splitlines()[no]
        status = "survived" if rc == 0 else "killed"
        row = {"id": tag, "file": f, "line": no + 1, "kind": kind, "status": status,
               "exit": rc, "seconds": round(secs, 1), "before": line.strip(),
               "after": (line[:a] + new + line[b:]).strip()}
        results.append(row)
        log(f"   {tag:18s} {status:8s} {f}:{no + 1} {kind}: {row['after']}")
    if any(f.endswith((".c", ".h")) for f in files):
        tree.build()  # the unmutated sources again
    return results


def _owner(path):
    """The module whose files hold ``path``."""
    for name in MODULES:
        if path in module_files(name):
            return name
    sys.exit(f"mutate: {path} is in no module of MODULES")


def _run_edits(tree, edits, log, only_tests=None):
    """Hand-written mutants (an audit's): ``path:line:old=>new`` replaces old by
    new on that line (1-based); each runs the tests of the module holding path."""
    rows = []
    for e in edits:
        try:
            path, line, change = e.split(":", 2)
            old, new = change.split("=>", 1)
            no = int(line) - 1
        except ValueError:
            sys.exit(f"mutate: --edit wants path:line:old=>new, got {e!r}")
        name = _owner(path)
        f = tree.dir / path
        text = f.read_text()
        lines = text.splitlines(keepends=True)
        if old not in lines[no]:
            sys.exit(f"mutate: --edit {e!r}: {old!r} is not on line {no + 1} of {path}: "
                     f"{lines[no].strip()!r}")
        before = lines[no]
        lines[no] = lines[no].replace(old, new, 1)
        f.write_text("".join(lines))
        try:
            c = path.endswith((".c", ".h"))
            if c and not tree.build():
                log(f"   {e}: does not compile\n{tree.last_log[-2000:]}")
                continue
            tests = only_tests or [t for t in MODULES[name][1]
                                   if not t.startswith("tests/") or (tree.dir / t).exists()]
            rc, secs = tree.pytest(tests, timeout=1800)
        finally:
            f.write_text(text)
            if path.endswith((".c", ".h")):
                tree.build()
        status = "survived" if rc == 0 else "killed"
        rows.append({"id": e, "file": path, "line": no + 1, "kind": "edit", "status": status,
                     "exit": rc, "seconds": round(secs, 1), "before": before.strip(),
                     "after": lines[no].strip()})
        log(f"   {status:8s} ({name}, {secs:.0f} s) {e}")
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("-m", "--module", action="append", choices=sorted(MODULES),
                    help="a module to mutate (repeatable; default: all)")
    ap.add_argument("-n", type=int, default=12, help="mutants per module (default 12)")
    ap.add_argument("--seed", type=int, default=20241123)
    ap.add_argument("--only", action="append", help="run only these mutants (module:index)")
    ap.add_argument("--out", default=str(ROOT / "build" / "mutate-report.json"),
                    help="the JSON report (default: build/, which git ignores)")
    ap.add_argument("--keep", action="store_true", help="keep the temporary copy")
    ap.add_argument("--edit", action="append",
                    help="a hand-written mutant path:line:old=>new (repeatable; runs the "
                         "tests of the module holding path)")
    ap.add_argument("--tests", help="with --edit: these pytest arguments instead of the "
                                    "module's tests (one string)")
    ap.add_argument("--list", action="store_true", help="list the modules and their tests")
    a = ap.parse_args(argv)
    if a.list:
        for name, (_, tests) in MODULES.items():
            print(f"{name:15s} {' '.join(module_files(name))}\n{'':15s} -> {' '.join(tests)}")
        for pat, why in EXCLUDED.items():
            print(f"{'(excluded)':15s} {pat}: {why}")
        return 0
    names = a.module or list(MODULES)
    only = set(a.only) if a.only else None
    if only:
        names = [nm for nm in names if any(o.split(":")[0] == nm for o in only)]

    def log(msg):
        print(msg, flush=True)

    # SIGTERM (a background job ignores SIGINT) ends the run as Ctrl-C does: the
    # report of the mutants done so far is written and the copy removed
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    tree = Tree(sys.executable, keep=a.keep)
    log(f"mutate: copy in {tree.dir}")
    report = {}
    try:
        if a.edit:
            report["edits"] = _run_edits(tree, a.edit, log, a.tests and shlex.split(a.tests))
            names = []
        for name in names:
            report[name] = _run_module(tree, name, a.n, a.seed, only, log)
    finally:
        tree.close()
        Path(a.out).parent.mkdir(parents=True, exist_ok=True)
        Path(a.out).write_text(json.dumps(report, indent=1))
    print(f"\n{'module':16s} {'mutants':>7s} {'killed':>7s} {'survived':>8s} {'rate':>6s}")
    for name, rows in report.items():
        k = sum(r["status"] == "killed" for r in rows)
        print(f"{name:16s} {len(rows):7d} {k:7d} {len(rows) - k:8d} "
              f"{(100 * k / len(rows) if rows else 0):5.0f}%")
    for name, rows in report.items():
        for r in rows:
            if r["status"] == "survived":
                print(f"survived {r['id']}: {r['file']}:{r['line']} {r['kind']}\n"
                      f"    - {r['before']}\n    + {r['after']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
