"""sweep: campaigns of floewave points over MPI, one HDF5 store, resume and provenance.

- :func:`load_campaign` — read and validate a campaign TOML (``[base]``, ``[sweep]``,
  ``[run]``) into a :class:`Campaign`
- :func:`point_hash` — a point's identity (SHA-256 of canonical config JSON)
- :func:`run_campaign` — run or resume a campaign (in-process, or master/worker MPI)
- :func:`load`, :func:`load_xarray`, :func:`load_profile` — read a store
- :func:`validate` — check a store against ``results_schema/``
- :func:`collision_stats`, :func:`alpha_omega` — collision-zone statistics and alpha(omega)
  power laws across a campaign (:mod:`sweep.stats`)

The command line is ``sweep`` (:mod:`sweep.cli`); user docs are in ``sweep/README.md``.
"""
from .analysis import load, load_profile, load_xarray
from .config import Campaign, Point, RunOptions, load_campaign, parse_campaign
from .errors import (
                     CampaignMismatchError,
                     ConfigError,
                     Interrupted,
                     LaunchError,
                     SchemaVersionError,
                     StoreError,
                     StoreLockedError,
                     SweepError,
                     WorkerError,
)
from .executor import run_campaign
from .identity import canonical_json, point_hash, short_hash
from .schema import SCHEMA_VERSION, validate
from .stats import alpha_omega, collision_stats, derived

__all__ = ["load_campaign", "parse_campaign", "Campaign", "Point", "RunOptions",
           "point_hash", "short_hash", "canonical_json", "run_campaign", "load",
           "load_xarray", "load_profile", "validate", "collision_stats", "alpha_omega",
           "derived", "SCHEMA_VERSION", "SweepError",
           "ConfigError", "StoreError", "StoreLockedError", "SchemaVersionError",
           "CampaignMismatchError", "LaunchError", "WorkerError", "Interrupted"]
