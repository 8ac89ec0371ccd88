"""The surrogate: the released grid read as a function of (L_x, T, a0, C_sd, eps, d_f) per
dispersion relation, with a standard error on every value.

**Values.** Each quantity is interpolated between the nodes of the grid (:mod:`.grid`: log
axes for L_x, a0, C_sd, d_f), in log(value): ``alpha_all``, ``alpha_edge``, ``a_end_rel``
(a_end/a0) and ``W_c``; multilinearly, except along the axes of ``meta["quadratic"]``
(per quantity) where the value is read quadratically: with three levels the quadratic
through all three, with more the mean of those through the cell and each neighbour
(:func:`.grid.window_weights`; where a node it needs has no value, linearly). ``p_zone``, the
probability that a compact zone forms, is the multilinear interpolant of the nodes' 0/1
outcome (recalibrated, ``meta["p_zone"]``); ``W_c`` (the zone's width where one forms) is
interpolated over the corners with a zone only, and is NaN where no corner has one. A node
without a result weighs nothing.

**Standard errors.** Two parts, added in quadrature (in log, so relative): the nodes'
stochastic errors carried through the weights, sqrt(sum w_i^2 se_i^2) (the calibrated SEs
of ``results/calibration/factors.csv`` where the table is of that model version), and the
interpolation error between the nodes: per axis a curvature term (the node values'
curvature along it, from the leave-one-out residual at each interior node with its noise
taken out, :mod:`.build`, times (t(1-t)h^2)^2) and a flat one ((4t(1-t))^2), each with its
own scale per quantity (each interval of the axes of ``meta["intervals"]`` apart: L_x's,
and d_f's), and a *missing* term, (1 - w)^2 where w is the weight of the cell's corners
the value is read from (a corner without a value weighs nothing: W_c at the margin of the
compact zones' region, a node without an SE), combined with a power p
(:func:`combine`); scales and p fitted on off-grid points run for the purpose, never on
the validation sets (:func:`.validate.fit_scale`). At a node every term is zero, and the
surrogate returns the node's own value and SE.
"""
from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from herman2019.surrogate.grid import (
    AXES,
    DISPERSIONS,
    OutsideBox,
    cell_weights,
    check_box,
    window_weights,
)

__all__ = ["QUANTITIES", "Surrogate", "SHIPPED"]

#: The interpolated quantities (each in log), in the output's order.
QUANTITIES = ("alpha_all", "alpha_edge", "a_end_rel", "W_c")
#: The shipped surrogate, built from the released grid.
SHIPPED = Path(__file__).resolve().parents[2] / "results" / "surrogate" / "surrogate.npz"
#: Points per block when predicting (bounds the memory of the corners' gather).
BLOCK = 8192


