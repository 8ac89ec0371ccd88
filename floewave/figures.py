"""Analytic figures: the paper's Fig. 1 (group velocity and the confined-ice rate factor).

Herman, Cheng & Shen (2019), §3: with confined ice the attenuation rate of eq. 24 is
``alpha_c = 4 C_sd / (3 pi g) * R`` with the dispersion-dependent factor

    R(omega) = omega^3 / (c_g tanh^3 kh)                                   (eq. 24, 26)

Fig. 1 shows c_g (panel a) and R (panel b) versus f = omega / (2 pi) for thin laboratory ice
and for field-scale ice, for the three dispersion relations of eq. 6 (``ow`` open water,
``ml`` mass loading, ``ep`` elastic plate). In the high-frequency tail R ~ c omega^m with
m = 4 for ``ow`` in deep water (eq. 27), m > 4 for ``ml`` (eq. 28) and m ~ 2-2.5 for
``ep`` (the paper's fits: m = 1.994 lab, 2.397 field).

Parameter sets
--------------
``LAB``: the LS-WICE-like defaults of :class:`ModelConfig` (h = 2.5 m, h_i = 0.03 m,
E = 3e7 Pa, rho_i = 910, rho_w = 1000, nu = 0.3). The paper does not give the series-3000
ice properties, so these are documented assumptions (docs/model.md §7) and the lab exponents
need not match the paper's. ``FIELD``: the paper's field example (Fig. 1 caption):
h = 1000 m, rho_w = 1025, rho_i = 910, E = 6e9 Pa, h_i = 1.5 m, nu = 0.3 (docs/model.md §7).

Frequency range and fit rule (one rule for every curve)
-------------------------------------------------------
Both cases are drawn on one frequency axis, ``F_RANGE`` = 0.02-2 Hz, as in the paper
(whose caption notes that the lab and field open-water curves overlap for f > 0.5 Hz, so
the field curves extend beyond 0.5 Hz). The LS-WICE wave periods T = 1.1-2.0 s
(f = 0.5-0.91 Hz, docs/model.md §7) are shaded.

The exponent m of R = c omega^m is a least-squares line in (log omega, log R) over the
top ``TAIL_OCTAVES`` = 2 octaves of the curve's admissible range, i.e. over
``[f_top / 4, f_top]`` (:func:`tail_range`), with f_top = ``F_RANGE[1]`` = 2 Hz, except for
``ml``, whose admissible range ends at the mass-loading cutoff
omega^2 = g rho_w / (rho_i h_i) (c_g -> 0 and R -> infinity there), where
f_top = min(2 Hz, ``ML_CUTOFF_FRACTION`` x f_cutoff) with ML_CUTOFF_FRACTION = 0.9.
So ow/ep (lab and field) and lab ml are fitted over 0.5-2 Hz; field ml (cutoff 0.432 Hz)
over 0.097-0.389 Hz. With this rule the field ``ep`` exponent is 2.392, the paper's 2.397
to within 0.005 (any tail inside 0.5-3 Hz gives 2.37-2.42: the field ``ep`` curve is close
to the flexural deep-water limit omega^2 = beta2 k^5, i.e. m = 2.4). ``ml`` exponents grow
without bound towards the cutoff, so they depend on the cutoff fraction by construction.
"""
from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .config import G, ModelConfig
from .dispersion import DispersionError, confined_rate_factor, solve_dispersion_omega
from .results import power_law

__all__ = ["LAB", "FIELD", "F_RANGE", "LSWICE_F", "TAIL_OCTAVES", "ML_CUTOFF_FRACTION",
           "DISPERSIONS", "Curve", "dispersion_curves", "mass_loading_cutoff", "tail_range",
           "fit_power_law", "tail_exponent", "tail_exponents", "figure1", "FIG1_NAME",
           "figure4", "FIG4_NAME"]

#: Thin laboratory ice: the LS-WICE-like ModelConfig defaults (assumptions, docs/model.md §7).
LAB = ModelConfig()
#: Field-scale ice of the paper's Fig. 1 caption (nu = 0.3 as in docs/model.md §7).
FIELD = ModelConfig(h=1000.0, rho_w=1025.0, rho_i=910.0, E=6.0e9, h_i=1.5, nu=0.3)

