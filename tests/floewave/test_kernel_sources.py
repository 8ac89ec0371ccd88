"""The numba cache key holds every kernel file (floewave._jit.KERNEL_SOURCES), in process:
every file with a jitted function, and every private module a kernel file imports (numba
freezes the globals it reads, such as floewave._layout's rows, into the compiled code)."""
from __future__ import annotations

import ast
import shutil
from pathlib import Path

import floewave
from floewave import _jit

PKG = Path(floewave.__file__).resolve().parent


def _imported_private_modules(path: Path) -> set[str]:
    """The ``_*.py`` files of floewave that ``path`` imports with ``from ._x import``."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level == 1 and node.module:
            if node.module.startswith("_"):
                out.add(node.module + ".py")
    return out


def test_every_file_with_a_kernel_is_a_kernel_source():
    jitted = {p.name for p in PKG.glob("*.py") if "njit" in p.read_text()}
    assert jitted, "no jitted file found"
    assert jitted <= set(_jit.KERNEL_SOURCES), sorted(jitted - set(_jit.KERNEL_SOURCES))


def test_every_private_module_a_kernel_file_imports_is_a_kernel_source():
    sources = set(_jit.KERNEL_SOURCES)
    for name in sources:
        assert (PKG / name).is_file(), name
        assert _imported_private_modules(PKG / name) <= sources, name


def test_the_key_changes_with_every_kernel_file(tmp_path, monkeypatch):
    for name in _jit.KERNEL_SOURCES:
        shutil.copy(PKG / name, tmp_path / name)
    monkeypatch.setattr(_jit, "_HERE", str(tmp_path))
    _jit.kernel_fingerprint.cache_clear()
    try:
        base = _jit.kernel_fingerprint()
        for name in _jit.KERNEL_SOURCES:
            path = tmp_path / name
            text = path.read_text()
            path.write_text(text + "\n# changed\n")
            _jit.kernel_fingerprint.cache_clear()
            assert _jit.kernel_fingerprint() != base, name
            path.write_text(text)
        _jit.kernel_fingerprint.cache_clear()
        assert _jit.kernel_fingerprint() == base
    finally:
        monkeypatch.undo()
        _jit.kernel_fingerprint.cache_clear()
