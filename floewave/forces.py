"""Floe forces of eq. 8 as small formulas (docs/model.md §3); the kernels use their coefficients.

Each function states its equation. This module imports no kernel:
:func:`floewave._kernels.kernel_params` collects the coefficients the numba time loop
needs from these formulas.
"""
from __future__ import annotations

import math

import numpy as np

from .config import ModelConfig

__all__ = ["froude_krylov_coefficient", "wave_force", "orbital_velocity_amplitude",
           "effective_modulus", "restitution_beta", "cell_offsets",
           "slope_force"]


def froude_krylov_coefficient(cfg: ModelConfig, k: float) -> float:
    """c_wave [N m^-1] with F_w,i = c_wave a_i sin(k x_i - omega t).

    Dynamic pressure p_d = rho_w (a omega^2 / k) cosh k(z+h) / sinh kh cos(theta)
    integrated over the two submerged end faces (depth 0..d):
    c_wave = rho_w L_y omega^2 G (2/k) sin(k L_x / 2), G = [sinh kh - sinh k(h-d)] / (k sinh kh).
    """
    d, h = cfg.draft, cfg.h
    G = (math.sinh(k * h) - math.sinh(k * (h - d))) / (k * math.sinh(k * h)) \
        if k * h < 300 else (1.0 - math.exp(-k * d)) / k
    return cfg.rho_w * cfg.L_y * cfg.omega**2 * G * (2.0 / k) * math.sin(k * cfg.L_x / 2.0)


def wave_force(cfg: ModelConfig, k: float, a: float, x: float, t: float) -> float:
    """Froude-Krylov force [N] on a floe centred at ``x`` at time ``t`` (amplitude ``a``)."""
    return froude_krylov_coefficient(cfg, k) * a * math.sin(k * x - cfg.omega * t)


def slope_force(cfg: ModelConfig, k: float, a: float, x: float, t: float) -> float:
    """Floe-averaged surface-slope force -m g [eta(x_r) - eta(x_l)] / L_x [N] (thin-floe check)."""
    th_r = k * (x + cfg.L_x / 2) - cfg.omega * t
    th_l = k * (x - cfg.L_x / 2) - cfg.omega * t
    return -cfg.mass * 9.81 * a * (math.cos(th_r) - math.cos(th_l)) / cfg.L_x


def orbital_velocity_amplitude(cfg: ModelConfig, k: float) -> float:
    """u_w0 = a (omega / tanh kh) cos(theta): returns omega / tanh(kh) [s^-1] (eq. 3, z = 0)."""
    return cfg.omega / math.tanh(k * cfg.h)


def effective_modulus(cfg: ModelConfig) -> float:
    """Y* = E / (2 (1 - nu^2)) [Pa]."""
    return cfg.E / (2.0 * (1.0 - cfg.nu**2))


def restitution_beta(eps: float) -> float:
    """beta = ln(eps) / sqrt(ln(eps)^2 + pi^2) (0 for eps = 1)."""
    le = math.log(eps)
    return le / math.sqrt(le * le + math.pi**2)


def cell_offsets(cfg: ModelConfig) -> np.ndarray:
    """Midpoints xi_j [m] of the n_x = L_x/dx drag cells, relative to the floe centre."""
    n_x = cfg.n_x
    return (np.arange(n_x) + 0.5) * (cfg.L_x / n_x) - cfg.L_x / 2.0
