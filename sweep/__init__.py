"""sweep: campaigns of floewave points over MPI, one HDF5 store, resume and provenance.

- :func:`load_campaign` — read and validate a campaign TOML (``[base]``, ``[sweep]``,
  ``[run]``) into a :class:`Campaign`
- :func:`point_hash` — a point's identity (SHA-256 of canonical config JSON)
- :func:`run_campaign` — run or resume a campaign (in-process, or master/worker MPI)
- :func:`load`, :func:`load_xarray`, :func:`load_profile` — read a store
- :func:`validate` — check a store against ``results_schema/``
- :func:`collision_stats`, :func:`alpha_omega` — collision-zone statistics and alpha(omega)
  power laws across a campaign (:mod:`sweep.stats`)
- :mod:`sweep.papercheck` — the paper's qualitative claims checked on the stores of the
  shipped paper campaigns (``sweep paper-check``)

The command line is ``sweep`` (:mod:`sweep.cli`); user docs are in ``sweep/README.md``.
"""
import importlib
from typing import Any

from .errors import (
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
    "load": "analysis", "load_profile": "analysis", "load_profiles": "analysis",
    "load_xarray": "analysis",
    "Campaign": "config", "Point": "config", "RunOptions": "config",
    "load_campaign": "config", "parse_campaign": "config",
    "run_campaign": "executor",
    "canonical_json": "identity", "point_hash": "identity", "short_hash": "identity",
    "SCHEMA_VERSION": "schema", "validate": "schema",
    "alpha_omega": "stats", "collision_stats": "stats", "derived": "stats",
}
_MODULES = {"analysis", "cli", "config", "errors", "executor", "figures", "identity",
            "journal", "lock", "merge", "papercheck", "plan", "progress", "provenance",
            "reader", "record", "schema", "stats", "store", "testing", "writer",
            "campaign_check", "master", "signals", "transport", "worker", "guard",
            "verify"}


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
