"""What more floe lengths would buy the surrogate: along L_x alone, from runs already made.

    python benchmarks/surrogate_lx_levels.py

The surrogate's axis sets (results/surrogate/*_axes) ran, at 48 grid nodes of the other
five axes, L_x = 0.6, 0.75, 1.0, 1.25, 2.0, 2.5, 2.75 m. The grid has 0.5, 1.5 and 3.0 there,
and configs/herman2019_lx.toml adds 0.75, 1.0 and 2.0: so at those nodes both readings can
be tried now. Prints the median |q_interp / q_model - 1| at the other values (0.6, 1.25,
2.5, 2.75 m) of the line in log-log through the grid's three levels and through the six
(the three plus the axis sets' own runs at 0.75, 1.0, 2.0), for alpha_all and a_end/a0,
and per value of L_x for alpha_all. Stochastic (8-replica ensembles).
"""
import numpy as np
import pandas as pd

import sweep
g = sweep.load("results/herman2019"); g["a_end_rel"] = g.a_end / g.a0
AX = ["T","a0","C_sd","eps","d_f","dispersion"]
rows = []
for name in ["calibration_axes", "validation_axes"]:
    r = pd.read_csv(f"results/surrogate/{name}/runs.csv.gz"); r = r[r.group == "axis:L_x"]; r["a_end_rel"] = r.a_end / r.a0
    for key, grp in r.groupby(AX):
        sel = np.ones(len(g), bool)
        for a, v in zip(AX, key):
            sel &= (g[a].astype(str) == str(v)) if a == "dispersion" else np.isclose(g[a], v)
        nodes = g[sel][["L_x", "alpha_all", "a_end_rel"]]
        for q in ["alpha_all", "a_end_rel"]:
            n6 = pd.concat([nodes[["L_x", q]], grp[grp.L_x.isin([0.75, 1.0, 2.0])][["L_x", q]]]).sort_values("L_x")
            n3 = nodes[["L_x", q]].sort_values("L_x")
            for _, p in grp[~grp.L_x.isin([0.75, 1.0, 2.0])].iterrows():
                for lab, n in (("3 levels", n3), ("6 levels", n6)):
                    y = np.exp(np.interp(np.log(p.L_x), np.log(n.L_x), np.log(n[q])))
                    rows.append({"q": q, "levels": lab, "L_x": p.L_x, "err": abs(y / p[q] - 1)})
d = pd.DataFrame(rows)
print(d.groupby(["q", "levels"]).err.median().unstack().round(4))
print(d[d.q == "alpha_all"].groupby(["L_x", "levels"]).err.median().unstack().round(3))
