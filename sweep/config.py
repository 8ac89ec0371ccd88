"""Campaign files: TOML with ``[base]``, ``[sweep]`` and ``[run]``, validated up front.

A campaign is a base :class:`floewave.ModelConfig` plus, per swept dimension, the list
of values to try; the grid is their Cartesian product in :data:`sweep.identity.DIMENSIONS`
order (:data:`floewave.SWEPT_FIELDS`, then ``seed``: the seeds of an ensemble are one
more dimension). Every problem found is reported, one message per bad key and value, before
anything runs or is written (:class:`sweep.errors.ConfigError`, exit status 2).

Physically impossible points (``T/dt`` not integral, an ``ml`` period beyond the
mass-loading cutoff...) are found with :meth:`floewave.ModelConfig.check_physics`.
When a swept value makes *every* point that carries it impossible (or the whole grid is
impossible) that is a configuration error; otherwise the impossible points are part of
the campaign and are stored with status ``invalid`` and the reason.
"""
from __future__ import annotations

import dataclasses
import functools
import itertools
import math
import stat
import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import floewave
from floewave import ModelConfig, solve_dispersion
from floewave.help import did_you_mean
from floewave.transient import transient_windows
from sweep.errors import ConfigError
from sweep.identity import DIMENSIONS, canonical_json, point_hash, sha256_hex

__all__ = ["Campaign", "Point", "RunOptions", "load_campaign", "parse_campaign",
           "DEFAULT_EXPECTED_ITERATIONS"]

#: Iterations assumed per point for cost estimates when ``[run] expected_iterations`` is not
#: given and the point's own minimum is not known (the ``noise_floor`` protocol; a point
#: whose dispersion relation has no root). Model version 5's protocol: mean 21.8 on 128
#: random paper-grid points.
DEFAULT_EXPECTED_ITERATIONS = 22
#: Windows a ``stationary`` point runs beyond its minimum (the transient of
#: ``floewave.transient.transient_windows`` plus ``n_average``), for cost estimates.
#: Measured with model version 6 (2026-12-02): mean 2.6 on ``benchmarks/plan_check.py --n 32
#: --seed 7``'s sample and 2.4 over the 64 runs of ``benchmarks/honesty.py --reference
#: --random 24`` (most points stop at the minimum; a few run 4-18 windows more).
EXTRA_WINDOWS = 3

#: Most floes accepted in a sheet (L_sheet / L_x); the paper's largest is a few hundred.
MAX_FLOES = 1_000_000
#: Longest time [s] accepted for a ``[run]`` duration (a year).
MAX_SECONDS = 3.2e7


@dataclass(frozen=True)
class RunOptions:
    """The ``[run]`` table: how to run, never what is computed (not part of any hash).

    Attributes
    ----------
    name : campaign name shown in logs and stored in the store.
    description : free text.
    progress_interval : seconds between progress log lines when not on a terminal.
    grace_period : seconds the master waits for running points after a stop signal.
    expected_iterations : iterations per point assumed by cost estimates (0: the
        default, ``min(max_iterations, DEFAULT_EXPECTED_ITERATIONS)``).
    max_attempts : a point whose worker (or the whole job) died while computing it this
        many times is stored as ``crashed`` instead of being handed out again (0: never).
    max_points : the largest grid accepted (a guard against a typo that would expand
        billions of points).
    point_timeout : seconds a point may run; one that runs longer is stored as
        ``timeout`` (0: no limit; ``--point-timeout`` overrides it).
    writer : who writes the store of an MPI run: ``"process"`` (a writer process beside
        the master, :mod:`sweep.run.store_process`; the master only schedules) or
        ``"inline"`` (the master itself). In-process runs always write inline.
    """

    name: str = ""
    description: str = ""
    progress_interval: float = 30.0
    grace_period: float = 60.0
    expected_iterations: int = 0
    max_attempts: int = 3
    max_points: int = 1_000_000
    point_timeout: float = 0.0
    writer: str = "process"


