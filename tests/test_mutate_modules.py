"""scripts/mutate.py's module list against the tree.

Every C source or header under csrc/ and every Python file under mechpy/ is
mutated by exactly one module of scripts/mutate.py (which names the tests that
cover it) or is listed in its EXCLUDED table with the reason; a file added to
the package without either fails here, with where to add it."""
import fnmatch
import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SCRIPT = ROOT / "scripts" / "mutate.py"

pytestmark = pytest.mark.skipif(not SCRIPT.exists(), reason="scripts/ is not in the sdist")


@pytest.fixture(scope="module")
def mutate():
    spec = importlib.util.spec_from_file_location("mechpy_mutate_script", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _excluded(mutate, f):
    return [pat for pat in mutate.EXCLUDED if fnmatch.fnmatch(f, pat)]


def test_every_source_is_in_exactly_one_module_or_excluded(mutate):
    owners = {}
    for name in mutate.MODULES:
        for f in mutate.module_files(name):
            owners.setdefault(f, []).append(name)
    sources = mutate.package_sources()
    assert "csrc/ode/driver.c" in sources and "mechpy/integrate.py" in sources
    missing = [f for f in sources if f not in owners and not _excluded(mutate, f)]
    assert not missing, (
        f"{missing}: not mutated by scripts/mutate.py. Add each to a module of its MODULES "
        "(with the test files that import it or call what it defines) or to its EXCLUDED "
        "table with the reason")
    twice = {f: o for f, o in owners.items() if len(o) > 1}
    assert not twice, f"files in two modules of scripts/mutate.py's MODULES: {twice}"
    both = {f: _excluded(mutate, f) for f in owners if _excluded(mutate, f)}
    assert not both, f"files both mutated and EXCLUDED in scripts/mutate.py: {both}"
    stray = [f for f in owners if f not in sources]
    assert not stray, f"scripts/mutate.py mutates files outside csrc/ and mechpy/: {stray}"


def test_every_entry_names_files_and_existing_tests(mutate):
    for name, (patterns, tests) in mutate.MODULES.items():
        assert mutate.module_files(name), f"module {name!r} of scripts/mutate.py has no file"
        test_files = [t for t in tests if t.startswith("tests/")]
        assert test_files, f"module {name!r} of scripts/mutate.py runs no test file"
        for t in test_files:
            assert (ROOT / t).is_file(), f"module {name!r}: {t} does not exist"
    for pat, why in mutate.EXCLUDED.items():
        assert mutate._glob([pat]), f"EXCLUDED pattern {pat!r} matches no file"
        assert len(why) > 20, f"EXCLUDED {pat!r}: give the reason"


def test_a_file_added_to_csrc_ode_is_mutated(mutate):
    # csrc/ode/ is a glob (the engine's files move between its sources); the lane
    # driver has its own entry, covered by the lanes' tests
    assert mutate.module_files("lanes") == ["csrc/ode/lanes.c", "csrc/ode/lanes.h",
                                            "csrc/ode/fixed.h"]
    assert "tests/test_lanes.py" in mutate.MODULES["lanes"][1]
    assert "tests/test_lanes.py" in mutate.MODULES["ode"][1]
    assert any(fnmatch.fnmatch("csrc/ode/controller.c", p) for p in mutate.MODULES["ode"][0])


def test_candidates_of_c_headers_are_c(mutate):
    # a header's inline functions are mutated as C (a Python parse would drop them)
    text = (ROOT / "csrc/ode/fixed.h").read_text()
    cands = mutate._candidates("csrc/ode/fixed.h", text)
    assert cands and {c[4] for c in cands} >= {"sign", "off-by-one"}
    # a long literal moves in its sixth significant digit, not in the round-off
    no, a, b, new, kind = next(c for c in mutate._candidates(
        "x.c", "    y = 0.12345678901234 * x;\n") if c[4] == "constant")
    assert new == "0.12345778901234"


def test_mutants_inside_python_strings_are_drawn_again(mutate):
    # a docstring's formula or a doctest is not behaviour: the lines of a docstring
    # give no candidates (a triple quote in a comment, as rigid.py's "# f'''(u0)",
    # opens none: it once turned 88 of rigid.py's 131 candidates into docstring
    # text), and a draw inside a string token is skipped at run time
    text = ('def f(a, b):\n'
            '    r"""Sum: a + b.\n\n'
            '    >>> f(1, 2) + 0\n'
            '    3\n'
            '    """\n'
            "    c = a + 1   # f'''(a) + 1\n"
            '    """Not a docstring: a + b."""\n'
            '    return a + b + c\n')
    signs = [c for c in mutate._candidates("x.py", text) if c[4] == "sign"]
    assert sorted({c[0] for c in signs}) == [6, 8]
    cells = mutate._string_cells(text)
    lines = text.splitlines()
    for no in (1, 7):   # the docstring's and the string statement's "+"
        assert mutate._in_string(cells, (no, lines[no].index("+"), 0, "-", "sign"))
    assert not any(mutate._in_string(cells, c) for c in signs)
    rigid = (ROOT / "mechpy/rigid.py").read_text()
    cells = mutate._string_cells(rigid)
    assert not any(mutate._in_string(cells, c) for c in mutate._candidates("rigid.py", rigid))
