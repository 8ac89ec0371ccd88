"""sweep: campaigns of floewave points over MPI, one HDF5 store, resume and provenance.

- :func:`load_campaign` — read and validate a campaign TOML (``[base]``, ``[sweep]``,
  ``[run]``) into a :class:`Campaign`
- :func:`point_hash` — a point's identity (SHA-256 of canonical config JSON)
- :func:`run_campaign` — run or resume a campaign (in-process, or master/worker MPI)
- :func:`load`, :func:`load_xarray`, :func:`load_profile` — read a store
- :func:`validate` — check a store against ``results_schema/``
- :func:`collision_stats`, :func:`alpha_omega` — collision-zone statistics and alpha(omega)
  power laws across a campaign (:mod:`sweep.analysis.stats`)

The command line is ``sweep`` (:mod:`sweep.cli`); user docs are in ``sweep/README.md``.
"""
import importlib
from typing import Any

from sweep.errors import (
                     CampaignMismatchError,
                     ConfigError,
                     Interrupted,
                     LaunchError,
                     PointNotFoundError,
                     SchemaVersionError,
                     StoreCorruptedError,
                     StoreError,
                     StoreLockedError,
                     SweepError,
                     WorkerError,
)

#: Imported on first use (``import sweep`` stays light, so the ``sweep`` command can
#: catch stop signals from its first instants): name -> module.
_LAZY = {
    "load": "analysis.load", "load_profile": "analysis.load", "load_profiles": "analysis.load",
    "load_xarray": "analysis.load",
    "Campaign": "config", "Point": "config", "RunOptions": "config",
    "load_campaign": "config", "parse_campaign": "config",
    "run_campaign": "run.launch",
    "canonical_json": "identity", "point_hash": "identity", "short_hash": "identity",
    "SCHEMA_VERSION": "store.schema", "validate": "store.validate",
    "alpha_omega": "analysis.stats", "collision_stats": "analysis.stats",
    "derived": "analysis.stats",
}
#: Subpackages and modules reachable as attributes of ``sweep`` (imported on first use).
_MODULES = {"analysis", "arguments", "cli", "config", "errors", "identity",
            "protocol", "provenance", "report", "run", "store", "system", "testing"}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    elif name in _MODULES:
        value = importlib.import_module(f".{name}", __name__)
    else:
        raise AttributeError(f"module 'sweep' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY) | _MODULES)


__all__ = ["load_campaign", "parse_campaign", "Campaign", "Point", "RunOptions",
           "point_hash", "short_hash", "canonical_json", "run_campaign", "load",
           "load_xarray", "load_profile", "load_profiles", "validate", "collision_stats",
           "alpha_omega",
           "derived", "SCHEMA_VERSION", "SweepError",
           "ConfigError", "StoreError", "StoreLockedError", "StoreCorruptedError",
           "SchemaVersionError", "CampaignMismatchError", "LaunchError", "WorkerError",
           "Interrupted", "PointNotFoundError"]
