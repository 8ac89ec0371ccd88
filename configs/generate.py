"""Regenerate the shipped campaign files from floewave.ModelConfig's defaults.

Every shipped config writes out every model and numerics parameter. When floewave adds
a field (which changes every point hash), run ``python configs/generate.py`` and commit
the result; ``tests/sweep/test_config.py`` fails until then.
"""
from __future__ import annotations

from pathlib import Path

from floewave import SWEPT_FIELDS, ModelConfig

HERE = Path(__file__).resolve().parent
GROUPS = [
    ("geometry and material (docs/model.md §1, §7: LS-WICE-like tank; documented assumptions)",
     ["L_sheet", "h", "L_y", "h_i", "rho_i", "rho_w", "E", "nu", "k_s", "C_m"]),
    ("contact law (§3)", ["contact", "damping", "clip_attraction"]),
    ("ensemble (docs/model.md §4 'Ensembles'; docs/convergence.md 'Ensembles and error bars')",
     ["replicas", "seed", "placement", "coupling"]),
    ("numerics (§3, §4)", []),  # every field not named elsewhere
    ("diagnostics (§6)", ["gap_threshold"]),
]


def _value(v: object) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return f'"{v}"'
    return repr(v)


def render(header: str, sweep: dict, run: str, over: dict | None = None) -> str:
    """The text of one campaign file."""
    defaults = ModelConfig(**(over or {})).to_dict()
    named = {k for _, keys in GROUPS for k in keys} | set(SWEPT_FIELDS)
    lines = [header.strip(), "", "[base]"]
    for title, keys in GROUPS:
        keys = keys or [k for k in defaults if k not in named]
        lines.append(f"# --- {title}")
        lines += [f"{k} = {_value(defaults[k])}" for k in keys]
    lines += ["", "[sweep]", "# the grid is the product of these lists, in this order"]
    lines += [f"{k} = [{', '.join(_value(x) for x in sweep[k])}]" for k in SWEPT_FIELDS]
    lines += ["", "[run]", run.strip(), ""]
    return "\n".join(lines)


