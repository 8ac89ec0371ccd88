"""Detecting and checking an MPI launch: launcher variables, the world, the Slurm size check.

Light on purpose (mpi4py is imported only under a launcher): the CLI reads
:data:`LAUNCHER_VARS` before anything heavy is imported.
"""
from __future__ import annotations

import os
from typing import Any

from sweep.errors import LaunchError

__all__ = ["LAUNCHER_VARS", "launched", "mpi_world", "check_launch"]

#: Variables an MPI launcher sets.
LAUNCHER_VARS = ("PMI_RANK", "PMI_SIZE", "PMIX_RANK", "OMPI_COMM_WORLD_SIZE",
                 "MPI_LOCALNRANKS", "HYDRA_CONTROL_FD", "PMI_FD")


def launched() -> bool:
    """Whether this process was started by an MPI launcher (mpiexec, srun)."""
    return any(v in os.environ for v in LAUNCHER_VARS)


def mpi_world() -> Any:
    """``MPI.COMM_WORLD`` when started by an MPI launcher (mpiexec/srun), else ``None``.

    Without a launcher mpi4py is not even imported, so plain ``python`` runs work on
    machines without MPI.
    """
    if not launched():
        return None
    try:
        from mpi4py import MPI  # lazy: initialises MPI; plain python runs use none
    except ImportError as exc:
        raise LaunchError(f"started by an MPI launcher but mpi4py cannot be imported: {exc};"
                          " pip install 'floewave[mpi]'") from None
    return MPI.COMM_WORLD


def check_launch(size: int, environ: dict[str, str] | None = None) -> None:
    """Refuse an MPI size that differs from ``SLURM_NTASKS`` (the N-singletons launch)."""
    env = os.environ if environ is None else environ
    ntasks = env.get("SLURM_NTASKS")
    if ntasks and ntasks.isdigit() and int(ntasks) != size:
        raise LaunchError(
            f"MPI size is {size} but SLURM_NTASKS={ntasks}: the ranks did not join one MPI"
            " job (N singletons: mpi4py built against another MPI than the launcher's, or"
            " 'sweep run' started without srun/mpiexec); fix the launch, or pass"
            " --ignore-slurm-ntasks if this is intended")
