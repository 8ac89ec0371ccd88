"""Model configuration: every parameter of the model (docs/model.md) in one frozen,
validated dataclass.

``ModelConfig`` is the single source of truth for a model point. It is frozen and
hashable, validated in one place (``__post_init__``), and round-trips exactly through
``to_dict`` / ``from_dict``. The kernel variant that runs is decided from it once,
outside the time loop.

Field-local problems (a negative length, eps outside (0, 1], an unknown dispersion
name...) raise :class:`ConfigError` (a ``ValueError``) naming the field and the value.
Cross-field *physical* problems (T/dt not an integer, ``ml`` beyond its mass-loading
cutoff, fewer than two floes) are found by :meth:`ModelConfig.check_physics`, which
raises :class:`InvalidPointError` (also a ``ValueError``): a campaign records such a
point as ``invalid`` instead of crashing.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, fields
from typing import Any

from ._validate import coerce, require, require_integral
from .dispersion import G, solve_dispersion
from .errors import ConfigError, FloewaveError, InvalidPointError

__all__ = [
    "ModelConfig",
    "FloewaveError",
    "ConfigError",
    "InvalidPointError",
    "SWEPT_FIELDS",
    "G",
]

# (G: gravity, defined with the dispersion relations it belongs to; re-exported here)

#: The seven swept dimensions of the paper's campaign (docs/model.md §7), in grid order.
SWEPT_FIELDS = ("L_x", "T", "a0", "C_sd", "eps", "d_f", "dispersion")

DISPERSIONS = ("ep", "ml", "ow")
CONTACTS = ("hertz_disk", "linear")
DAMPINGS = ("liggghts", "exact")
DRAG_INTEGRATIONS = ("quadrature", "exact")
INTEGRATORS = ("predictor", "half_step", "respa", "mts")
DRAG_HOLDS = ("linear", "midpoint")
PLACEMENTS = ("uniform", "random")
COUPLINGS = ("mean", "independent")
PROTOCOLS = ("stationary", "noise_floor")
#: the fewest time steps a binary contact may take (:meth:`ModelConfig.contact_steps`). The
#: realised restitution is within 0.01 of dt 1e-4's when a contact takes >= 50 steps and
#: 0.03-0.07 off at 9-11 (``benchmarks/dt_convergence.py``, 2026-12-02); the stiffest-limit
#: estimate is a lower bound, about 0.4x the steps of a contact at 0.05 m/s
MIN_CONTACT_STEPS = 20
STATIONARITY = ("mser", "fixed")


@dataclass(frozen=True)
class ModelConfig:
    """All parameters of one model point (SI units; docs/model.md section in brackets).

    Swept dimensions (paper §4.1)
    ----------------------------
    L_x : floe length [m] (§1)
    T : wave period [s] (§2)
    a0 : incident wave amplitude at the ice edge [m] (§4)
    C_sd : skin-drag coefficient [-] (eq. 15)
    eps : nominal restitution coefficient, in (0, 1] [-] (§3)
    d_f : initial floe-floe distance [m] (§1)
    dispersion : ``"ep"`` elastic plate, ``"ml"`` mass loading, ``"ow"`` open water (eq. 6)

    Geometry and material (§1, §7; LS-WICE-like tank, documented assumptions)
    ------------------------------------------------------------------------
    L_sheet : length of the ice sheet [m]; N_f = round(L_sheet / L_x)
    h : water depth [m]; L_y : floe width [m]; h_i : ice thickness [m]
    rho_i, rho_w : ice and water density [kg m^-3]
    E : Young's modulus [Pa]; nu : Poisson's ratio [-]
    k_s : edge-spring constant on floes 1 and N_f [N m^-1]
    C_m : added-mass coefficient [-]

    Contact law (§3)
    ----------------
    contact : ``"hertz_disk"`` (DESIgn/LIGGGHTS law) or ``"linear"``
    damping : ``"liggghts"`` (gamma = -beta sqrt(5 k m*)) or ``"exact"`` (-2 beta sqrt(k m*))
    clip_attraction : clip the contact force at 0 at the end of a contact

    Numerics (§3, §4)
    -----------------
    dt : time step [s]; T/dt must be an integer
    dx : drag/dissipation quadrature spacing along the floe bottom [m]; L_x/dx integer
    drag_integration : ``"quadrature"`` (the paper's dx grid, default) or ``"exact"``
        (closed-form floe-bottom integrals, the limit dx -> 0; floewave._exact)
    drag_every : evaluate the ice-water drag and dissipation sums (eqs. 15, 19) every this
        many time steps, at the centre of the steps they are held for (multiple time
        stepping: the floe-bottom sums cost most of a step, the contacts need every step;
        second order in the hold); n_t must be a multiple of it; 1 evaluates them every
        step as the paper does; default 4 by measurement (docs/convergence.md)
    drag_hold : how a drag held over ``drag_every`` > 1 steps is evaluated: ``"linear"``
        (at the true state of the evaluation step, where its dissipation is sampled, and
        extrapolated between evaluations along the slope from the evaluation before) or
        ``"midpoint"`` (model version 7: at the state predicted for the centre of the
        steps it holds, where the dissipation is also sampled, biased by about +2e-3)
    integrator : ``"predictor"`` (velocity Verlet, velocity-dependent forces at the
        predicted end-of-step velocity u + dt*a: second order) or ``"half_step"``
        (forces at the half-step velocity as LIGGGHTS does: first order in the damping)
        or ``"respa"`` (contacts on their own clock: the waves, drag and edge springs as
        impulses every ``drag_every`` steps, the contacts resolved at dt by sub-stepping
        only the floes in or about to enter contact; :mod:`floewave._respa`) or ``"mts"``
        (the same, but the slow force evaluated at the centre of each outer step and held
        over it instead of the impulses at its ends)
    protocol : ``"stationary"`` (default: eq. 25 start, self-consistent march update, MSER
        stationarity test, stop at the error-bar targets; :mod:`floewave.iteration.stationary`) or
        ``"noise_floor"`` (the earlier protocol: a = a0 start, relaxed update, averaging
        once the residual stops falling; with relax = 1 and noise_window = 0 the paper's
        plain algorithm). ``relax``, ``noise_window`` and ``reuse_floor`` apply to
        ``noise_floor`` only; ``transient_min`` to ``stationary`` only
    n0 : spin-up periods per iteration; nT : averaging periods per iteration (the
        stationary protocol's window)
    delta : convergence threshold on max_i |a_new - a| / a
    relax : under-relaxation of the amplitude update (the paper has 1)
    max_iterations : hard cap on iterations
    noise_window : iterations over which a stalled residual marks the noise floor
        (0 disables noise handling: the paper's plain algorithm)
    n_average : iterations averaged once the noise floor is reached (the minimum when
        ``target_stderr`` > 0)
    target_stderr : if > 0, keep averaging until max_i a_stderr_i / a0 <= target_stderr
        (adaptive window; status ``not_converged`` if ``max_average`` windows averaged or
        ``max_iterations`` come first)
    target_W_c_stderr : ensembles (R >= 2): if > 0, keep averaging also until the standard
        error of W_c is at most this [m] (points with a compact zone in >= 2 replicas)
    max_average : the stationary protocol averages at most this many windows for the
        error-bar targets: a stationary run whose targets are not met by then stops with
        the estimate and error bars it has, status ``not_converged`` (with ``iterations``
        below ``max_iterations``; 0: no such bound, the targets are pursued until
        ``max_iterations``)
    reuse_floor : start the average with the samples of the ``noise_window`` iterations
        whose residuals revealed the noise floor (instead of discarding them)
    transient_min : windows never averaged by the stationary protocol (whatever MSER says)
    transient_drag_times : the stationary protocol discards at least this many drag
        relaxation times tau_d as transient (:func:`floewave.transient.drag_time`; 0: no
        such bound)
    stationarity : the stationary protocol's transient: ``"mser"`` (MSER truncation, the
        default) or ``"fixed"`` (the first ``transient_min`` windows; reference runs)
    n0_warm : spin-up periods of every iteration after the first when ``warm_start``
        (the state is already developed and a changes by at most ~relax x residual)
    warm_start : carry the DEM state over between iterations (default) instead of
        restarting from the initial state
    confined : hold all floes fixed (u = 0), the analytic limit of §5 (deterministic:
        one chain whatever ``replicas``, uniform placement)
    overwash : include overwash dissipation (eqs. 17, 18, 21); c_ow [-], s_min [-]

    Ensemble (docs/model.md §4 "Ensembles"; docs/convergence.md "Ensembles and error bars")
    -------------------------------------------------------------------
    replicas : R, independent floe chains per point (1: a single trajectory)
    seed : ensemble seed; replica r's arrangement derives from (the configuration without
        ``replicas``, seed, r), so a point is bit-reproducible and replica r starts the
        same whatever R
    placement : ``"uniform"`` (the paper's: every gap d_f; replicas r >= 1 perturbed by
        1e-6 of the random gaps' deviation, so that chaos separates them) or ``"random"``
        (gaps (N_f - 1) d_f w_i with w uniform on the simplex: i.i.d. exponential gaps of
        mean d_f conditioned on their sum, so the ice extent is the paper's, no overlaps)
        (:func:`floewave.ensemble.initial_positions`)
    coupling : ``"mean"`` (one a(x) marched from the replica-mean dissipation; error bars
        by the jackknife over replicas) or ``"independent"`` (every replica iterates its
        own a(x); the point is the replica mean)

    Diagnostics (§6)
    ----------------
    gap_threshold : phase-averaged gap below which a pair is compact [m] (the paper's
        1e-4 m)
    compact_min_pairs, compact_min_length : a run of compact pairs (and a collisional
        stretch at either end of the ice) is a zone only if it has at least this many pairs
        and spans at least this many metres [-], [m]
    compact_bridge, compact_bridge_gap : up to ``compact_bridge`` consecutive pairs with
        mean gaps below ``compact_bridge_gap`` [m] between compact pairs count as compact
        (marginal pairs inside compact ice)
    fit_min_floes, fit_min_length : alpha_edge and alpha_inner are fitted only over a zone
        of at least this many floes spanning at least this many metres [-], [m]
    (the rule and how its defaults were chosen: :func:`floewave.results.compact_zones`,
    docs/model.md §6 "The compact-zone rule")
    """

    # --- swept (paper §4.1) ---
    L_x: float = 0.5
    T: float = 1.2
    a0: float = 0.0125
    C_sd: float = 0.05
    eps: float = 0.6
    d_f: float = 0.005
    dispersion: str = "ml"
    # --- geometry and material ---
    L_sheet: float = 42.0
    h: float = 2.5
    L_y: float = 10.0
    h_i: float = 0.03
    rho_i: float = 910.0
    rho_w: float = 1000.0
    E: float = 3.0e7
    nu: float = 0.3
    k_s: float = 9.0e4
    C_m: float = 0.1
    # --- contact ---
    contact: str = "hertz_disk"
    damping: str = "liggghts"
    clip_attraction: bool = False
    # --- numerics ---
    dt: float = 1.0e-3
    dx: float = 0.01
    drag_integration: str = "quadrature"
    drag_every: int = 4
    drag_hold: str = "midpoint"
    integrator: str = "predictor"
    protocol: str = "stationary"
    n0: int = 5
    nT: int = 5
    delta: float = 1.0e-3
    relax: float = 0.5
    max_iterations: int = 100
    noise_window: int = 4
    n_average: int = 10
    target_stderr: float = 0.01
    target_W_c_stderr: float = 1.0
    max_average: int = 30
    n0_warm: int = 0
    transient_min: int = 6
    transient_drag_times: float = 2.0
    stationarity: str = "mser"
    reuse_floor: bool = True
    warm_start: bool = True
    confined: bool = False
    overwash: bool = False
    c_ow: float = 1.0
    s_min: float = 0.03
    # --- ensemble ---
    replicas: int = 8
    seed: int = 0
    placement: str = "random"
    coupling: str = "independent"
    # --- diagnostics ---
    gap_threshold: float = 1.0e-4
    compact_min_pairs: int = 3
    compact_min_length: float = 3.0
    compact_bridge: int = 2
    compact_bridge_gap: float = 2.0e-4
    fit_min_floes: int = 5
    fit_min_length: float = 2.0

    # ------------------------------------------------------------------ validation
    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            object.__setattr__(self, f.name, coerce(f.name, f.type, value))
        positive = ("L_x", "T", "a0", "L_sheet", "h", "L_y", "h_i", "rho_i", "rho_w",
                    "dt", "dx", "delta", "gap_threshold")
        for name in positive:
            require(self, name, getattr(self, name) > 0, "must be > 0")
        non_negative = ("C_sd", "d_f", "E", "k_s", "C_m", "c_ow", "s_min",
                        "compact_min_length", "fit_min_length")
        for name in non_negative:
            require(self, name, getattr(self, name) >= 0, "must be >= 0")
        require(self, "eps", 0 < self.eps <= 1, "must be in (0, 1]")
        require(self, "nu", 0 <= self.nu < 0.5, "must be in [0, 0.5)")
        require(self, "relax", 0 < self.relax <= 1, "must be in (0, 1]")
        require(self, "n0", self.n0 >= 0, "must be >= 0")
        require(self, "drag_every", 1 <= self.drag_every <= 100, "must be in [1, 100]")
        require(self, "nT", self.nT >= 1, "must be >= 1")
        require(self, "max_iterations", self.max_iterations >= 1, "must be >= 1")
        require(self, "noise_window", self.noise_window >= 0, "must be >= 0")
        require(self, "n_average", self.n_average >= 2, "must be >= 2")
        require(self, "n0_warm", self.n0_warm >= 0, "must be >= 0")
        require(self, "transient_min", self.transient_min >= 0, "must be >= 0")
        require(self, "transient_drag_times", 0 <= self.transient_drag_times <= 1000,
                 "must be in [0, 1000]")
        # counts that would make a point run for ever (or overflow the cost): refused here
        for name in ("n0", "nT", "n0_warm", "max_iterations", "noise_window", "n_average",
                     "transient_min", "max_average"):
            require(self, name, getattr(self, name) <= 1_000_000, "must be <= 1000000")
        require(self, "max_average", self.max_average == 0 or self.max_average >= self.n_average,
                f"must be 0 or >= n_average ({self.n_average}): set it with n_average")
        require(self, "replicas", 1 <= self.replicas <= 4096, "must be in [1, 4096]")
        require(self, "seed", 0 <= self.seed < 2**63, "must be in [0, 2**63)")
        require(self, "compact_min_pairs", self.compact_min_pairs >= 1, "must be >= 1")
        require(self, "compact_bridge", self.compact_bridge >= 0, "must be >= 0")
        require(self, "compact_bridge_gap", self.compact_bridge_gap > 0, "must be > 0")
        require(self, "fit_min_floes", self.fit_min_floes >= 3, "must be >= 3")
        require(self, "target_stderr", 0 <= self.target_stderr < 1, "must be in [0, 1)")
        require(self, "target_W_c_stderr", self.target_W_c_stderr >= 0, "must be >= 0")
        require(self, "rho_i", self.rho_i < self.rho_w or self.rho_i == self.rho_w,
                 "must not exceed rho_w (floes float)")
        for name, allowed in (("dispersion", DISPERSIONS), ("contact", CONTACTS),
                              ("damping", DAMPINGS), ("drag_integration", DRAG_INTEGRATIONS),
                              ("integrator", INTEGRATORS), ("drag_hold", DRAG_HOLDS), ("placement", PLACEMENTS),
                              ("coupling", COUPLINGS),
                              ("protocol", PROTOCOLS),
                              ("stationarity", STATIONARITY)):
            require(self, name, getattr(self, name) in allowed, f"must be one of {allowed}")

    # ------------------------------------------------------------------ derived
    @property
    def n_floes(self) -> int:
        """N_f = round(L_sheet / L_x) (docs/model.md §1)."""
        return int(round(self.L_sheet / self.L_x))

    @property
    def n_t(self) -> int:
        """Time steps per wave period, T / dt (must be an integer)."""
        return int(round(self.T / self.dt))

    @property
    def n_x(self) -> int:
        """Quadrature cells along a floe bottom, L_x / dx (must be an integer)."""
        return int(round(self.L_x / self.dx))

    @property
    def omega(self) -> float:
        """Angular frequency 2 pi / T [rad s^-1]."""
        return 2.0 * math.pi / self.T

    @property
    def mass(self) -> float:
        """Floe mass m = rho_i L_x L_y h_i [kg]."""
        return self.rho_i * self.L_x * self.L_y * self.h_i

    @property
    def draft(self) -> float:
        """Floe draft d = h_i rho_i / rho_w [m]."""
        return self.h_i * self.rho_i / self.rho_w

    @property
    def n_chains(self) -> int:
        """Floe chains that run: ``replicas``, or 1 when the replicas could not differ:
        ``confined`` (deterministic), d_f = 0 (every arrangement is the touching one) or
        two floes (one gap, which must be d_f). One chain reports the single trajectory's
        error bars (the iteration standard error of a; NaN for the scalars), never the
        zero spread of identical copies."""
        if self.confined or self.d_f == 0.0 or self.n_floes <= 2:
            return 1
        return self.replicas

    def floe_steps_per_iteration(self) -> int:
        """(n0 + nT) n_t N_f: the cost unit of docs/model.md §4 for the first iteration."""
        return self.floe_steps_of(1)

    def floe_steps_of(self, iterations: int) -> int:
        """Floe-steps of ``iterations`` iterations (n0 in the first, n0_warm after it;
        confined: nT only), summed over the :attr:`n_chains` replicas."""
        if iterations <= 0:
            return 0
        n0_first = 0 if self.confined else self.n0
        n0_later = 0 if self.confined else (self.n0_warm if self.warm_start else self.n0)
        periods = (n0_first + self.nT) + (iterations - 1) * (n0_later + self.nT)
        return periods * self.n_t * self.n_floes * self.n_chains

    def contact_steps(self) -> float:
        """Time steps in the shortest binary contact the contact law allows: the half period
        pi sqrt(m* / k_n) of an undamped contact at the stiffest k_n (``linear``: Y* L_y h_i
        / L_x; ``hertz_disk``: pi Y* h_i 0.9117, the limit of f(s)), with the added-mass
        reduced mass m* = (1 + C_m) m / 2 (docs/model.md §3). A lower bound of the steps a real
        contact takes (measured at 0.05 m/s, lab ice, dt 1e-3: 51-62 steps for
        ``hertz_disk`` where this gives 22; ``benchmarks/dt_convergence.py``)."""
        y_star = self.E / (2.0 * (1.0 - self.nu**2))
        if self.contact == "linear":
            k_n = y_star * self.L_y * self.h_i / self.L_x
        else:
            k_n = math.pi * y_star * self.h_i * 0.9117
        m_star = (1.0 + self.C_m) * self.mass / 2.0
        if k_n <= 0.0:
            return math.inf
        return math.pi * math.sqrt(m_star / k_n) / self.dt

    def check_physics(self) -> tuple[float, float]:
        """Raise :class:`InvalidPointError` if this point cannot be simulated; else return
        the wavenumber k and group velocity c_g it solved for (eqs. 6, 7).

        Checks: T/dt and L_x/dx integral, n_t a multiple of ``drag_every``, a binary contact
        resolved in at least :data:`MIN_CONTACT_STEPS` steps (:meth:`contact_steps`; not for
        ``confined``), at least two floes, and (via the dispersion solver) that eq. 6 has an
        admissible root (``ml`` below its cutoff).
        """
        require_integral("T", self.T, self.dt, "dt")
        require_integral("L_x", self.L_x, self.dx, "dx")
        if not self.confined and self.n_t % self.drag_every:     # (confined: no drag loop)
            fits = max(d for d in range(1, self.drag_every) if self.n_t % d == 0)
            raise InvalidPointError(
                f"T / dt = {self.n_t} time steps per period is not a multiple of drag_every ="
                f" {self.drag_every} (the drag is evaluated every drag_every steps): set"
                f" drag_every = {fits}, or a T that is a multiple of"
                f" {self.drag_every * self.dt:g} s", field="drag_every")
        steps = self.contact_steps()
        if not self.confined and steps < MIN_CONTACT_STEPS:
            raise InvalidPointError(
                f"dt = {self.dt!r} resolves a binary contact ({self.contact} law, stiffest"
                f" limit: {steps * self.dt:.3g} s) in {steps:.1f} steps; at least"
                f" {MIN_CONTACT_STEPS} are needed (dt <= {steps * self.dt / MIN_CONTACT_STEPS:.3g}"
                " s; the paper's dt is 1e-4)", field="dt")
        if self.n_floes < 2:
            raise InvalidPointError(
                f"L_sheet / L_x = {self.L_sheet!r} / {self.L_x!r} gives {self.n_floes} floe(s);"
                " at least 2 are needed")
        return solve_dispersion(self)

    # ------------------------------------------------------------------ (de)serialise
    def to_dict(self) -> dict[str, Any]:
        """All fields as plain Python values (exact round trip with :meth:`from_dict`).

        Every field is a bool, int, float or str (``__post_init__`` coerces them), so a
        shallow dict is the whole value (``dataclasses.asdict``'s deep copy was ~20x
        slower; the campaign master builds one per task)."""
        return {name: getattr(self, name) for name in _FIELD_NAMES}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ModelConfig:
        """Build from a mapping; unknown keys raise :class:`ConfigError` naming them."""
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise ConfigError(f"unknown ModelConfig field(s): {', '.join(map(repr, unknown))}")
        return cls(**data)

    def replace_validated(self, **values: Any) -> ModelConfig:
        """A copy with fields set to values that were each validated (and coerced) by
        :meth:`replace` of that one field on this config, without validating every field
        again. For the campaign grid: one validation per distinct swept value, not one per
        point. Only for fields without a cross-field rule (every swept field)."""
        if not set(values) <= _SINGLE_FIELD_RULES:
            raise ConfigError("replace_validated: only for fields without a cross-field rule"
                              f" ({sorted(set(values) - _SINGLE_FIELD_RULES)})")
        new = object.__new__(type(self))
        new.__dict__.update(self.__dict__)
        new.__dict__.update(values)
        return new

    def replace(self, **changes: Any) -> ModelConfig:
        """A copy with some fields changed (validated again)."""
        unknown = sorted(set(changes) - {f.name for f in fields(self)})
        if unknown:
            raise ConfigError(f"unknown ModelConfig field(s): {', '.join(map(repr, unknown))}")
        return dataclasses.replace(self, **changes)


_FIELD_NAMES = tuple(f.name for f in fields(ModelConfig))
#: fields whose validity does not depend on another field (__post_init__ relates only rho_i
#: and rho_w)
_SINGLE_FIELD_RULES = frozenset(_FIELD_NAMES) - {"rho_i", "rho_w"}