CONFIGS = {
    "herman2019": dict(header="""
# The paper's campaign (Herman, Cheng & Shen 2019, §4.1; docs/model.md §7):
# 3 x 7 x 4 x 6 x 4 x 4 x 3 = 24,192 points. Every model and numerics parameter is written
# out with floewave.ModelConfig's default, so this file states the whole configuration.
# Cost: see `sweep plan configs/herman2019.toml`.
""", sweep=dict(L_x=[0.5, 1.5, 3.0], T=[1.1, 1.2, 1.4, 1.5, 1.6, 1.8, 2.0],
                a0=[0.0125, 0.015, 0.02, 0.025], C_sd=[0.005, 0.01, 0.05, 0.1, 0.15, 0.2],
                eps=[0.2, 0.4, 0.6, 0.8], d_f=[0.005, 0.010, 0.020, 0.050],
                dispersion=["ep", "ow", "ml"]),
        run='name = "herman2019"\ndescription = "Herman, Cheng & Shen (2019) full parameter'
            ' grid"\nprogress_interval = 300.0\ngrace_period = 240.0'),
    "herman2019_lx": dict(header="""
# The paper's grid at three more floe lengths (issue 48: the surrogate between the grid's
# nodes is limited by L_x's three levels): L_x 0.75, 1.0 and 2.0 m with every other list
# of configs/herman2019.toml, 3 x 7 x 4 x 6 x 4 x 4 x 3 = 24,192 points, so that with it
# L_x has six levels (0.5, 0.75, 1.0, 1.5, 2.0, 3.0). Every other parameter as there.
# Cost: see `sweep plan configs/herman2019_lx.toml`.
""", sweep=dict(L_x=[0.75, 1.0, 2.0], T=[1.1, 1.2, 1.4, 1.5, 1.6, 1.8, 2.0],
                a0=[0.0125, 0.015, 0.02, 0.025], C_sd=[0.005, 0.01, 0.05, 0.1, 0.15, 0.2],
                eps=[0.2, 0.4, 0.6, 0.8], d_f=[0.005, 0.010, 0.020, 0.050],
                dispersion=["ep", "ow", "ml"]),
        run='name = "herman2019_lx"\ndescription = "Herman, Cheng & Shen (2019) grid at'
            ' three more floe lengths"\nprogress_interval = 300.0\ngrace_period = 240.0'),
    "demo": dict(header="""
# A small demonstration campaign: 16 points with reduced numerics (n0 = 2, nT = 2,
# max_iterations = 30, n_average = 8, ensembles of 4 replicas without the W_c precision
# target). `mpiexec -n 3 sweep run configs/demo.toml --store demo.h5` (one master, two
# workers on 2 cores): timing in the README (`python benchmarks/docs_numbers.py`).
# Results are noisier than with the default numerics; use it to try the workflow, not for
# science.
""", sweep=dict(L_x=[0.5, 1.5], T=[1.2, 1.6], a0=[0.0125], C_sd=[0.05], eps=[0.2, 0.6],
                d_f=[0.005], dispersion=["ml", "ep"]),
        run='name = "demo"\ndescription = "16-point demonstration with reduced numerics"\n'
            'progress_interval = 10.0\ngrace_period = 30.0',
        over=dict(n0=2, nT=2, max_iterations=30, n_average=8, replicas=4,
                  target_W_c_stderr=0.0)),
    "fig2": dict(header="""
# Paper Fig. 2: a/a0 for L_x = 0.5 m, T = 1.2 s, a0 = 0.0125 m, d_f = 0.005 m, C_sd = 0.05,
# eps = 0.2, 0.4, 0.6, 0.8, with 'ML' (a) and 'EP' (b) dispersion. 8 points.
""", sweep=dict(L_x=[0.5], T=[1.2], a0=[0.0125], C_sd=[0.05], eps=[0.2, 0.4, 0.6, 0.8],
                d_f=[0.005], dispersion=["ml", "ep"]),
        run='name = "fig2"\ndescription = "Herman et al. 2019 Fig. 2: restitution'
            ' coefficient, ML and EP"'),
    "fig5": dict(header="""
# Paper Fig. 5: a/a0 for floe sizes L_x = 0.5, 1.5, 3.0 m, T = 1.4 s, a0 = 0.015 m,
# d_f = 0.005 m, C_sd = 0.05, eps = 0.6, 'EP' (continuous) and 'ML' (dashed). 6 points.
""", sweep=dict(L_x=[0.5, 1.5, 3.0], T=[1.4], a0=[0.015], C_sd=[0.05], eps=[0.6],
                d_f=[0.005], dispersion=["ep", "ml"]),
        run='name = "fig5"\ndescription = "Herman et al. 2019 Fig. 5: floe size, EP and ML"'),
    "fig6a": dict(header="""
# Paper Fig. 6a: a/a0 for floe-floe distances d_f = 0.005, 0.01, 0.02, 0.05 m (the
# campaign's values), L_x = 0.5 m, a0 = 0.015 m, C_sd = 0.05, eps = 0.6, two wave periods.
# The caption does not name the periods or the dispersion relation: the text names
# T = 1.8 s for the long waves; T = 1.2 s (Figs. 2-4) is assumed for the short ones and
# 'ML' (Figs. 2a-4) for the dispersion. 8 points.
""", sweep=dict(L_x=[0.5], T=[1.2, 1.8], a0=[0.015], C_sd=[0.05], eps=[0.6],
                d_f=[0.005, 0.010, 0.020, 0.050], dispersion=["ml"]),
        run='name = "fig6a"\ndescription = "Herman et al. 2019 Fig. 6a: floe-floe distance,'
            ' two periods"'),
    "dfscan": dict(header="""
# The d_f scan at T = 1.8 s (issue 23; docs/dfscan.md): the Fig. 6a setting (L_x = 0.5 m,
# a0 = 0.015 m, C_sd = 0.05, eps = 0.6, 'ML') at nine floe-floe distances d_f = 2 ... 50 mm,
# to see where the paper's "smaller d_f attenuates more near the edge" holds. 9 points.
""", sweep=dict(L_x=[0.5], T=[1.8], a0=[0.015], C_sd=[0.05], eps=[0.6],
                d_f=[0.002, 0.003, 0.005, 0.0075, 0.01, 0.015, 0.02, 0.03, 0.05],
                dispersion=["ml"]),
        run='name = "dfscan"\ndescription = "d_f scan at T = 1.8 s, Fig. 6a setting'
            ' (sweep.paper.dfscan)"'),
    "fig6b": dict(header="""
# Paper Fig. 6b: a/a0 for incident amplitudes a0 = 0.0125, 0.015, 0.02, 0.025 m (the
# campaign's values), L_x = 0.5 m, d_f = 0.005 m, C_sd = 0.05, eps = 0.6, two wave periods.
# As for Fig. 6a: T = 1.8 s from the text, T = 1.2 s and 'ML' dispersion assumed. 8 points.
""", sweep=dict(L_x=[0.5], T=[1.2, 1.8], a0=[0.0125, 0.015, 0.02, 0.025], C_sd=[0.05],
                eps=[0.6], d_f=[0.005], dispersion=["ml"]),
        run='name = "fig6b"\ndescription = "Herman et al. 2019 Fig. 6b: incident amplitude,'
            ' two periods"'),
    "periods": dict(header="""
# alpha(omega): every campaign period T = 1.1 ... 2.0 s for the three dispersion relations at
# the Fig. 2 setup (L_x = 0.5 m, a0 = 0.0125 m, d_f = 0.005 m, C_sd = 0.05) with eps = 0.6.
# 21 points. `sweep figures` draws alpha(omega) with the fitted exponents m
# (alpha_omega.png); `sweep.alpha_omega(sweep.load(store))` gives them as a table.
""", sweep=dict(L_x=[0.5], T=[1.1, 1.2, 1.4, 1.5, 1.6, 1.8, 2.0], a0=[0.0125], C_sd=[0.05],
                eps=[0.6], d_f=[0.005], dispersion=["ep", "ow", "ml"]),
        run='name = "periods"\ndescription = "alpha(omega) across the campaign periods, EP,'
            ' OW and ML"'),
    "periods_fine": dict(header="""
# alpha(omega) of the DEM's compact zone (paper §5): the periods of configs/periods.toml
# that have a compact zone (T 1.1-1.5 s) resolved into ten, so that the exponent of
# alpha_inner has 8 degrees of freedom instead of 2 (issue 23). T/dt is a multiple of
# drag_every (4): T in steps of 0.04 s. eps 0.6, EP, OW and ML. 30 points.
""", sweep=dict(L_x=[0.5], T=[1.1, 1.16, 1.2, 1.24, 1.28, 1.32, 1.36, 1.4, 1.44, 1.5],
                a0=[0.0125], C_sd=[0.05], eps=[0.6], d_f=[0.005],
                dispersion=["ep", "ow", "ml"]),
        run='name = "periods_fine"\ndescription = "alpha(omega) over ten periods with a'
            ' compact zone, EP, OW and ML"'),
    "uniform": dict(header="""
# Paper §4.1: "tests with random initial locations of the floes have shown that this aspect
# of the setup has no influence on the results". The Fig. 2 points (configs/fig2.toml) with
# the paper's uniform initial placement (replicas perturbed by nanometres) instead of random
# arrangements; `sweep paper-check` compares the two. 8 points.
""", sweep=dict(L_x=[0.5], T=[1.2], a0=[0.0125], C_sd=[0.05], eps=[0.2, 0.4, 0.6, 0.8],
                d_f=[0.005], dispersion=["ml", "ep"]),
        run='name = "uniform"\ndescription = "Fig. 2 points with the paper\'s uniform initial'
            ' placement"', over=dict(placement="uniform")),
    "spring_none": dict(header="""
# Paper §4.1-4.2: the edge spring (k_s, on floes 1 and N_f) keeps the ice edge in place;
# "without that force, the floes drift gradually in the upwave direction". The Fig. 2 point
# ML eps 0.6 with k_s = 0. 1 point.
""", sweep=dict(L_x=[0.5], T=[1.2], a0=[0.0125], C_sd=[0.05], eps=[0.6], d_f=[0.005],
                dispersion=["ml"]),
        run='name = "spring_none"\ndescription = "Fig. 2 ML eps 0.6 without the edge spring"',
        over=dict(k_s=0.0)),
    "spring_soft": dict(header="""
# Paper §4.1: "the value of k_s doesn't have visible results on the simulated attenuation".
# The Fig. 2 point ML eps 0.6 with k_s / 10. 1 point.
""", sweep=dict(L_x=[0.5], T=[1.2], a0=[0.0125], C_sd=[0.05], eps=[0.6], d_f=[0.005],
                dispersion=["ml"]),
        run='name = "spring_soft"\ndescription = "Fig. 2 ML eps 0.6 with k_s / 10"',
        over=dict(k_s=9.0e3)),
    "spring_stiff": dict(header="""
# Paper §4.1: "the value of k_s doesn't have visible results on the simulated attenuation".
# The Fig. 2 point ML eps 0.6 with k_s x 10. 1 point.
""", sweep=dict(L_x=[0.5], T=[1.2], a0=[0.0125], C_sd=[0.05], eps=[0.6], d_f=[0.005],
                dispersion=["ml"]),
        run='name = "spring_stiff"\ndescription = "Fig. 2 ML eps 0.6 with k_s x 10"',
        over=dict(k_s=9.0e5)),
}


def main() -> None:
    """Write every shipped config."""
    for name, spec in CONFIGS.items():
        (HERE / f"{name}.toml").write_text(render(**spec), encoding="utf-8")


if __name__ == "__main__":
    main()
