"""What the attenuation iteration hands :func:`floewave.run_point`: an :class:`Iteration`
(how it ended) whose :attr:`Iteration.estimate` is an :class:`Estimate` (what the averaged
windows say), typed from :data:`floewave.outputs.OUTPUTS`."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from .. import outputs

__all__ = ["Estimate", "Iteration", "OF_THE_RUN", "ESTIMATED"]

#: The outputs :func:`floewave.run_point` knows itself (the configuration, the dispersion
#: relation, the iteration's course and the clock); every other one is estimated.
OF_THE_RUN = ("n_floes", "alpha_c", "k", "c_g", "status", "noise", "iterations", "residual",
              "floe_steps", "kernel_mode", "wall_time", "residual_history", "replicas")
#: The outputs of an :class:`Estimate`, in :data:`floewave.outputs.OUTPUTS`' order.
ESTIMATED = tuple(o for o in outputs.OUTPUTS if o.name not in OF_THE_RUN)


def _outputs(self: Any) -> dict[str, Any]:
    """Every field by output name (arrays stay numpy arrays, not copied)."""
    return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}


#: The point's estimates from the averaged windows (:func:`floewave.iteration.estimate
#: .estimate_point`, with the protocol's ``a_stderr``): one field per output of
#: :data:`ESTIMATED`, named, dimensioned and explained in :data:`floewave.outputs.OUTPUTS`.
Estimate = dataclasses.make_dataclass(
    "Estimate", [(o.name, "np.ndarray" if o.dims else o.kind) for o in ESTIMATED],
    namespace={"outputs": _outputs, "__module__": __name__,
               "__doc__": "The point's estimates, one field per output of :data:`ESTIMATED`:\n\n"
               + "\n".join(f"{o.name}: {o.long_name}" for o in ESTIMATED)})


@dataclass
class Iteration:
    """What an attenuation protocol hands :func:`floewave.run_point`.

    status : ``converged``, ``converged_noisy`` or ``not_converged``
        (:data:`floewave.results.STATUSES`).
    estimate : the point's :class:`Estimate`.
    history : the update's residual max_i |a_new - a| / a per iteration (or window).
    noise : the residual's noise floor (0 when ``converged``).
    truncation : windows discarded as transient (the stationary protocol; else None).
    """

    status: str
    estimate: Estimate
    history: list[float]
    noise: float
    truncation: int | None = None
