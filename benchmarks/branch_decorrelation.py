"""Does a transient paid once decorrelate? Replicas branched from one relaxed parent against
independent ones (issue [cost]'s first lever, measured and not taken).

    python benchmarks/branch_decorrelation.py [--after 16]

For each point (three Fig. 2 points, and grid points with short and long transients): R = 8
independent replicas run the stationary protocol's windows for the transient bound
(:func:`floewave.transient.transient_windows`, B windows) plus ``--after`` more; then one
parent (replica 0's arrangement) runs the same B windows alone and branches into 8 children
(its state copied, positions moved by 1e-9 m of Gaussian noise each), which run ``--after``
windows with their own a(x) updates. Per window statistic (the sheet-mean and far-end
amplitude the window implies, the fraction of compact pairs, the window's W_c) it prints
the children's variance across replicas at lag j after the branch over the independent
replicas' mean variance after the transient (1: decorrelated), and the spread of 4-window
means starting at lag 1, 2, 4 for both. A branched ensemble's error bar is honest only once
the children are decorrelated over the whole averaging span: the lag at which the ratio
reaches about 1 is the transient each child still pays.

Stochastic (chaotic runs): the machine and date belong beside any figure quoted.
"""
import argparse
import json
import time

import numpy as np

from floewave import ModelConfig, march_coefficients
from floewave._march import coefficients, mean_coefficients
from floewave.collision_stats import zone_of
from floewave.dispersion import alpha_confined
from floewave.ensemble import initial_positions
from floewave.iteration.stationary import confined_profile
from floewave.iteration.window import run_window
from floewave.model import FloeChain
from floewave.transient import transient_windows

R = 8


def stats_of(cfg, windows, S, a, c_g, k):
    C = coefficients(S, a)
    implied = march_coefficients(cfg, C, c_g, k)
    zones = [zone_of(cfg, w.x_mean, w.gap_mean) for w in windows]
    comp = np.array([np.mean(np.asarray(w.gap_mean[:-1]) < cfg.gap_threshold) for w in windows])
    wc = np.array([z.W_c for z in zones])
    return C, np.array([implied.mean(axis=1) / cfg.a0, implied[:, -1] / cfg.a0, comp, wc])


def run(cfg, chain, a, nwin, first, c_g, k, Cs, series):
    for it in range(nwin):
        windows, S = run_window(cfg, chain, chain.x0, a, first and it == 0)
        C, s = stats_of(cfg, windows, S, a, c_g, k)
        Cs.append(C)
        series.append(s)
        n = len(Cs)
        lo = n // 2 if n >= 4 else n - 1
        a = march_coefficients(cfg, mean_coefficients(np.array(Cs[lo:])), c_g, k)
    return a


def point(p, B_extra=0, after=16, pert=1e-9):
    cfg = ModelConfig(**p, replicas=R)
    k, c_g = cfg.check_physics()
    alpha_c = alpha_confined(cfg, k, c_g)
    x0s = np.array(initial_positions(cfg))
    B = transient_windows(cfg, k) + B_extra
    # independent replicas
    ch = FloeChain(cfg, k, x0s)
    a = np.tile(confined_profile(cfg, x0s[0] - x0s[0, 0] + 0.5 * cfg.L_x, alpha_c), (R, 1))
    Ci, si = [], []
    t = time.process_time()
    run(cfg, ch, a, B + after, True, c_g, k, Ci, si)
    t_ind = time.process_time() - t
    # parent: replica 0 alone
    cfg1 = cfg.replace(replicas=1)
    par = FloeChain(cfg1, k, x0s[:1])
    a1 = a[:1].copy()
    Cp, sp = [], []
    t = time.process_time()
    a1 = run(cfg1, par, a1, B, True, c_g, k, Cp, sp)
    # branch
    chb = FloeChain(cfg, k, np.tile(x0s[:1], (R, 1)))
    chb.x[:] = par.x; chb.u[:] = par.u; chb.acc[:] = par.acc
    chb.in_contact[:] = par.in_contact; chb.istep = par.istep
    chb._held_drag()[:] = par._held_drag()
    chb._acc_a = np.tile(par._acc_a, (R, 1)); chb._acc_ready = par._acc_ready
    rng = np.random.default_rng(1)
    chb.x += pert * rng.standard_normal(chb.x.shape)
    Cb = [np.tile(c, (R, 1)) for c in Cp]
    sb = []
    run(cfg, chb, np.tile(a1, (R, 1)), after, False, c_g, k, Cb, sb)
    t_br = time.process_time() - t
    si = np.array(si[B:])       # (after, 4, R)
    sb = np.array(sb)
    return cfg, B, si, sb, t_ind, t_br


PTS = [
    dict(eps=0.8, dispersion="ml"), dict(eps=0.4, dispersion="ep"), dict(eps=0.2, dispersion="ml"),
    dict(L_x=0.5, T=1.6, a0=0.015, C_sd=0.005, eps=0.8, d_f=0.05, dispersion="ml"),
    dict(L_x=0.5, T=1.4, a0=0.02, C_sd=0.15, eps=0.4, d_f=0.005, dispersion="ep"),
    dict(L_x=1.5, T=1.4, a0=0.0125, C_sd=0.2, eps=0.2, d_f=0.01, dispersion="ep"),
    dict(L_x=0.5, T=1.2, a0=0.015, C_sd=0.05, eps=0.8, d_f=0.05, dispersion="ow"),
    dict(L_x=3.0, T=1.6, a0=0.02, C_sd=0.005, eps=0.4, d_f=0.01, dispersion="ml"),
]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--after", type=int, default=16)
    ap.add_argument("--json", help="also write the series to this file")
    args = ap.parse_args()
    out = {}
    names = ["amean", "aend", "comp", "Wc"]
    for i, p in enumerate(PTS):
        cfg, B, si, sb, ti, tb = point(p, after=args.after)
        print(f"{p} B={B} windows; CPU independent {ti:.1f} s, parent + children {tb:.1f} s",
              flush=True)
        for s, nm in enumerate(names):
            if not np.any(np.isfinite(si[:, s, :])) or np.nanmax(np.abs(si[:, s, :])) == 0:
                print(f"  {nm:6s} (no values: no compact zone)")
                continue
            vref = float(np.nanmean(np.nanvar(si[:, s, :], axis=1, ddof=1)))
            vb = np.nanvar(sb[:, s, :], axis=1, ddof=1)
            ratio = vb / vref if vref > 0 else vb * 0
            print(f"  {nm:6s} var_ind={vref:.3e} children/independent by lag: "
                  + " ".join(f"{x:.2f}" for x in ratio), flush=True)
            for j0 in (1, 2, 4):
                mb = np.nanmean(sb[j0:j0 + 4, s, :], axis=0)
                mi = np.nanmean(si[j0:j0 + 4, s, :], axis=0)
                print(f"     mean of windows {j0}-{j0 + 3}: sd children "
                      f"{np.nanstd(mb, ddof=1):.3e}, independent {np.nanstd(mi, ddof=1):.3e}")
        out[i] = dict(p=p, B=B, si=si.tolist(), sb=sb.tolist(), ti=ti, tb=tb)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f)


if __name__ == "__main__":
    main()
