"""Dispersion relations (eq. 6), group velocity (eq. 7) and the confined-ice rate (eq. 24)."""
from __future__ import annotations

import math
from typing import Protocol

import numpy as np

from .errors import DispersionError


class ModelConfig(Protocol):
    """The fields of a :class:`floewave.ModelConfig` these formulas read (a structural
    type: this module imports no floewave module but errors, and config imports it)."""

    T: float
    h: float
    h_i: float
    rho_i: float
    rho_w: float
    E: float
    nu: float
    C_sd: float
    dispersion: str

    @property
    def omega(self) -> float: ...

G = 9.81  # [m s^-2] acceleration due to gravity (docs/model.md §2)

__all__ = ["G", "coefficients", "dispersion_residual", "omega_of_k", "group_velocity",
           "solve_dispersion", "solve_dispersion_omega", "alpha_confined",
           "confined_rate_factor", "DispersionError"]


def coefficients(cfg: ModelConfig) -> tuple[float, float]:
    """(beta1 [m], beta2 [m^5 s^-2]) of eq. 6 for ``cfg.dispersion``.

    beta1 = rho_i h_i / rho_w, beta2 = E h_i^3 / (12 rho_w (1 - nu^2)); ``ml`` sets
    beta2 = 0, ``ow`` sets both to 0.
    """
    b1 = cfg.rho_i * cfg.h_i / cfg.rho_w
    b2 = cfg.E * cfg.h_i**3 / (12.0 * cfg.rho_w * (1.0 - cfg.nu**2))
    if cfg.dispersion == "ow":
        return 0.0, 0.0
    if cfg.dispersion == "ml":
        return b1, 0.0
    return b1, b2


def omega_of_k(k: float, h: float, b1: float, b2: float) -> float:
    """omega(k) from eq. 6: omega^2 = (g + b2 k^4) k tanh(kh) / (1 + b1 k tanh(kh))."""
    kt = k * math.tanh(k * h)
    return math.sqrt((G + b2 * k**4) * kt / (1.0 + b1 * kt))


def dispersion_residual(k: float, omega: float, h: float, b1: float, b2: float) -> float:
    """Relative residual of eq. 6: [omega^2 (1 + b1 k tanh kh) - (g + b2 k^4) k tanh kh] / rhs."""
    kt = k * math.tanh(k * h)
    rhs = (G + b2 * k**4) * kt
    return (omega**2 * (1.0 + b1 * kt) - rhs) / rhs


def group_velocity(k: float, omega: float, h: float, b1: float, b2: float) -> float:
    """Eq. 7: c_g = omega/(2k) [(1 - b1 w^2/(g + b2 k^4)) (1 + 2kh/sinh 2kh)
    + 4 b2 k^4/(g + b2 k^4)]."""
    gk = G + b2 * k**4
    kh2 = 2.0 * k * h
    shallow = 1.0 + (kh2 / math.sinh(kh2) if kh2 < 700.0 else 0.0)
    return omega / (2.0 * k) * ((1.0 - b1 * omega**2 / gk) * shallow + 4.0 * b2 * k**4 / gk)


def _solve(omega: float, h: float, b1: float, b2: float, what: str) -> tuple[float, float]:
    if b2 == 0.0 and b1 > 0.0 and omega**2 * b1 >= G:
        raise DispersionError(
            f"{what}: omega^2 = {omega**2:.6g} s^-2 is at or above the mass-loading cutoff"
            f" g / beta1 = g rho_w / (rho_i h_i) = {G / b1:.6g} s^-2: eq. 6 has no root with"
            " positive group velocity")

    def f(k: float) -> float:
        kt = k * math.tanh(k * h)
        return omega**2 * (1.0 + b1 * kt) - (G + b2 * k**4) * kt

    # f(0+) > 0 (omega^2 > 0). Upper bracket: grow until f < 0. For ml, k -> inf gives
    # f -> kt (omega^2 b1 - g) < 0 below the cutoff; for ow/ep, -(g + b2 k^4) k wins.
    lo = 1e-12
    hi = max(omega**2 / G, omega / math.sqrt(G * h)) * 2.0 + 1e-6
    while f(hi) > 0.0:
        hi *= 2.0
        if hi > 1e12:
            raise DispersionError(f"{what}: no root of eq. 6 found below k = 1e12 m^-1")
    from scipy.optimize import brentq  # lazy: 0.3 s; `sweep status` solves no eq. 6

    k = brentq(f, lo, hi, xtol=1e-300, rtol=1e-15, maxiter=500)
    cg = group_velocity(k, omega, h, b1, b2)
    if not (cg > 0.0 and math.isfinite(cg)):
        raise DispersionError(f"{what}: group velocity c_g = {cg!r} is not positive")
    return k, cg


def solve_dispersion(cfg: ModelConfig) -> tuple[float, float]:
    """Wavenumber k [m^-1] and group velocity c_g [m s^-1] for ``cfg`` (eqs. 6, 7).

    Brent's method on the bracketed unique positive root, to ~1e-15 relative in k.
    Raises :class:`DispersionError` (an :class:`InvalidPointError`) when ``ml`` is at or
    beyond its cutoff omega^2 >= g rho_w / (rho_i h_i).
    """
    b1, b2 = coefficients(cfg)
    what = f"dispersion {cfg.dispersion!r} at T = {cfg.T!r} s"
    return _solve(cfg.omega, cfg.h, b1, b2, what)


def solve_dispersion_omega(cfg: ModelConfig, omega: float) -> tuple[float, float]:
    """k [m^-1] and c_g [m s^-1] at the angular frequency ``omega`` [rad s^-1] for
    ``cfg``'s dispersion, ice and depth (``cfg.T`` is not read): :func:`solve_dispersion`
    without a configuration per frequency (a curve of many frequencies)."""
    b1, b2 = coefficients(cfg)
    what = f"dispersion {cfg.dispersion!r} at omega = {omega!r} rad/s"
    return _solve(omega, cfg.h, b1, b2, what)


def confined_rate_factor(omega, k, c_g, h):
    """omega^3 / (c_g tanh^3 kh) [m^-1 s^-2], the dispersion-dependent factor of eq. 24
    (eq. 26; the paper's Fig. 1b). Floats or numpy arrays."""
    return omega**3 / (c_g * np.tanh(k * h) ** 3)


def alpha_confined(cfg: ModelConfig, k: float | None = None,
                   c_g: float | None = None) -> float:
    """Eq. 24: alpha_c = 4 C_sd omega^3 / (3 pi g c_g tanh^3 kh)  [m^-2] (``k``, ``c_g``:
    the solution of eqs. 6-7 if the caller has it, else solved here)."""
    if k is None or c_g is None:
        k, c_g = solve_dispersion(cfg)
    cg = c_g
    return float(4.0 * cfg.C_sd / (3.0 * math.pi * G)
                 * confined_rate_factor(cfg.omega, k, cg, cfg.h))
