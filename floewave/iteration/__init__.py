"""The attenuation iteration (docs/model.md §4, docs/convergence.md): the wave-energy
iteration that finds a(x) on an ensemble of floe chains, in one room.

- :mod:`.window` runs one averaging window on the chains and keeps its statistics;
- the update, eq. 20 marched from the dissipation or self-consistent from its coefficients,
  and the residual, is :mod:`floewave._march` (compiled, so beside the other kernel files);
- :mod:`.stationary` and :mod:`.noise_floor` are the two protocols (``cfg.protocol``);
- :mod:`.estimate` makes the point's estimate of the averaged windows, with its error bars;
- :mod:`.result` types what a protocol hands :func:`floewave.run_point`: an
  :class:`Iteration` whose estimate is an :class:`Estimate`.
"""
from .noise_floor import iterate_noise_floor
from .result import Estimate, Iteration
from .stationary import iterate_stationary

__all__ = ["iterate_stationary", "iterate_noise_floor", "Iteration", "Estimate"]