#: Frequency axis of Fig. 1 [Hz] (both cases), log-spaced.
F_RANGE = (0.02, 2.0)
#: LS-WICE wave frequencies [Hz]: periods T = 2.0 s to 1.1 s (docs/model.md §7).
LSWICE_F = (1.0 / 2.0, 1.0 / 1.1)
#: The fit tail is [f_top / 2**TAIL_OCTAVES, f_top].
TAIL_OCTAVES = 2
#: For ``ml`` the tail ends at this fraction of the mass-loading cutoff frequency.
ML_CUTOFF_FRACTION = 0.9
DISPERSIONS = ("ow", "ml", "ep")
FIG1_NAME = "fig1_dispersion.png"

_PARAMS = ("h", "h_i", "rho_i", "rho_w", "E", "nu")


@dataclass(frozen=True)
class Curve:
    """c_g and R on a frequency grid for one dispersion relation (NaN where inadmissible)."""

    dispersion: str
    f: np.ndarray  # [Hz]
    omega: np.ndarray  # [rad s^-1]
    k: np.ndarray  # [m^-1]
    c_g: np.ndarray  # [m s^-1]
    R: np.ndarray  # omega^3 / (c_g tanh^3 kh) [m^-1 s^-2]


def _as_config(params: ModelConfig | Mapping[str, Any]) -> ModelConfig:
    """A ModelConfig from a ModelConfig or from a mapping / object with the six ice-water
    fields h, h_i, rho_i, rho_w, E, nu (other ModelConfig fields keep their defaults)."""
    if isinstance(params, ModelConfig):
        return params
    if isinstance(params, Mapping):
        return ModelConfig(**{p: params[p] for p in _PARAMS if p in params})
    return ModelConfig(**{p: getattr(params, p) for p in _PARAMS if hasattr(params, p)})


def dispersion_curves(params: ModelConfig | Mapping[str, Any], f: Iterable[float],
                      dispersions: Iterable[str] = DISPERSIONS) -> dict[str, Curve]:
    """k, c_g (eqs. 6, 7) and R = omega^3 / (c_g tanh^3 kh) at frequencies ``f`` [Hz].

    ``params`` supplies h, h_i, rho_i, rho_w, E, nu (a :class:`ModelConfig`, a mapping or
    any object with those attributes); its ``dispersion`` and ``T`` are ignored. Each
    point is solved with :func:`floewave.dispersion.solve_dispersion_omega` (the k and c_g
    of a configuration with T = 1 / f, bit for bit); where eq. 6 has no admissible root
    (``ml`` at or beyond omega^2 = g rho_w / (rho_i h_i)) k, c_g and R are NaN.
    Returns ``{dispersion: Curve}``.
    """
    cfg = _as_config(params)
    f = np.asarray(list(f) if not isinstance(f, np.ndarray) else f, dtype=float)
    if f.ndim != 1 or not np.all(f > 0) or not np.all(np.isfinite(f)):
        raise ValueError("f must be a 1-d array of finite frequencies > 0 [Hz]")
    out: dict[str, Curve] = {}
    for disp in dispersions:
        base = cfg.replace(dispersion=disp)
        omega = 2.0 * np.pi * f
        k = np.full_like(f, np.nan)
        cg = np.full_like(f, np.nan)
        for i, fi in enumerate(f):
            try:  # omega as ModelConfig.omega computes it from T = 1 / f
                k[i], cg[i] = solve_dispersion_omega(base,
                                                     2.0 * math.pi / (1.0 / float(fi)))
            except DispersionError:
                pass
        with np.errstate(invalid="ignore"):
            R = confined_rate_factor(omega, k, cg, cfg.h)
        out[disp] = Curve(disp, f, omega, k, cg, R)
    return out


def mass_loading_cutoff(params: ModelConfig | Mapping[str, Any]) -> float:
    """Cutoff frequency [Hz] of ``ml``: omega^2 = g rho_w / (rho_i h_i) (paper §3)."""
    cfg = _as_config(params)
    return math.sqrt(G * cfg.rho_w / (cfg.rho_i * cfg.h_i)) / (2.0 * math.pi)


def tail_range(params: ModelConfig | Mapping[str, Any], dispersion: str,
               f_max: float = F_RANGE[1]) -> tuple[float, float]:
    """The documented fit tail [f_top / 2**TAIL_OCTAVES, f_top] in Hz.

    f_top = ``f_max`` (the figure's upper frequency), or for ``ml``
    min(f_max, ML_CUTOFF_FRACTION x mass-loading cutoff).
    """
    f_top = f_max
    if dispersion == "ml":
        f_top = min(f_max, ML_CUTOFF_FRACTION * mass_loading_cutoff(params))
    return f_top / 2.0**TAIL_OCTAVES, f_top


