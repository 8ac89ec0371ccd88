"""Shared harnesses for the physics tests: isolated collisions and free oscillators."""
from __future__ import annotations

import numpy as np

from floewave import ModelConfig
from floewave.model import FloeChain


def collision_config(**kw) -> ModelConfig:
    """Two free lab-ice floes (docs/model.md §7) with no waves, drag, springs or added mass."""
    base = dict(L_x=0.5, L_sheet=1.0, a0=0.0125, C_sd=0.0, k_s=0.0, C_m=0.0, d_f=0.001,
                dispersion="ow")
    base.update(kw)
    return ModelConfig(**base)


def two_floe_collision(cfg: ModelConfig, v_approach: float = 0.05, chunk: int = 50):
    """Collide two floes head-on; return (restitution, KE_after / KE_before, steps in contact).

    Floe 1 moves at +v/2, floe 2 at -v/2; the run goes until the pair has separated
    (gap > 0 and separating) after a contact.
    """
    chain = FloeChain(cfg, 1.0)
    a = np.zeros(2)
    chain.u[:] = [0.5 * v_approach, -0.5 * v_approach]
    ke0 = 0.5 * cfg.mass * float(np.sum(chain.u**2))
    touched = False
    steps_in_contact = 0
    for _ in range(200000):
        chain.run(a, chunk)
        gap = chain.x[1] - chain.x[0] - cfg.L_x
        if gap < 0:
            touched = True
            steps_in_contact += chunk
        elif touched and chain.u[1] - chain.u[0] > 0:
            break
    else:  # pragma: no cover - a failure path
        raise AssertionError("collision did not end")
    e = (chain.u[1] - chain.u[0]) / v_approach
    ke1 = 0.5 * cfg.mass * float(np.sum(chain.u**2))
    return float(e), ke1 / ke0, steps_in_contact
