"""The packages' layering: floewave <- sweep <- herman2019 (the study imports sweep and
floewave; neither imports it), no import circle in any of them, no module of any over 450
lines, no private name imported across modules, and a docstring on every module.

The import graph is built with :mod:`ast` from every ``import`` statement of a module,
including those inside functions (a function-level import that hides a circle is still a
circle). Run as a script to print the graph's circles and the longest modules::

    python tests/test_layers.py
"""
from __future__ import annotations

import ast
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("sweep", "floewave", "herman2019")
MAX_LINES = 450
LINE_RULE = PACKAGES


def module_name(path: Path) -> str:
    """The dotted name of the module at ``path`` (a file under ROOT)."""
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def modules(package: str) -> dict[str, Path]:
    """Every module of ``package``: dotted name -> file."""
    return {module_name(p): p for p in sorted((ROOT / package).rglob("*.py"))}


def _resolve(current: str, is_package: bool, node: ast.ImportFrom) -> str:
    if not node.level:
        return node.module or ""
    base = current.split(".")
    if not is_package:
        base = base[:-1]
    if node.level > 1:
        base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _type_checking(node: ast.AST) -> bool:
    test = getattr(node, "test", None)
    return isinstance(node, ast.If) and (
        (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING")
        or (isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"))


def _walk(node: ast.AST):
    """Every node under ``node`` but those of ``if TYPE_CHECKING:`` blocks."""
    for child in ast.iter_child_nodes(node):
        if _type_checking(child):
            for other in child.orelse:
                yield other
                yield from _walk(other)
            continue
        yield child
        yield from _walk(child)


def imports(name: str, path: Path, known: set[str]) -> list[tuple[str, str]]:
    """The (module, imported name) pairs that module ``name`` imports from ``known``.

    ``from a import b`` counts as an import of ``a.b`` when that is a module, else of
    ``a`` (with ``b`` as the imported name). Imports under ``if TYPE_CHECKING:`` are not
    counted: they never run.
    """
    tree = ast.parse(path.read_text(), filename=str(path))
    is_package = path.name == "__init__.py"
    found: list[tuple[str, str]] = []
    for node in _walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                target = alias.name
                while target and target not in known:
                    target = target.rpartition(".")[0]
                if target:
                    found.append((target, ""))
        elif isinstance(node, ast.ImportFrom):
            source = _resolve(name, is_package, node)
            for alias in node.names:
                sub = f"{source}.{alias.name}"
                if sub in known:
                    found.append((sub, ""))
                elif source in known:
                    found.append((source, alias.name))
    return found


def graph(packages=PACKAGES) -> dict[str, set[str]]:
    """The import graph of ``packages``: module -> modules it imports.

    A package's ``__init__`` is not counted as imported by its own submodules' parents
    (``import sweep.store.reader`` runs ``sweep/__init__`` and ``sweep/store/__init__``,
    but those edges are Python's, not the code's).
    """
    files: dict[str, Path] = {}
    for package in packages:
        files.update(modules(package))
    known = set(files)
    return {name: {t for t, _ in imports(name, path, known) if t != name}
            for name, path in files.items()}


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    counter = [0]
    sys.setrecursionlimit(max(10000, sys.getrecursionlimit()))

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return found


def private_imports(packages=PACKAGES) -> list[str]:
    """``module imports module2._name`` for every private name imported across modules."""
    files: dict[str, Path] = {}
    for package in packages:
        files.update(modules(package))
    known = set(files)
    bad = []
    for name, path in files.items():
        for target, imported in imports(name, path, known):
            leaf = imported or target.rpartition(".")[2]
            if target != name and leaf.startswith("_") and not leaf.startswith("__"):
                bad.append(f"{name} imports {target}{'.' + imported if imported else ''}")
    return bad


def _private(dotted: str) -> bool:
    return any(part.startswith("_") and not part.startswith("__")
               for part in dotted.split("."))


def private_floewave_imports(package: str = "sweep") -> list[str]:
    """``module imports floewave._x`` for every import by ``package`` of a private
    floewave module or name (floewave's public names are its own: :mod:`floewave`,
    :mod:`floewave.paths`, :mod:`floewave.help`...)."""
    bad = []
    for name, path in modules(package).items():
        for node in _walk(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
                targets = [f"{node.module}.{alias.name}" for alias in node.names]
            else:
                continue
            bad += [f"{name} imports {t}" for t in targets
                    if t.split(".")[0] == "floewave" and _private(t)]
    return bad


#: Imports of a private floewave module left in code another change moves out of sweep
#: (issue 44: sweep/paper/ becomes its own package; it is to use
#: ``floewave.march_coefficients``). Each must still be there: drop it once it is gone.


def long_modules(packages=LINE_RULE, limit: int = MAX_LINES) -> list[tuple[str, int]]:
    """Modules of ``packages`` longer than ``limit`` lines, longest first."""
    out = []
    for package in packages:
        for name, path in modules(package).items():
            n = len(path.read_text().splitlines())
            if n > limit:
                out.append((name, n))
    return sorted(out, key=lambda item: -item[1])


@pytest.mark.parametrize("package", PACKAGES)
def test_no_import_circle(package):
    found = cycles(graph((package,)))
    assert not found, f"import circles in {package}/: {found}"


def test_cycles_finds_a_circle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_function_level_imports_count(tmp_path, monkeypatch):
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text('"""p."""\n')
    (pkg / "a.py").write_text('"""a."""\nfrom . import b\n')
    (pkg / "b.py").write_text('"""b."""\ndef f():\n    from .a import g\n    return g\n')
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    assert cycles(graph(("pkg",))) == [["pkg.a", "pkg.b"]]


def package_graph(package: str = "sweep") -> dict[str, set[str]]:
    """The import graph between the parts of ``package``: its subpackages and top-level
    modules (``sweep.store``, ``sweep.run``, ``sweep.cli``...)."""
    def part(module: str) -> str:
        return ".".join(module.split(".")[:2])

    edges: dict[str, set[str]] = {}
    for module, targets in graph((package,)).items():
        edges.setdefault(part(module), set()).update(
            part(t) for t in targets if part(t) != part(module))
    return edges


def test_the_parts_of_sweep_form_layers():
    """No circle between sweep's subpackages either: store, run, analysis, report, cli each
    point down only."""
    assert not cycles(package_graph("sweep"))


@pytest.mark.parametrize("package", LINE_RULE)
def test_no_long_module(package):
    assert not long_modules((package,)), f"modules over {MAX_LINES} lines"


def test_no_private_name_imported_across_modules():
    assert not private_imports(("sweep", "herman2019"))


def test_the_packages_form_layers():
    """floewave <- sweep <- herman2019: no module of sweep/ or floewave/ imports the study,
    and no circle runs through the three packages together."""
    edges = graph(PACKAGES)
    up = [f"{m} imports {t}" for m, targets in edges.items()
          if m.split(".")[0] in ("sweep", "floewave")
          for t in targets if t.split(".")[0] == "herman2019"]
    assert not up, f"the library imports the study: {up}"
    assert not cycles(edges)


def test_the_layer_rule_sees_an_import_of_the_study(tmp_path, monkeypatch):
    for package, text in (("sweep", "from herman2019.check import x\n"),
                          ("herman2019", "import sweep\n")):
        (tmp_path / package).mkdir()
        (tmp_path / package / "__init__.py").write_text(f'"""{package}."""\n' + text)
    (tmp_path / "herman2019" / "check.py").write_text('"""c."""\n')
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    edges = graph(("sweep", "herman2019"))
    assert "herman2019.check" in edges["sweep"] and "sweep" in edges["herman2019"]


@pytest.mark.parametrize("package", ["sweep", "herman2019"])
def test_no_private_floewave_module_is_imported_from_outside(package):
    """sweep and the study use floewave's public names only (a private module of floewave
    may change or go with any release of it)."""
    assert sorted(private_floewave_imports(package)) == []


def test_private_floewave_imports_are_found(tmp_path, monkeypatch):
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text('"""p."""\n')
    (pkg / "a.py").write_text('"""a."""\nimport floewave._jit\nfrom floewave import _kernels'
                              '\nfrom floewave.paths import quiet_stdout\nimport floewave\n'
                              'def f():\n    from floewave._march import march_coefficients\n')
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    assert private_floewave_imports("pkg") == [
        "pkg.a imports floewave._jit", "pkg.a imports floewave._kernels",
        "pkg.a imports floewave._march.march_coefficients"]


@pytest.mark.parametrize("package", PACKAGES)
def test_every_module_says_its_job(package):
    missing = [name for name, path in modules(package).items()
               if not ast.get_docstring(ast.parse(path.read_text()))]
    assert not missing, f"modules without a docstring: {missing}"


if __name__ == "__main__":
    for package in PACKAGES:
        edges = graph((package,))
        n_edges = sum(len(v) for v in edges.values())
        print(f"{package}/: {len(edges)} modules, {n_edges} import edges")
        for component in cycles(edges):
            print(f"  circle of {len(component)}: {' '.join(component)}")
    parts = package_graph("sweep")
    print("sweep's parts:", "; ".join(f"{k} -> {', '.join(sorted(v))}"
                                      for k, v in sorted(parts.items()) if v))
    for component in cycles(parts):
        print(f"  circle of parts: {' '.join(component)}")
    for line in private_imports(("sweep", "herman2019")):
        print(f"  private: {line}")
    for line in private_floewave_imports("sweep"):
        print(f"  private floewave: {line}")
    for name, n in long_modules(PACKAGES):
        print(f"  {n:5d} lines: {name}")


@pytest.mark.slow
def test_following_cfg_through_the_model_returns_to_few_files():
    """Issue 44: a reader following ``cfg`` from :func:`floewave.run_point` through its calls
    (tests/cfg_walk.py) came back to a file already left 29 times by this walk before the
    renovation's last step (25 by the review's own reading); 21 since. A new hop fails."""
    from tests.cfg_walk import returns, walk
    files = walk()
    assert returns(files) <= 21, files
    assert files[0] == "floewave/model.py"
