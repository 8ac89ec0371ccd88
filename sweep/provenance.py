"""Provenance: versions of everything that ran a point, the git state and the host."""
from __future__ import annotations

import functools
import os
import platform
import socket
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy

import floewave

__all__ = ["environment", "git_state", "host"]


def host() -> str:
    """The host name."""
    return socket.gethostname()


@functools.lru_cache(maxsize=1)
def git_state() -> tuple[str, bool | None]:
    """(commit, dirty) of the checkout that holds the ``floewave`` package.

    ``("unknown", None)`` outside a git checkout (an installed wheel). Dirty means tracked
    files differ from the commit.
    """
    root = Path(floewave.__file__).resolve().parent.parent
    try:
        commit = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"],
                                capture_output=True, text=True, timeout=10, check=True)
        status = subprocess.run(["git", "-C", str(root), "status", "--porcelain",
                                 "--untracked-files=no"], capture_output=True, text=True,
                                timeout=10, check=True)
    except (OSError, subprocess.SubprocessError):
        return "unknown", None
    return commit.stdout.strip(), bool(status.stdout.strip())


def _version(module: str) -> str:
    try:
        mod = __import__(module)
    except ImportError:
        return "not installed"
    return str(getattr(mod, "__version__", "unknown"))


def environment(*, with_git: bool = True, with_mpi: bool | None = None) -> dict[str, Any]:
    """Versions of Python, numpy, numba, h5py, floewave, sweep, mpi4py and MPI, host, pid.

    Parameters
    ----------
    with_git : include ``git_commit`` / ``git_dirty`` (runs ``git`` once per process).
    with_mpi : include the MPI library version; default: only if mpi4py is already
        imported (so asking does not initialise MPI).
    """
    env: dict[str, Any] = {
        "sweep_version": floewave.__version__,
        "floewave_version": floewave.__version__,
        "model_version": floewave.MODEL_VERSION,
        "python": platform.python_version(),
        "numpy": numpy.__version__,
        "numba": _version("numba"),
        "h5py": _version("h5py"),
        "host": host(),
        "pid": os.getpid(),
    }
    if with_git:
        commit, dirty = git_state()
        env["git_commit"] = commit
        env["git_dirty"] = "unknown" if dirty is None else dirty
    if with_mpi is None:
        with_mpi = "mpi4py.MPI" in sys.modules
    env["mpi4py"] = _version("mpi4py")
    if with_mpi:
        from mpi4py import MPI  # lazy: initialises MPI: asked only once imported

        env["mpi_library"] = MPI.Get_library_version().splitlines()[0].strip()
    else:
        env["mpi_library"] = "not used"
    return env
