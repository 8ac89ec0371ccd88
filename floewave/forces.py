"""Floe forces of eq. 8 as small formulas (docs/model.md §3); the kernels use their coefficients.

Each function states its equation; :func:`time_loop_coefficients` evaluates those the numba
time loop needs for one point, in one call (:func:`floewave._kernels.kernel_params` adds the
step and the drag cells' geometry). This module imports no kernel.
"""
from __future__ import annotations

import math

import numpy as np

from .config import ModelConfig

__all__ = ["froude_krylov_coefficient", "wave_force", "orbital_velocity_amplitude",
           "effective_modulus", "restitution_beta", "cell_offsets",
           "slope_force", "time_loop_coefficients"]


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


def time_loop_coefficients(cfg: ModelConfig, k: float) -> dict[str, float]:
    """The coefficients of eq. 8's terms the time loop needs at wavenumber ``k`` [m^-1], by
    the names of :class:`floewave._kernels.KernelParams`: ``c_wave`` [N m^-1]
    (:func:`froude_krylov_coefficient`), ``u_amp`` [s^-1]
    (:func:`orbital_velocity_amplitude`), ``c_drag`` = rho_w C_sd L_y dx [kg m^-2] (eq. 15),
    ``inv_mass`` = 1 / ((1 + C_m) m) [kg^-1], ``one_cm`` = 1 + C_m, ``k_s`` [N m^-1],
    ``m_star`` = m / 2 [kg], ``beta`` (:func:`restitution_beta`), ``kn_lin`` = Y* L_y h_i /
    L_x [N m^-1], ``kn_disk`` = pi Y* h_i [N m^-1] and ``s_scale`` = R* / (2 h_i^2) [m^-1]
    with R* = r / 2 (docs/model.md §3)."""
    Ystar = effective_modulus(cfg)
    r = cfg.L_x / 2.0
    return dict(
        c_wave=froude_krylov_coefficient(cfg, k),
        u_amp=orbital_velocity_amplitude(cfg, k),
        c_drag=cfg.rho_w * cfg.C_sd * cfg.L_y * (cfg.L_x / cfg.n_x),
        inv_mass=1.0 / ((1.0 + cfg.C_m) * cfg.mass),
        one_cm=1.0 + cfg.C_m,
        k_s=cfg.k_s,
        m_star=cfg.mass / 2.0,
        beta=restitution_beta(cfg.eps),
        kn_lin=Ystar * cfg.L_y * cfg.h_i / cfg.L_x,
        kn_disk=math.pi * Ystar * cfg.h_i,
        s_scale=(r / 2.0) / (2.0 * cfg.h_i**2),
    )
