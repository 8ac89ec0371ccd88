"""Ensembles of floe chains (docs/model.md §4 "Ensembles"): the replicas' initial
arrangements and their seeds.

A point runs R = ``cfg.replicas`` chains. Replica r starts from its own arrangement
(:func:`initial_positions`), drawn from a seed that derives from the configuration
*without* ``replicas``, from ``cfg.seed`` and from r (:func:`replica_seed_sequence`):
the same configuration gives the same arrangements bit for bit, and replica r starts
the same whatever R.

The estimators over the replicas are the iteration's (:mod:`floewave.iteration.estimate`).
"""
from __future__ import annotations

import hashlib
import json

import numpy as np

from .config import ModelConfig

__all__ = ["initial_positions", "replica_seed_sequence"]


def replica_seed_sequence(cfg: ModelConfig) -> np.random.SeedSequence:
    """The parent seed sequence of a point's replicas: entropy = SHA-256 of the canonical
    JSON of every field but ``replicas`` (so replica r does not depend on R), then
    ``cfg.seed``. Replica r uses ``.spawn`` child r (spawn keys are (r,))."""
    d = cfg.to_dict()
    d.pop("replicas")
    text = json.dumps(d, sort_keys=True, separators=(",", ":"))
    digest = hashlib.sha256(text.encode("ascii")).digest()
    words = [int.from_bytes(digest[i:i + 4], "little") for i in range(0, 32, 4)]
    return np.random.SeedSequence([*words, cfg.seed & 0xFFFFFFFF, cfg.seed >> 32])


def initial_positions(cfg: ModelConfig) -> np.ndarray:
    """(R, N_f) initial floe centres [m], the ice edge at x = 0, the first floe's left end
    at 0, gaps g_i between floes i and i + 1 (x_{i+1} = x_i + L_x + g_i).

    ``random``: g_i = (N_f - 1) d_f e_i / sum_j e_j with e_i i.i.d. standard exponential
    (the replica's PCG64 stream by inversion, -log1p(-u)): uniform on the simplex, so every
    gap is >= 0 (no overlap), their mean is d_f and the ice extent is the uniform
    arrangement's.
    ``uniform`` (the paper's): g_i = d_f. Replica 0 is exactly that; replicas r >= 1 are
    that arrangement perturbed, g_i = d_f + 1e-6 (g_i^random - d_f) (a few nanometres per
    gap at d_f = 5 mm), which the chaotic collisions amplify: an ensemble of the paper's
    arrangement. Replica 0 is the same for every seed, so two uniform ensembles are not
    independent (compare uniform with random, not uniform with uniform). With d_f = 0 or
    two floes nothing can differ: one chain runs (``ModelConfig.n_chains``).
    ``confined`` points run one chain at the uniform arrangement.
    """
    n = cfg.n_floes
    R = cfg.n_chains
    uniform = cfg.L_x / 2.0 + np.arange(n) * (cfg.L_x + cfg.d_f)
    out = np.tile(uniform, (R, 1))
    if cfg.confined or n < 2 or cfg.d_f == 0.0:
        return out
    children = replica_seed_sequence(cfg).spawn(R)
    for r in range(R):
        if cfg.placement == "uniform" and r == 0:
            continue
        u = np.random.Generator(np.random.PCG64(children[r])).random(n - 1)
        e = -np.log1p(-u)
        gaps = (n - 1) * cfg.d_f * (e / e.sum())
        if cfg.placement == "uniform":
            gaps = cfg.d_f + 1e-6 * (gaps - cfg.d_f)
        out[r, 1:] = cfg.L_x / 2.0 + np.arange(1, n) * cfg.L_x + np.cumsum(gaps)
    return out
