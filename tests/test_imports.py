"""mechpy's import graph: no cycle among its modules' module-level imports,
and the "Layout" diagram of CONTRIBUTING.md is the graph the code has."""
from __future__ import annotations

import ast
import importlib.util
import re
from pathlib import Path

import mechpy

ROOT = Path(__file__).resolve().parents[1]          # CONTRIBUTING.md and csrc/ beside tests/
PKG = Path(mechpy.__file__).resolve().parent        # the mechpy under test (maybe installed)


def _module_name(path: Path) -> str:
    parts = path.relative_to(PKG.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _module_level(tree: ast.Module):
    """The import statements that run when the module is imported: at top
    level and inside top-level if/try blocks (not in functions or classes)."""
    todo = list(tree.body)
    while todo:
        node = todo.pop(0)
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        elif isinstance(node, (ast.If, ast.Try)):
            todo.extend(node.body + node.orelse + getattr(node, "finalbody", [])
                        + [s for h in getattr(node, "handlers", []) for s in h.body])


def import_graph() -> dict:
    """{module: set of mechpy modules it imports at module level}; a
    ``from .pkg import name`` counts as importing pkg.name when that is a
    module, else pkg (a package the module lies in does not count)."""
    files = {_module_name(p): p for p in PKG.rglob("*.py")}
    built = set()       # modules the build generates (not files of an editable tree)

    def exists(name: str) -> bool:
        if name in files or name in built:
            return True
        try:
            found = name.startswith("mechpy.") and importlib.util.find_spec(name) is not None
        except (ImportError, ValueError):
            found = False
        if found:
            built.add(name)
        return found

    graph = {}
    for mod, path in files.items():
        is_pkg = path.name == "__init__.py"
        base = mod.split(".") if is_pkg else mod.split(".")[:-1]
        deps = set()
        for node in _module_level(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            else:
                stem = base[:len(base) - node.level + 1] if node.level else []
                head = ".".join(stem + ([node.module] if node.module else []))
                targets = [f"{head}.{a.name}" if exists(f"{head}.{a.name}") else head
                           for a in node.names]
            # a module's own packages are imported before it, never through it
            deps |= {t for t in targets if exists(t) and t != mod
                     and not mod.startswith(t + ".")}
        graph[mod] = deps
    return graph | {m: set() for m in built if m not in graph}


def _cycle(graph: dict):
    """One cycle as a list of modules, or None."""
    state, stack = {}, []

    def visit(m):
        state[m] = 1
        stack.append(m)
        for d in sorted(graph[m]):
            if state.get(d) == 1:
                return stack[stack.index(d):] + [d]
            if d not in state and (c := visit(d)):
                return c
        stack.pop()
        state[m] = 2
        return None

    for m in sorted(graph):
        if m not in state and (c := visit(m)):
            return c
    return None


def test_no_import_cycle():
    graph = import_graph()
    assert "mechpy.scenes" in graph and "mechpy.integrate" in graph["mechpy.scenes"]
    cycle = _cycle(graph)
    assert cycle is None, "import cycle: " + " -> ".join(cycle)


def test_solving_modules_import_one_way_at_load_time():
    """integrate, scenes, cluster and the modules that solve import each other
    at load time, never inside a function to hold a cycle apart."""
    solving = {"mechpy.integrate", "mechpy.scenes", "mechpy.cluster", "mechpy._solution",
               "mechpy._system", "mechpy.phase", "mechpy.frames", "mechpy.tangent",
               "mechpy._motion", "mechpy.plot"}
    late = []
    for mod in sorted(solving):
        path = PKG.joinpath(*mod.split(".")[1:]).with_suffix(".py")
        tree = ast.parse(path.read_text())
        top = set(map(id, _module_level(tree)))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.level and id(node) not in top:
                target = "mechpy." + (node.module or "")
                if target in solving:
                    late.append(f"{mod}:{node.lineno} imports {target} inside a function")
    assert late == []


def test_cycle_finder_finds_one():
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b"}, "b": set()}) is None


#: Left out of CONTRIBUTING's diagram: the extension, the package itself, the
#: helpers every module uses, and the tooling (benchmarks, tours).
SKIP = {"mechpy", "mechpy._core", "mechpy._validate", "mechpy._timing"}
TOOLING = ("mechpy.bench", "mechpy.benches", "mechpy.tours")


def _readme_block() -> str:
    text = (ROOT / "CONTRIBUTING.md").read_text()
    m = re.search(r"^## Layout\n(.*?)^## ", text, flags=re.M | re.S)
    assert m, "CONTRIBUTING.md has no '## Layout' section"
    block = re.search(r"```text\n(.*?)```", m.group(1), flags=re.S)
    assert block, "CONTRIBUTING's Layout section has no ```text block"
    return block.group(1)


def _edges(block: str, csrc: bool) -> dict:
    """The diagram's lines ``a -> b, c``: csrc/ folders, or mechpy modules
    without the ``mechpy.`` prefix (the headings, with parentheses, aside)."""
    edges = {}
    for line in block.splitlines():
        if "->" not in line or "(" in line or line.lstrip().startswith("csrc") != csrc:
            continue
        src, dst = (x.strip() for x in line.split("->", 1))
        pre = "" if csrc else "mechpy."
        edges[pre + src] = {pre + d.strip() for d in dst.split(",") if d.strip()}
    return edges


def test_contributing_layout_is_the_import_graph():
    """Every module with mechpy imports is drawn with exactly those imports."""
    graph = {m: deps - SKIP for m, deps in import_graph().items()
             if m not in SKIP and not m.startswith(TOOLING)}
    graph = {m: deps for m, deps in graph.items() if deps}
    drawn = _edges(_readme_block(), csrc=False)
    assert drawn == graph, {m: (sorted(drawn.get(m, ())), sorted(graph.get(m, ())))
                            for m in set(drawn) | set(graph) if drawn.get(m) != graph.get(m)}


def _folder(path: str) -> str:
    """csrc/<folder> of a file (or a header named from csrc/), csrc for the top."""
    parts = Path(path).parts
    return "csrc/" + parts[0] if len(parts) > 1 else "csrc"


def test_contributing_layout_is_the_csrc_include_graph():
    """The csrc/ lines: each folder -> the folders whose headers it includes."""
    graph = {}
    for f in sorted((ROOT / "csrc").rglob("*.[ch]")):
        src = _folder(str(f.relative_to(ROOT / "csrc")))
        for inc in re.findall(r'^#include "([^"]+)"', f.read_text(), flags=re.M):
            local = (f.parent / inc).exists()   # beside the file, else from csrc/
            dst = src if local else _folder(inc)
            if dst != src:
                graph.setdefault(src, set()).add(dst)
    assert _edges(_readme_block(), csrc=True) == graph