@dataclass
class Surrogate:
    """Node arrays per dispersion relation (fields in C order over :data:`AXES`) and the
    interpolation error's scales (``scale["q:term"]``) and combination (``meta``). Build
    with :func:`.build.build`; save and
    load with :meth:`save` and :meth:`load`."""

    levels: dict[str, np.ndarray]
    fields: dict[str, np.ndarray]          # dispersion -> (n_nodes, n_fields)
    names: tuple[str, ...]                 # the field names
    scale: dict[str, float] = field(default_factory=dict)   # quantity -> c
    meta: dict = field(default_factory=dict)

    # ------------------------------------------------------------------ files
    def save(self, path: str | Path) -> None:
        """One ``.npz`` file (loads in milliseconds; no pickle)."""
        arrays = {f"level_{a}": v for a, v in self.levels.items()}
        arrays |= {f"fields_{d}": v.astype(np.float64) for d, v in self.fields.items()}
        arrays["meta"] = np.frombuffer(json.dumps(
            {"names": list(self.names), "scale": self.scale, "meta": self.meta},
            sort_keys=True).encode(), dtype=np.uint8)
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        with open(path, "wb") as fh:
            np.savez_compressed(fh, **arrays)

    @classmethod
    def load(cls, path: str | Path | None = None) -> Surrogate:
        """The surrogate of ``path`` (default: the shipped one, :data:`SHIPPED`)."""
        path = SHIPPED if path is None else Path(path)
        if not path.is_file():
            raise FileNotFoundError(f"{path}: no surrogate file (build it with"
                                    " `herman2019 surrogate --build`)")
        with np.load(path, allow_pickle=False) as z:
            head = json.loads(z["meta"].tobytes().decode())
            levels = {a: z[f"level_{a}"] for a in AXES}
            fields = {d: z[f"fields_{d}"] for d in DISPERSIONS if f"fields_{d}" in z}
        return cls(levels, fields, tuple(head["names"]), head["scale"], head["meta"])

    # ------------------------------------------------------------------ reading
    def column(self, name: str) -> int:
        return self.names.index(name)

    def predict(self, dispersion, detail: bool | str = False, **params) -> pd.DataFrame:
        """The surrogate at the points given by ``params`` (the six axes, scalars or arrays
        broadcast together; ``dispersion`` a name or an array of names): one row per
        point with the parameters and, per quantity, its value and ``_se`` (``detail``:
        also ``_se_noise`` and ``_se_interp``, relative; ``detail="terms"``: also each
        error term before its scale, ``q_term_<name>`` for the names of :meth:`terms`).
        OutsideBox (a ValueError) for a point outside the grid's box or an unknown
        dispersion relation."""
        missing = [a for a in AXES if a not in params]
        extra = sorted(set(params) - set(AXES))
        if missing or extra:
            raise TypeError(f"surrogate: give each of {', '.join(AXES)} and dispersion"
                            + (f"; missing {', '.join(missing)}" if missing else "")
                            + (f"; unknown {', '.join(extra)}" if extra else ""))
        arrays = np.broadcast_arrays(*(np.asarray(params[a], dtype=float) for a in AXES),
                                     np.asarray(dispersion, dtype=object))
        q = {a: arrays[k].ravel() for k, a in enumerate(AXES)}
        disp = arrays[-1].ravel().astype(str)
        unknown = sorted(set(disp) - set(self.fields))
        if unknown:
            raise OutsideBox(f"dispersion {str(unknown[0])!r}: the surrogate knows"
                             f" {', '.join(self.fields)}")
        check_box(self.levels, q)
        out = pd.DataFrame({a: q[a] for a in AXES})
        out.insert(len(AXES), "dispersion", pd.array(disp, dtype="string"))
        cols: dict[str, np.ndarray] = {}
        for d in self.fields:
            sel = np.flatnonzero(disp == d)
            for lo in range(0, sel.size, BLOCK):
                part = sel[lo:lo + BLOCK]
                got = self._predict_one(d, {a: q[a][part] for a in AXES}, detail)
                for k, v in got.items():
                    cols.setdefault(k, np.full(disp.size, np.nan))[part] = v
        return pd.concat([out, pd.DataFrame(cols, index=out.index)], axis=1)

    def quadratic_axes(self, q: str) -> tuple[str, ...]:
        """The axes along which ``q``'s value is read quadratically (the others linearly:
        :func:`.grid.window_weights`), ``meta["quadratic"]``; a file of the first
        surrogates says ``meta["lx_order"]`` (2: along L_x)."""
        if "quadratic" in self.meta:
            return tuple(a for a in AXES if a in self.meta["quadratic"].get(q, ()))
        return ("L_x",) if int(self.meta.get("lx_order", {}).get(q, 1)) == 2 else ()

    def _columns(self, d: str) -> dict[str, np.ndarray]:
        """Dispersion ``d``'s node fields as contiguous columns, cached (a prediction
        gathers only the columns it reads)."""
        cache = self.__dict__.setdefault("_cols", {})
        if d not in cache:
            cache[d] = {n: np.ascontiguousarray(self.fields[d][:, i])
                        for i, n in enumerate(self.names)}
        return cache[d]

    def term_names(self) -> tuple[str, ...]:
        """The interpolation-error terms, each with its own scale per quantity: per axis
        the curvature's term, ``AXIS``, and a flat one, ``AXIS:flat`` ((4 t(1 - t))^2: 1
        mid-cell, 0 at the nodes), which keeps an error between the nodes where the
        curvature seen at them is nil; and ``missing``, (1 - w)^2 with w the weight of
        the corners the value is read from. The intervals of the axes of
        :meth:`interval_axes` each have their own: ``AXIS`` the first, then
        ``L_x:upper`` (L_x with three levels) or ``AXIS:i1``, ``AXIS:i2``... (more)."""
        base = (*AXES, *(n for a in self.interval_axes() for n in self._interval_names(a)[1:]))
        return base + tuple(f"{n}:flat" for n in base) + ("missing",)

    def interval_axes(self) -> tuple[str, ...]:
        """The axes whose intervals each have their own error terms (``meta["intervals"]``;
        a file of the first surrogates: L_x alone)."""
        return tuple(a for a in AXES if a in self.meta.get("intervals", ("L_x",)))

    def _interval_names(self, axis: str) -> list[str]:
        """The name of the axis's term in each of its intervals (one name: every
        interval shares it)."""
        if axis not in self.interval_axes():
            return [axis]
        n = len(self.levels[axis]) - 1
        if axis == "L_x" and n == 2:
            return ["L_x", "L_x:upper"]
        return [axis] + [f"{axis}:i{j}" for j in range(1, n)]

    def combine_power(self, qn: str) -> float:
        """How the terms' variances combine: (sum v_n^(p/2))^(2/p); p = 2 adds them, a
        large p takes the largest (fitted, ``meta["combine"]``)."""
        return float(self.meta.get("combine", {}).get(qn, 2.0))

    def _scale(self, qn: str, name: str) -> float:
        """The term's fitted scale; unfitted: 1 for a curvature term, 0 for a flat one and
        for ``missing`` (a file without it reads as before)."""
        default = (0.0 if name.endswith(":flat") or name == "missing"
                   else self.scale.get(qn, 1.0))
        return float(self.scale.get(f"{qn}:{name}", default))

    def _predict_one(self, d: str, q: Mapping[str, np.ndarray], detail: bool | str
                     ) -> dict[str, np.ndarray]:
        col = self._columns(d)
        idx, w, t, h = cell_weights(self.levels, q)
        pos = (t * (1.0 - t) * h**2) ** 2                      # (t(1-t)h^2)^2
        flat = (4.0 * t * (1.0 - t)) ** 2                      # 1 mid-cell, 0 at nodes
        lower = np.unravel_index(idx[:, 0], [len(self.levels[a]) for a in AXES])
        split = {a: (self._interval_names(a), lower[k])   # the axis's interval, from 0
                 for k, a in enumerate(AXES) if a in self.interval_axes()}
        windows: dict[tuple[str, ...], tuple[np.ndarray, np.ndarray]] = {}
        zone = col["zone"][idx]                # NaN at a node without a result: left out
        known = np.isfinite(zone)
        wz = np.where(known, w, 0.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            p = np.sum(wz * np.where(known, zone, 0.0), axis=1) / wz.sum(axis=1)
        res: dict[str, np.ndarray] = {"p_zone": self._p_zone(p)}
        for qn in QUANTITIES:
            every = detail == "terms"           # else a term of scale 0 is not computed
            need = {a for a in AXES if every or any(
                self._scale(qn, n) > 0 for n in self._interval_names(a))}
            mean, noise2, terms, bad, used_w = _linear(col, idx, w, pos, qn, need)
            named = {}
            for suffix, arr in (("", terms), (":flat", flat)):
                named |= {a + suffix: arr[:, k] for k, a in enumerate(AXES)}
                for k, a in enumerate(AXES):                  # one per interval
                    if a in split:
                        names, interval = split[a]
                        for j, name in enumerate(names):
                            named[name + suffix] = np.where(interval == j, arr[:, k], 0.0)
            named["missing"] = np.clip(1.0 - used_w, 0.0, 1.0) ** 2
            used = [self._scale(qn, n) ** 2 * v for n, v in named.items()
                    if every or self._scale(qn, n) > 0]
            interp2 = (combine(np.stack(used, axis=1), self.combine_power(qn)) if used
                       else np.zeros(len(mean)))
            axes = self.quadratic_axes(qn)
            if axes:
                if axes not in windows:
                    windows[axes] = window_weights(self.levels, q, axes)
                quad = windows[axes]
                y, s = col[f"y_{qn}"][quad[0]], col[f"s_{qn}"][quad[0]]
                # (a node of the window that weighs nothing, e.g. an end cell's fourth,
                # need not have a value)
                full = np.all((np.isfinite(y) & np.isfinite(s)) | (quad[1] == 0), axis=1)
                w2 = np.where(full[:, None], quad[1], 0.0)
                mean2 = np.sum(w2 * np.where(w2 != 0, y, 0.0), axis=1)
                noise2q = np.sum((w2 * np.where(w2 != 0, s, 0.0)) ** 2, axis=1)
                mean = np.where(full, mean2, mean)             # linear where a node lacks
                noise2 = np.where(full, noise2q, noise2)
            value = np.exp(mean)
            rel = np.sqrt(noise2 + interp2)
            value[bad], rel[bad] = np.nan, np.nan
            res[qn] = value
            res[qn + "_se"] = value * rel
            if detail:
                res[qn + "_se_noise"] = np.where(bad, np.nan, np.sqrt(noise2))
                res[qn + "_se_interp"] = np.where(bad, np.nan, np.sqrt(interp2))
            if detail == "terms":
                for n, v in named.items():
                    res[f"{qn}_term_{n}"] = np.where(bad, np.nan, v)
        return res

    def _p_zone(self, p: np.ndarray) -> np.ndarray:
        """The interpolated 0/1 outcome, recalibrated where 0 < p < 1 (``meta["p_zone"]``:
        a, b of p' = 1 / (1 + exp(-(a + b logit p))), fitted on the calibration sets)."""
        ab = self.meta.get("p_zone")
        if not ab:
            return p
        inside = (p > 0) & (p < 1)
        with np.errstate(divide="ignore", invalid="ignore"):
            logit = np.log(p / (1 - p))
            out = 1.0 / (1.0 + np.exp(-(ab[0] + ab[1] * logit)))
        return np.where(inside, out, p)


def combine(v: np.ndarray, p: float) -> np.ndarray:
    """(sum_n v_n^(p/2))^(2/p) over the last axis of variances ``v`` >= 0, computed about
    their largest (no overflow for a large p)."""
    top = np.max(v, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(top[..., None] > 0, v / np.where(top > 0, top, 1.0)[..., None], 0.0)
    return top * np.sum(ratio ** (p / 2), axis=-1) ** (2 / p)


def _linear(col: Mapping[str, np.ndarray], idx: np.ndarray, w: np.ndarray, pos: np.ndarray,
            qn: str, need=AXES):
    """Multilinear over the corners where ``qn`` has a value (weights renormalised): mean
    of log q, its noise variance, the interpolation-error terms per axis (n, 6), where
    no corner has a value, and the weight of the corners with one."""
    y, s = col[f"y_{qn}"][idx], col[f"s_{qn}"][idx]
    m = np.isfinite(y) & np.isfinite(s)
    every = bool(m.all())
    wm = w if every else np.where(m, w, 0.0)
    tot = wm.sum(axis=1)
    bad = tot <= 0
    terms = np.empty(pos.shape)
    with np.errstate(invalid="ignore", divide="ignore"):
        wn = wm / tot[:, None]
        mean = np.sum(wn * (y if every else np.where(m, y, 0.0)), axis=1)
        noise2 = np.sum((wn * (s if every else np.where(m, s, 0.0))) ** 2, axis=1)
        for k, a in enumerate(AXES):
            if a not in need:
                terms[:, k] = 0.0
                continue
            kappa = col[f"k_{qn}_{a}"][idx]
            mk = m & np.isfinite(kappa)
            if mk.all():
                kk = np.sum(w * kappa, axis=1)
            else:
                wk = np.where(mk, w, 0.0)
                kk = np.sum(wk * np.where(mk, kappa, 0.0), axis=1) / wk.sum(axis=1)
            terms[:, k] = np.nan_to_num(kk) * pos[:, k]
    return mean, noise2, terms, bad, np.where(m.all(axis=1), 1.0, tot)