def fit_power_law(omega: np.ndarray, R: np.ndarray, fmin: float,
                  fmax: float) -> tuple[float, float]:
    """Least-squares fit of R = c omega^m in log-log over fmin <= omega/(2 pi) <= fmax [Hz].

    NaN / non-positive R (e.g. ``ml`` beyond its cutoff) are skipped. Returns (m, c) with
    c in the units of R divided by [rad s^-1]^m. Raises ValueError with fewer than 3 points.
    """
    omega = np.asarray(omega, dtype=float)
    R = np.asarray(R, dtype=float)
    f = omega / (2.0 * np.pi)
    eps = 1e-12 * max(abs(fmin), abs(fmax))
    sel = (f >= fmin - eps) & (f <= fmax + eps) & np.isfinite(R) & (R > 0)
    if np.count_nonzero(sel) < 3:
        raise ValueError(f"fit_power_law: fewer than 3 usable points in [{fmin}, {fmax}] Hz")
    m, c, _, _ = power_law(omega[sel], R[sel])
    return m, c


def tail_exponent(params: ModelConfig | Mapping[str, Any], dispersion: str,
                  f_max: float = F_RANGE[1], n: int = 201) -> tuple[float, float, float, float]:
    """(m, c, fmin, fmax): the power-law fit over :func:`tail_range` on ``n`` log-spaced
    frequencies."""
    fmin, fmax = tail_range(params, dispersion, f_max)
    c = dispersion_curves(params, np.geomspace(fmin, fmax, n), (dispersion,))[dispersion]
    m, pref = fit_power_law(c.omega, c.R, fmin, fmax)
    return m, pref, fmin, fmax


def tail_exponents(f_max: float = F_RANGE[1]) -> dict[tuple[str, str], tuple[float, ...]]:
    """{(case, dispersion): (m, c, fmin, fmax)} for case in lab/field, all dispersions."""
    return {(case, d): tail_exponent(p, d, f_max)
            for case, p in (("lab", LAB), ("field", FIELD)) for d in DISPERSIONS}


_STYLE = {  # (case, dispersion) -> colour; paper: ow black, ml red/violet, ep blue/yellow
    ("lab", "ow"): "black", ("field", "ow"): "black",
    ("lab", "ml"): "tab:red", ("field", "ml"): "darkviolet",
    ("lab", "ep"): "tab:blue", ("field", "ep"): "goldenrod",
}
_LS = {"lab": "-", "field": "--"}