@dataclass(frozen=True)
class Point:
    """One grid point: its position, resolved configuration, identity and cost.

    ``cost`` is the floe-steps of the expected number of iterations (docs/model.md §4;
    ``ModelConfig.floe_steps_of``: the first iteration spins up n0 periods, later ones n0_warm),
    ``invalid`` the reason the point is physically impossible (``""`` when it is not).
    """

    index: int
    hash: str
    config: ModelConfig
    swept: dict[str, Any]
    cost: float
    invalid: str = ""


@dataclass(frozen=True)
class Campaign:
    """A validated campaign: base configuration, swept values and run options."""

    base: ModelConfig
    sweep: dict[str, tuple[Any, ...]]
    run: RunOptions = field(default_factory=RunOptions)
    text: str = ""
    source: str = "<string>"
    shard_of: tuple[int, int] | None = None

    def shard(self, k: int, n: int) -> Campaign:
        """The same campaign restricted to shard ``k`` of ``n``: points whose hash,
        as an integer, is ``k`` modulo ``n`` (stable under ``--extend``). The grid
        already expanded (and checked) for this campaign is filtered, not expanded
        again."""
        sharded = dataclasses.replace(self, shard_of=(k, n))
        full = self.__dict__.get("_grid") if self.shard_of is None else None
        if full is not None:  # the cached_property's slot (a frozen dataclass allows it)
            sharded.__dict__["_grid"] = tuple(p for p in full if int(p.hash, 16) % n == k)
        return sharded

    @property
    def swept_fields(self) -> tuple[str, ...]:
        """The swept dimensions, in :data:`sweep.identity.DIMENSIONS` order."""
        return tuple(self.sweep)

    @property
    def size(self) -> int:
        """Number of grid points (of this shard, when sharded)."""
        if self.shard_of is not None:
            return len(self._grid)
        return math.prod(len(v) for v in self.sweep.values())

    def definition(self) -> dict[str, Any]:
        """What the campaign computes: base fields, swept values and model version."""
        return {"base": self.base.to_dict(),
                "sweep": {k: list(v) for k, v in self.sweep.items()},
                "model_version": floewave.MODEL_VERSION}

    def definition_hash(self) -> str:
        """SHA-256 of the canonical JSON of :meth:`definition` (comments do not count)."""
        return sha256_hex(canonical_json(self.definition()))

    def expected_iterations(self, cfg: ModelConfig) -> int:
        """Iterations assumed for ``cfg`` in cost estimates: ``[run] expected_iterations``
        if given; for the ``stationary`` protocol the point's own minimum (its transient,
        which grows as 1/C_sd, plus ``n_average``) plus :data:`EXTRA_WINDOWS`; else
        :data:`DEFAULT_EXPECTED_ITERATIONS`. At most ``max_iterations``."""
        n = self.run.expected_iterations
        if not n and cfg.protocol == "stationary" and not cfg.confined:
            k = self._wavenumber(cfg)
            if k is not None:
                n = transient_windows(cfg, k) + cfg.n_average + EXTRA_WINDOWS
        return min(cfg.max_iterations, n or DEFAULT_EXPECTED_ITERATIONS)

    def _wavenumber(self, cfg: ModelConfig) -> float | None:
        """k of eq. 6 for ``cfg`` (None without a root), solved once per distinct wave and
        ice (the grid has few)."""
        key = (cfg.dispersion, cfg.T, cfg.h, cfg.h_i, cfg.rho_i, cfg.rho_w, cfg.E, cfg.nu)
        cache = self.__dict__.setdefault("_k_cache", {})
        if key not in cache:
            try:
                cache[key] = solve_dispersion(cfg)[0]
            except ValueError:
                cache[key] = None
        return cache[key]

    def points(self) -> list[Point]:
        """Expand the grid (product in DIMENSIONS order), with hashes and costs."""
        return list(self._grid)

    @functools.cached_property
    def _grid(self) -> tuple[Point, ...]:
        names = self.swept_fields
        out = []
        for index, combo in enumerate(itertools.product(*self.sweep.values())):
            swept = dict(zip(names, combo, strict=False))
            # each swept value was validated against the base when the file was read
            # (_parse_sweep): the base is not validated again for every point
            cfg = self.base.replace_validated(**swept)
            try:
                cfg.check_physics()
                invalid = ""
            except floewave.InvalidPointError as exc:
                invalid = str(exc) or type(exc).__name__
            except ValueError as exc:  # e.g. DispersionError: no admissible root
                invalid = f"{type(exc).__name__}: {exc}"
            cost = float(cfg.floe_steps_of(self.expected_iterations(cfg)))
            out.append(Point(index, point_hash(cfg), cfg, swept, cost, invalid))
        if self.shard_of is not None:
            k, n = self.shard_of
            out = [p for p in out if int(p.hash, 16) % n == k]
        return tuple(out)


