"""tests/data/surrogate_first.npz and its predictions: a small surrogate built, and read
at 300 points, by the first surrogate's code (commit 923a0ed), for
tests/herman2019/test_surrogate.py::test_a_first_surrogate_s_file_predicts_as_its_own_code_did.

    mkdir /tmp/old && git archive 923a0ed herman2019 | tar -x -C /tmp/old
    PYTHONPATH=/tmp/old python tests/data/make_surrogate_first.py tests/data/surrogate_first
"""
import itertools
import math
import sys

import numpy as np
import pandas as pd

from herman2019.surrogate import AXES
from herman2019.surrogate.build import build
from herman2019.surrogate.grid import coordinate
from herman2019.surrogate.model import Surrogate

# that commit's code: no intervals, no missing term
assert not hasattr(Surrogate, "interval_axes"), "run with 923a0ed's herman2019 first on the path"
LEVELS = {"L_x": [0.5, 1.0, 1.5, 3.0], "T": [1.1, 1.4, 2.0], "a0": [0.0125, 0.025],
          "C_sd": [0.005, 0.05, 0.2], "eps": [0.2, 0.5, 0.8], "d_f": [0.005, 0.01, 0.02, 0.05]}
rng = np.random.default_rng(48)
rows = []
for d in ("ml", "ep"):
    for combo in itertools.product(*(LEVELS[a] for a in AXES)):
        p = dict(zip(AXES, combo, strict=True))
        u = {a: float(coordinate(a, p[a])) for a in AXES}
        f = 0.4 * u["T"] ** 2 - 0.3 * u["eps"] + 0.2 * u["L_x"] * u["d_f"] + 0.1 * rng.normal()
        z = p["eps"] >= 0.5 and p["T"] > 1.2
        row = {**p, "dispersion": d, "status": "converged_noisy",
               "compact_zone": "edge" if z else "none"}
        for q in ("alpha_all", "alpha_edge", "a_end_rel"):
            v = math.exp(f + 0.05 * rng.normal())
            row[q], row[q + "_stderr"] = v, 0.02 * v
        if rng.uniform() < 0.05:                 # a node with a value and no SE
            row["alpha_edge_stderr"] = np.nan
        row["W_c"] = 20 * math.exp(f) if z else np.nan
        row["W_c_stderr"] = 0.03 * row["W_c"] if z else np.nan
        rows.append(row)
sur = build(pd.DataFrame(rows))
names = sur.term_names()
for k, q in enumerate(("alpha_all", "alpha_edge", "a_end_rel", "W_c")):
    for j, n in enumerate(names):
        sur.scale[f"{q}:{n}"] = 0.2 + 0.05 * ((3 * k + j) % 7)
    sur.meta.setdefault("combine", {})[q] = (2.0, 4.0, 64.0, 8.0)[k]
sur.meta["p_zone"] = [-0.2, 1.5]
out = sys.argv[1]
sur.save(out + ".npz")
n = 300
q = {a: np.exp(rng.uniform(np.log(LEVELS[a][0]), np.log(LEVELS[a][-1]), n))
     if a in ("L_x", "a0", "C_sd", "d_f") else rng.uniform(LEVELS[a][0], LEVELS[a][-1], n)
     for a in AXES}
disp = rng.choice(["ml", "ep"], n)
pred = sur.predict(disp, detail=True, **q)
np.savez_compressed(out + "_predictions.npz", dispersion=disp.astype("U2"),
                    **{c: pred[c].to_numpy(float) for c in pred.columns if c != "dispersion"})
print(len(pred.columns), "columns;", names)
