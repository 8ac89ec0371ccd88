"""Every output of a model point, declared once: name, kind, unit, long name, dims, W_c rule.

:data:`OUTPUTS` is the one declaration. :class:`floewave.PointResult`'s fields
(:mod:`floewave.results`), ``PROFILE_FIELDS`` / ``SCALAR_FIELDS`` / ``REPLICA_FIELDS``,
the store's model columns, profile datasets and their attributes
(:mod:`sweep.store.schema`), the xarray attributes (:func:`sweep.load_xarray`) and the
tables of docs/output.md are built from it. Adding an output is one :class:`Output` here
plus the code that computes it (and, for a store to keep it, sweep's schema version that
added it: ``sweep.store.schema.ADDED_IN``; a test names what is missing).

Dims (:attr:`Output.dims`): ``()`` a scalar of the point; ``("N_f",)`` per floe;
``("pair",)`` per pair (i, i + 1): N_f - 1 values and a trailing NaN, so every profile has
the length N_f; ``("R",)`` and ``("R", "N_f")`` per replica of the ensemble;
``("iterations",)`` one value per attenuation iteration. Units are written as the store
writes them (``1``: dimensionless, ``m-2``: per square metre).

The collision-zone width is reported by more than one rule (:data:`W_C_RULES`, in the
order figures draw them). ``W_c`` follows the per-window rule (the paper's): a replica's
W_c is the mean over its averaging windows of the window's W_c
(:func:`floewave.results.compact_zones` of that window's mean gaps), the point's the mean
over the ``W_c_n`` replicas with a compact zone, ``compact_zone`` the most common layout
over windows and replicas. ``W_c_gap`` applies the same rule to each replica's gaps
time-averaged over the whole averaging (``gap_mean_replicas``): the mean over the replicas
with a compact zone (:mod:`floewave.collision_stats`).

Ensemble (``replicas`` = R chains, :mod:`floewave.ensemble`): profiles and scalars are the
ensemble's estimates; ``a_stderr`` and every ``*_stderr`` are jackknife standard errors over
the replicas (R = 1: ``a_stderr`` and ``a_end_stderr`` are the iteration standard error and
the other scalar ones are NaN: one trajectory has no error bar for them).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

__all__ = ["Output", "REQUIRED", "OUTPUTS", "W_C_RULES", "LAYOUT_MEANINGS", "output", "profiles", "scalars",
           "replica_outputs", "history", "table_outputs"]

#: :attr:`Output.default` of an output every model point reports (a required field).
REQUIRED = "required"
PER_FLOE, PER_PAIR, PER_REPLICA, PER_REPLICA_FLOE = ("N_f",), ("pair",), ("R",), ("R", "N_f")
HISTORY = ("iterations",)


@dataclass(frozen=True)
class Output:
    """One output of a point.

    name : the :class:`floewave.PointResult` field.
    kind : ``"float"``, ``"int"`` or ``"str"`` (the values' kind; arrays hold floats).
    unit : as the store writes it (``""`` for text).
    long_name : what it is (the store's ``long_name``).
    dims : ``()`` or the array's dims (module docstring).
    default : the value of a point that does not compute it, or :data:`REQUIRED`.
    column : the store's table column (scalars; ``None``: not a model column).
    rule : for a collision-zone width, the rule it follows (:data:`W_C_RULES`).
    """

    name: str
    kind: str
    unit: str
    long_name: str
    dims: tuple[str, ...] = ()
    default: Any = REQUIRED
    column: str | None = ""
    rule: str = ""

    def __post_init__(self) -> None:
        if self.kind not in ("float", "int", "str"):
            raise ValueError(f"output {self.name}: kind {self.kind!r}")
        if self.column == "" and not self.dims:
            object.__setattr__(self, "column", self.name)
        if self.dims:
            object.__setattr__(self, "column", None)


def _se(name: str, unit: str, long_name: str) -> Output:
    return Output(name, "float", unit, long_name, default=math.nan)


_O = Output
#: Every output of a point, in :class:`floewave.PointResult`'s field order (the store's
#: model columns keep this order).
OUTPUTS: tuple[Output, ...] = (
    _O("x_mean", "float", "m", "time-mean floe centre from the ice edge", PER_FLOE),
    _O("a", "float", "m", "wave amplitude at the floe", PER_FLOE),
    _O("a_stderr", "float", "m", "standard error of the amplitude", PER_FLOE),
    _O("S_sd", "float", "W m-2", "skin-drag dissipation (eq. 19)", PER_FLOE),
    _O("gap_mean", "float", "m", "mean gap to the next floe (last value NaN)", PER_PAIR),
    _O("contact_fraction", "float", "1", "fraction of time in contact with the next floe",
       PER_PAIR),
    _O("collisions", "float", "1", "contact onsets with the next floe in the averaging"
       " window", PER_PAIR),
    _O("F_w_mean", "float", "N", "time-mean |wave force|", PER_FLOE),
    _O("F_c_mean", "float", "N", "time-mean |contact force|", PER_FLOE),
    _O("F_d_mean", "float", "N", "time-mean |drag force|", PER_FLOE),
    _O("n_floes", "int", "1", "number of floes N_f"),
    _O("W_c", "float", "m", "collision-zone width: start of the first compact zone (NaN:"
       " none)", rule="per averaging window"),
    _O("compact_zone", "str", "", "layout of the compact zone: edge, inverted, patchy, none"),
    _O("compact_end", "float", "m", "end of the first compact zone"),
    _O("ice_extent", "float", "m", "far end of the ice: last floe's mean centre + L_x/2"),
    _O("alpha_all", "float", "m-2", "slope of 1/a over all floes"),
    _O("alpha_all_resid", "float", "1", "RMS misfit of the 1/a fit over all floes / a0"),
    _O("alpha_edge", "float", "m-2", "slope of 1/a in the collisional zone x < W_c (all"
       " floes without a compact zone; NaN if too short)"),
    _O("alpha_edge_resid", "float", "1", "RMS misfit of the edge fit / a0"),
    _O("alpha_inner", "float", "m-2", "slope of 1/a in the first compact zone (NaN: none or"
       " too short)"),
    _O("alpha_inner_resid", "float", "1", "RMS misfit of the inner fit / a0"),
    _O("alpha_exp", "float", "m-1", "exponential attenuation rate (slope of -ln a)"),
    _O("alpha_exp_resid", "float", "1", "RMS misfit of the exponential fit / a0"),
    _O("alpha_c", "float", "m-2", "confined-ice attenuation rate (eq. 24)"),
    _O("k", "float", "rad m-1", "wavenumber (eq. 6)"),
    _O("c_g", "float", "m s-1", "group velocity (eq. 7)"),
    # the store's status column is sweep's (the model's three statuses and sweep's own)
    _O("status", "str", "", "converged, converged_noisy or not_converged", column=None),
    _O("noise", "float", "1", "residual noise floor (converged_noisy)"),
    _O("iterations", "int", "1", "attenuation iterations done"),
    _O("residual", "float", "1", "final residual max |a_new - a| / a"),
    _O("floe_steps", "int", "1", "floe-steps computed (cost unit)"),
    _O("kernel_mode", "str", "", "kernel variant that ran"),
    _O("a_end", "float", "m", "amplitude at the far end of the sheet"),
    _O("wall_time", "float", "s", "wall time reported by the model",
       column="model_wall_time"),
    _O("residual_history", "float", "1", "residual max |a_new - a| / a per iteration",
       HISTORY, default=()),
    _O("replicas", "int", "1", "floe chains R of the ensemble (1: a single trajectory)",
       default=1),
    _se("W_c_stderr", "m", "standard error of W_c (mean over the W_c_n replicas with a"
        " compact zone; NaN with fewer than 2)"),
    _O("W_c_n", "int", "1", "replicas with a compact zone (-1: stored before schema 3)",
       default=0),
    _se("alpha_all_stderr", "m-2", "jackknife standard error of alpha_all over replicas"
        " (NaN: R = 1)"),
    _se("alpha_edge_stderr", "m-2", "jackknife standard error of alpha_edge"),
    _se("alpha_inner_stderr", "m-2", "jackknife standard error of alpha_inner"),
    _se("alpha_exp_stderr", "m-1", "jackknife standard error of alpha_exp"),
    _se("a_end_stderr", "m", "standard error of a_end"),
    _O("W_c_gap", "float", "m", "W_c of the gaps time-averaged over the whole averaging:"
       " the W_c rule on each replica's gap_mean_replicas, mean over the replicas with a"
       " compact zone (NaN: none)", default=math.nan,
       rule="the gaps averaged over all windows"),
    _se("W_c_gap_stderr", "m", "standard error of W_c_gap (NaN with fewer than 2 replicas"
        " with a compact zone)"),
    _se("contact_fraction_mean", "1", "fraction of time steps in contact, mean over the"
        " N_f - 1 pairs and the replicas (NaN: confined)"),
    _se("contact_fraction_mean_stderr", "1", "jackknife standard error of"
        " contact_fraction_mean over replicas (NaN: R = 1)"),
    _se("collision_rate", "1", "contact onsets per pair per wave period: mean over the"
        " pairs and the replicas of onsets in an averaging window / nT (NaN: confined)"),
    _se("collision_rate_stderr", "1", "jackknife standard error of collision_rate"),
    _se("dissipation_per_collision", "J", "skin-drag dissipation per collision: sum over"
        " floes of -S_sd L_x L_y [W] / sum over pairs of onsets per second, replica means"
        " (NaN: no collision, confined)"),
    _se("dissipation_per_collision_stderr", "J", "jackknife standard error of"
        " dissipation_per_collision"),
    _O("W_c_replicas", "float", "m", "W_c of each replica (NaN: no compact zone)",
       PER_REPLICA, default=()),
    _O("compact_end_replicas", "float", "m", "end of each replica's first compact zone",
       PER_REPLICA, default=()),
    _O("x_mean_replicas", "float", "m", "time-mean floe centre per replica",
       PER_REPLICA_FLOE, default=()),
    _O("gap_mean_replicas", "float", "m", "mean gap to the next floe per replica (last"
       " NaN)", PER_REPLICA_FLOE, default=()),
    _O("S_sd_replicas", "float", "W m-2", "skin-drag dissipation per replica",
       PER_REPLICA_FLOE, default=()),
)
_BY_NAME = {o.name: o for o in OUTPUTS}

#: The collision-zone widths, one per rule, in the order figures draw them (the first is
#: the paper's: the dot, its error bar and the compact-ice curve start there).
W_C_RULES: tuple[Output, ...] = tuple(o for o in OUTPUTS if o.rule)

#: The values of ``compact_zone``, the layout of a point's compact ice
#: (:func:`floewave.results.compact_zones`), with what each means, in order of precedence
#: (a tie between layouts over windows and replicas goes to the earlier one).
LAYOUT_MEANINGS: dict[str, str] = {
    "edge": "the paper's: collisional ice at the ice edge, then one compact zone from W_c to"
            " the far end",
    "compact": "compact from the first pair to the far end: no collisional zone (W_c = 0)",
    "inverted": "compact from the ice edge, collisional further in, to the far end",
    "patchy": "any other layout with a compact zone: a compact band with collisional ice on"
              " both sides, or several compact zones",
    "none": "no sustained compact zone: the whole ice is collisional (W_c is NaN)",
}


def output(name: str) -> Output:
    """The :class:`Output` called ``name``."""
    return _BY_NAME[name]


def profiles(outputs: tuple[Output, ...] = OUTPUTS) -> tuple[Output, ...]:
    """The per-floe and per-pair profiles (length N_f)."""
    return tuple(o for o in outputs if o.dims in (PER_FLOE, PER_PAIR))


def scalars(outputs: tuple[Output, ...] = OUTPUTS) -> tuple[Output, ...]:
    """The scalar results and diagnostics."""
    return tuple(o for o in outputs if not o.dims)


def replica_outputs(outputs: tuple[Output, ...] = OUTPUTS) -> tuple[Output, ...]:
    """The per-replica results, (R,) or (R, N_f)."""
    return tuple(o for o in outputs if o.dims and o.dims[0] == "R")


def history(outputs: tuple[Output, ...] = OUTPUTS) -> Output:
    """The one per-iteration output (the residual history)."""
    (out,) = (o for o in outputs if o.dims == HISTORY)
    return out


def table_outputs(outputs: tuple[Output, ...] = OUTPUTS) -> tuple[Output, ...]:
    """The scalars a store keeps in its table (those with a :attr:`Output.column`)."""
    return tuple(o for o in scalars(outputs) if o.column)