_RUN_TYPES = {f.name: f.type for f in fields(RunOptions)}
_MODEL_FIELDS = {f.name for f in fields(ModelConfig)}
_FLOAT_FIELDS = {f.name for f in fields(ModelConfig) if f.type in (float, "float")}
#: Largest campaign file [bytes] (the paper's grid is 3 KB): ``sweep run /dev/zero``
#: or a huge file by mistake is refused, not read without bound.
MAX_CAMPAIGN_BYTES = 1 << 20
#: Magnitudes a real parameter of a campaign may have (SI units), zero apart: no
#: parameter of the model lies outside, and values beyond overflow (a0 = 1e308) or
#: underflow (dt = 1e-300, eps = 5e-324) the model's arithmetic. Sweep's own bound, on
#: top of floewave's validation.
MAGNITUDE = (1e-12, 1e12)


def _magnitude_problem(key: str, value: Any) -> str:
    """Why a real parameter's value is out of :data:`MAGNITUDE` ("" when it is not)."""
    if key not in _FLOAT_FIELDS or isinstance(value, bool) or \
            not isinstance(value, (int, float)):
        return ""
    v = abs(float(value))
    if v == 0 or not math.isfinite(v) or MAGNITUDE[0] <= v <= MAGNITUDE[1]:
        return ""  # zero, and non-finite values, are floewave's to judge
    return (f"magnitude {v:.3g} is out of range [{MAGNITUDE[0]:g}, {MAGNITUDE[1]:g}] (SI"
            " units): no parameter of the model is there")


def load_campaign(path: str | Path) -> Campaign:
    """Read and validate a campaign file.

    Parameters
    ----------
    path : the TOML file.

    Raises
    ------
    ConfigError
        With one message per problem, each naming the key and the value.
    """
    path = Path(path)
    try:
        st = path.stat()
        if not stat.S_ISREG(st.st_mode):  # /dev/zero reads forever, a FIFO blocks
            raise ConfigError(f"{path}: not a regular file; a campaign file is a TOML file")
        if st.st_size > MAX_CAMPAIGN_BYTES:
            raise ConfigError(f"{path}: {st.st_size:,} bytes; a campaign file is at most"
                              f" {MAX_CAMPAIGN_BYTES:,} (is this the right file?)")
        with open(path, "rb") as fh:
            data = fh.read(MAX_CAMPAIGN_BYTES + 1)
        if len(data) > MAX_CAMPAIGN_BYTES:
            raise ConfigError(f"{path}: more than {MAX_CAMPAIGN_BYTES:,} bytes")
        text = data.decode("utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{path}: cannot read campaign file: {exc}") from None
    return parse_campaign(text, str(path))