def figure1(out_path: str | Path, n: int = 400) -> dict[tuple[str, str], tuple[float, ...]]:
    """Write the paper's Fig. 1 to ``out_path`` (PNG): (a) c_g vs f, (b) R vs f.

    Lab (solid) and field (dashed) ice, ``ow``/``ml``/``ep``; the legend gives each
    curve's fitted tail exponent m (fit rule: module docstring). Returns the fits as
    :func:`tail_exponents`. Needs matplotlib (Agg backend).
    """
    import matplotlib  # lazy: optional (plot extra): its absence is reported

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # lazy: optional (plot extra), 0.8 s

    f = np.geomspace(F_RANGE[0], F_RANGE[1], n)
    fits = tail_exponents(F_RANGE[1])
    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(11.5, 5.0))
    handles = {}
    r_top = 0.0  # upper y limit of (b): ml diverges at its cutoff, so ow/ep set the scale
    for case, params in (("lab", LAB), ("field", FIELD)):
        curves = dispersion_curves(params, f)
        for d in ("ep", "ml", "ow"):  # ow drawn last, on top where the curves coincide
            c = curves[d]
            m, pref, fmin, fmax = fits[(case, d)]
            style = dict(color=_STYLE[(case, d)], ls=_LS[case], lw=1.3 if d == "ow" else 1.9)
            label = f"{case}, {d} (m = {m:.3f}, fit {fmin:.3g}-{fmax:.3g} Hz)"
            (h,) = ax_a.plot(c.f, c.c_g, label=label, **style)
            ax_b.plot(c.f, c.R, **style)
            if d != "ml":
                r_top = max(r_top, float(np.nanmax(c.R)))
            # the fitted power law c omega^m over its tail, as a translucent band
            ft = np.geomspace(fmin, fmax, 20)
            ax_b.plot(ft, pref * (2 * np.pi * ft) ** m, color=_STYLE[(case, d)], lw=5,
                      alpha=0.18, solid_capstyle="butt")
            handles[(case, d)] = h
        fc = mass_loading_cutoff(params)
        if F_RANGE[0] < fc < F_RANGE[1]:
            for ax in (ax_a, ax_b):
                ax.axvline(fc, color=_STYLE[(case, "ml")], ls=":", lw=1)
    for ax, tag in ((ax_a, "(a)"), (ax_b, "(b)")):
        ax.axvspan(*LSWICE_F, color="tab:green", alpha=0.12, lw=0)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(*F_RANGE)
        ax.set_xlabel("wave frequency f = ω / 2π [Hz]")
        ax.grid(True, which="major", alpha=0.3)
        ax.text(0.02, 0.97, tag, transform=ax.transAxes, va="top", fontweight="bold")
    ax_a.set_ylabel("group velocity $c_g$ [m s$^{-1}$]")
    ax_b.set_ylabel(r"$\omega^3 / (c_g \tanh^3 kh)$ [m$^{-1}$ s$^{-2}$]")
    ax_a.set_ylim(0.1, None)
    ax_b.set_ylim(None, 10.0 * r_top)
    ax_b.text(0.98, 0.03, "shaded bands: power-law fits $R = c\\,\\omega^m$ (top 2 octaves);\n"
              "dotted: ml cutoffs; green: LS-WICE f range",
              transform=ax_b.transAxes, ha="right", va="bottom", fontsize=8)
    order = [(case, d) for case in ("lab", "field") for d in DISPERSIONS]
    fig.legend(handles=[handles[key] for key in order], loc="lower center", ncol=2,
               fontsize=9, frameon=False)
    fig.suptitle("Herman et al. (2019) Fig. 1: lab ice (solid: h = 2.5 m, h$_i$ = 0.03 m, "
                 "E = 3e7 Pa) and field ice (dashed: h = 1000 m, h$_i$ = 1.5 m, E = 6e9 Pa)",
                 fontsize=10)
    fig.tight_layout(rect=(0, 0.15, 1, 1))
    fig.savefig(out_path, dpi=130)
    plt.close(fig)
    return fits


FIG4_NAME = "fig4_trace.png"


def figure4(trace: Any, cfg: ModelConfig, out_path: str | Path) -> Path:
    """The paper's Fig. 4 from a :class:`floewave.trace.Trace`: |S_sd| versus t/T, one
    panel per traced floe (nearest the ice edge on top).

    Ticks under each curve mark the samples with a floe-floe contact (F_c != 0), so a
    reader can check the paper's description: regular spikes after each collision near the
    edge, low periodic S_sd far from it, erratic in between. Needs matplotlib.
    """
    import matplotlib  # lazy: optional (plot extra): its absence is reported

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # lazy: optional (plot extra), 0.8 s

    n = len(trace.floes)
    fig, axes = plt.subplots(n, 1, figsize=(8.0, 1.9 * n + 0.9), sharex=True, squeeze=False)
    tt = (trace.t - trace.t[0]) / trace.T
    for j, ax in enumerate(axes[:, 0]):
        s = np.abs(trace.S_sd[:, j])
        ax.plot(tt, s, color="k", lw=0.8)
        contact = trace.F_c[:, j] != 0.0
        top = float(np.max(s)) if s.size else 1.0
        ax.plot(tt[contact], np.full(int(contact.sum()), -0.04 * top), "|", color="tab:red",
                ms=5, mew=0.8)
        ax.set_ylim(-0.08 * top, 1.08 * top)
        ax.set_ylabel("|S$_{sd}$| [W m$^{-2}$]")
        ax.text(0.01, 0.93, f"({chr(97 + j)}) floe {int(trace.floes[j]) + 1},"
                f" x = {trace.distance[j]:.1f} m", transform=ax.transAxes, va="top",
                fontsize=9)
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("time t / T from the start of the record [-]")
    fig.suptitle(f"Fig. 4: instantaneous skin-drag dissipation, L_x = {cfg.L_x:g} m, T ="
                 f" {cfg.T:g} s, a0 = {cfg.a0:g} m, C_sd = {cfg.C_sd:g}, eps = {cfg.eps:g},"
                 f" {cfg.dispersion}\n(red ticks: in contact with a neighbour; a(x) fixed"
                 " at the converged profile)", fontsize=9)
    fig.tight_layout()
    fig.savefig(out_path, dpi=130)
    plt.close(fig)
    return Path(out_path)
