"""Follow a point's configuration through the model, as a reader of the code would.

:func:`walk` runs :func:`floewave.run_point` on a small configuration and records, in call
order, each Python function of the packages that is handed that ``cfg`` (as an argument, or
as ``self.cfg``; not the configuration's own methods and properties, which read its
fields) the first time it is called: a reader who follows ``cfg`` from
``run_point`` opens each such function once and comes back to its caller when it returns.
The files visited, consecutive visits of one file merged, are the walk's *stays*; a stay in
a file the walk had already left is a *return*. (Issue 44 counted 40 stays in 15 files and
25 returns before the renovation.) Functions compiled by numba are not Python frames and
are not followed; a function called again is not reopened, nor what it calls.

Run as a script to print the walk::

    python -m tests.cfg_walk
"""
from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("floewave", "sweep", "herman2019")


def small_config():
    """A quick point with a compact zone's worth of floes and the default protocol."""
    from floewave import ModelConfig
    return dataclasses.replace(ModelConfig(), L_x=3.0, n0=2, nT=1, max_iterations=3,
                               replicas=2)


def _ours(path: str) -> str | None:
    p = Path(path).resolve()
    try:
        rel = p.relative_to(ROOT)
    except ValueError:
        return None
    return str(rel) if rel.parts and rel.parts[0] in PACKAGES else None


def _holds(frame, cfg) -> bool:
    """Is ``cfg`` handed to this frame's function (but as ``self``: the configuration's own
    methods and properties are reading its fields, not following it)?"""
    if frame.f_locals.get("self") is cfg:
        return False
    for value in frame.f_locals.values():
        if value is cfg or getattr(value, "cfg", None) is cfg:
            return True
    return False


def walk(cfg=None) -> list[str]:
    """The files of the walk, in order, one entry per stay (see the module docstring)."""
    import floewave
    cfg = small_config() if cfg is None else cfg
    seen: set = set()
    files: list[str] = []
    calls: list[str] = []     # every function followed, in order (for the script)
    stack: list = []          # (frame, followed) of the open functions that hold cfg

    def visit(name: str) -> None:
        if not files or files[-1] != name:
            files.append(name)

    def profile(frame, event, arg):
        if event == "call":
            name = _ours(frame.f_code.co_filename)
            if name is None or not _holds(frame, cfg):
                return
            followed = (not stack or stack[-1][1]) and frame.f_code not in seen
            seen.add(frame.f_code)
            stack.append((frame, followed))
            if followed:
                visit(name)
                calls.append(f"{name}:{frame.f_code.co_name}")
        elif event == "return" and stack and stack[-1][0] is frame:
            _, followed = stack.pop()
            if followed and stack:
                visit(_ours(stack[-1][0].f_code.co_filename))

    sys.setprofile(profile)
    try:
        floewave.run_point(cfg)
    finally:
        sys.setprofile(None)
    walk.calls = calls
    return files


def returns(files: list[str]) -> int:
    """How many stays are in a file the walk had already left."""
    return sum(1 for i, f in enumerate(files) if f in files[:i])


def main() -> None:
    files = walk()
    for i, f in enumerate(files):
        mark = "  (return)" if f in files[:i] else ""
        print(f"{i + 1:3d} {f}{mark}")
    print("functions followed:", ", ".join(walk.calls))
    print(f"{len(files)} stays in {len(set(files))} files, {returns(files)} returns "
          f"to a file already left")


if __name__ == "__main__":
    main()