def parse_campaign(text: str, source: str = "<string>") -> Campaign:
    """Validate campaign TOML text; see :func:`load_campaign`."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{source}: not valid TOML: {exc}") from None
    except RecursionError:
        raise ConfigError(f"{source}: not valid TOML: nested too deeply") from None
    errors: list[str] = []
    for key in sorted(set(data) - {"base", "sweep", "run"}):
        errors.append(f"{source}: unknown table or key [{key}] (allowed: [base], [sweep], [run])")
    for section in ("base", "sweep", "run"):
        if section in data and not isinstance(data[section], dict):
            errors.append(f"{source}: {section} = {data[section]!r}: expected a table [{section}]")
            data[section] = {}
    if "sweep" not in data:
        errors.append(f"{source}: missing table [sweep] (the swept values)")
    for key in sorted(set(data.get("base", {})) & set(data.get("sweep", {}))):
        errors.append(f"{source}: {key} is set in both [base] ({key} ="
                      f" {data['base'][key]!r}) and [sweep] ({key} = {data['sweep'][key]!r}):"
                      " a swept value replaces the base one; keep it in one place")
    base = _parse_base(data.get("base", {}), source, errors)
    sweep = _parse_sweep(data.get("sweep", {}), base, source, errors)
    run = _parse_run(data.get("run", {}), source, errors)
    if errors:
        raise ConfigError(errors)
    assert base is not None
    if not sweep:
        raise ConfigError(f"{source}: [sweep] is empty: list the values of at least one"
                          f" swept dimension ({', '.join(DIMENSIONS)})")
    size = math.prod(len(v) for v in sweep.values())
    if size > run.max_points:
        raise ConfigError(f"{source}: the grid has {size:,} points, more than [run]"
                          f" max_points = {run.max_points:,}; raise max_points if that is"
                          " intended")
    campaign = Campaign(base=base, sweep=sweep, run=run, text=text, source=source)
    try:
        _check_physics(campaign, source)
    except (OverflowError, ZeroDivisionError, RecursionError) as exc:
        raise ConfigError(f"{source}: a value is out of range ({type(exc).__name__}: {exc});"
                          " check the [base] and [sweep] lengths, periods and time steps"
                          ) from None
    return campaign


def _field_problem(exc: Exception, key: str | None) -> str:
    """What is wrong with ``key``'s value: the floewave error's ``problem`` when ``key`` is
    the field at fault, else the whole message (another field, or no field, at fault)."""
    if key is not None and isinstance(exc, floewave.FloewaveError) and exc.field == key:
        return exc.problem
    return str(exc)


def _parse_base(table: dict[str, Any], source: str, errors: list[str]) -> ModelConfig | None:
    ok: dict[str, Any] = {}
    n_before = len(errors)
    for key, value in table.items():
        if key not in _MODEL_FIELDS:
            errors.append(f"{source}: [base] {key} = {value!r}: unknown parameter"
                          f"{did_you_mean(key)} (the parameters: 'floewave run --help')")
            continue
        problem = _magnitude_problem(key, value)
        if problem:
            errors.append(f"{source}: [base] {key} = {value!r}: {problem}")
            continue
        try:
            ModelConfig(**{key: value})
        except (floewave.ConfigError, TypeError) as exc:
            errors.append(f"{source}: [base] {key} = {value!r}: {_field_problem(exc, key)}")
            continue
        ok[key] = value
    if len(errors) > n_before:
        return None
    try:
        return ModelConfig(**ok)
    except (floewave.ConfigError, TypeError) as exc:  # a cross-field rule
        field = getattr(exc, "field", None)
        key = field if field in ok else None
        shown = f"{key} = {ok[key]!r}" if key else "(combination)"
        errors.append(f"{source}: [base] {shown}: {_field_problem(exc, key)}")
        return None


def _parse_sweep(table: dict[str, Any], base: ModelConfig | None, source: str,
                 errors: list[str]) -> dict[str, tuple[Any, ...]]:
    sweep: dict[str, tuple[Any, ...]] = {}
    allowed = DIMENSIONS
    for key, values in table.items():
        if key not in allowed:
            errors.append(f"{source}: [sweep] {key} = {values!r}: not a swept dimension"
                          f" (allowed: {', '.join(allowed)})")
            continue
        if not isinstance(values, list) or not values:
            errors.append(f"{source}: [sweep] {key} = {values!r}: expected a non-empty list"
                          " of values")
            continue
        resolved = []
        for value in values:
            problem = _magnitude_problem(key, value)
            if problem:
                errors.append(f"{source}: [sweep] {key} = {value!r}: {problem}")
                continue
            try:
                cfg = (base or ModelConfig()).replace(**{key: value})
            except (floewave.ConfigError, TypeError) as exc:
                errors.append(f"{source}: [sweep] {key} = {value!r}: "
                              f"{_field_problem(exc, key)}")
                continue
            resolved.append(getattr(cfg, key))  # coerced: 1 -> 1.0 for float fields
        seen = set()
        for value in resolved:
            if value in seen:
                errors.append(f"{source}: [sweep] {key} = {value!r}: listed twice")
            seen.add(value)
        sweep[key] = tuple(resolved)
    return {k: sweep[k] for k in allowed if k in sweep}


def _parse_run(table: dict[str, Any], source: str, errors: list[str]) -> RunOptions:
    ok: dict[str, Any] = {}
    for key, value in table.items():
        kind = _RUN_TYPES.get(key)
        if kind is None:
            errors.append(f"{source}: [run] {key} = {value!r}: unknown option"
                          f" (allowed: {', '.join(_RUN_TYPES)})")
            continue
        if kind == "str" and not isinstance(value, str):
            errors.append(f"{source}: [run] {key} = {value!r}: expected a string")
        elif kind == "float" and (isinstance(value, bool) or not isinstance(value, (int, float))
                                  or not math.isfinite(value) or value < 0):
            errors.append(f"{source}: [run] {key} = {value!r}: expected a number >= 0")
        elif kind == "int" and (isinstance(value, bool) or not isinstance(value, int)
                                or value < 0):
            errors.append(f"{source}: [run] {key} = {value!r}: expected an integer >= 0")
        else:
            ok[key] = float(value) if kind == "float" else value
    if "writer" in ok and ok["writer"] not in ("process", "inline"):
        errors.append(f"{source}: [run] writer = {ok.pop('writer')!r}: expected \"process\""
                      " or \"inline\"")
    if ok.get("progress_interval") == 0:
        errors.append(f"{source}: [run] progress_interval = 0: must be > 0")
    for key in ("progress_interval", "grace_period", "point_timeout"):
        if ok.get(key, 0) > MAX_SECONDS:
            errors.append(f"{source}: [run] {key} = {table[key]!r}: at most {MAX_SECONDS:g}"
                          " s (a year)")
            ok.pop(key)
    return RunOptions(**ok)


def _check_physics(campaign: Campaign, source: str) -> None:
    """Refuse swept values (or a base) for which every point is physically impossible,
    sheets of more than :data:`MAX_FLOES` floes, and periods that give the same number of
    time steps per period (the same physics under two hashes)."""
    points = campaign.points()
    big = max(points, key=lambda p: p.config.n_floes)
    if big.config.n_floes > MAX_FLOES:
        raise ConfigError(f"{source}: {big.swept}: L_sheet / L_x = {big.config.n_floes:,}"
                          f" floes, more than {MAX_FLOES:,}: check L_sheet and L_x")
    if "T" in campaign.sweep:
        steps: dict[int, float] = {}
        for T in campaign.sweep["T"]:
            n_t = campaign.base.replace(T=T).n_t
            if n_t in steps:
                raise ConfigError(f"{source}: [sweep] T = {T!r}: the same {n_t} time steps"
                                  f" per period as T = {steps[n_t]!r} (dt ="
                                  f" {campaign.base.dt!r}): the same point twice")
            steps[n_t] = T
    invalid = [p for p in points if p.invalid]
    if not invalid:
        return
    if len(invalid) == len(points):
        raise ConfigError(f"{source}: every one of the {len(points)} grid points is physically"
                          f" impossible, e.g. {invalid[0].swept}: {invalid[0].invalid}")
    errors = []
    for key, values in campaign.sweep.items():
        for value in values:
            having = [p for p in points if p.swept[key] == value]
            if all(p.invalid for p in having):
                errors.append(f"{source}: [sweep] {key} = {value!r}: every point with this"
                              f" value is physically impossible: {having[0].invalid}")
    if errors:
        raise ConfigError(errors)
