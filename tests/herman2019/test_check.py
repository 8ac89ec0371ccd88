"""herman2019.check: each rule's three verdicts on hand-built inputs, the claims on
hand-built tables (with and without the ensemble's *_stderr columns), and ``herman2019
check`` end to end on stores of the shipped paper campaigns computed by a stand-in."""
import json
import math

import numpy as np
import pandas as pd
import pytest

from herman2019.cli import main
from herman2019 import check as pc
from herman2019 import claims, estimates, points
from herman2019.estimates import FAILS, HOLDS, INCONCLUSIVE, Estimate


def E(value, se=0.01, label="p"):
    return Estimate(label, value, se, "replicas" if math.isfinite(se) else "none")


# ---------------------------------------------------------------------- ordering (chain)
def test_ordering_holds_when_every_step_has_the_sign_and_the_ends_differ():
    verdict, evidence = estimates.ordering([E(0.9), E(0.85), E(0.8), E(0.7)], increasing=False)
    assert verdict == HOLDS, evidence
    # a step of the right sign but within its error bar does not stop it
    assert estimates.ordering([E(0.9), E(0.895), E(0.7)], increasing=False)[0] == HOLDS


def test_ordering_fails_on_one_significant_wrong_step():
    verdict, evidence = estimates.ordering([E(0.9), E(0.8), E(0.86), E(0.5)], increasing=False)
    assert verdict == FAILS, evidence
    assert "+7.1, -4.2, +25.5" in evidence


def test_same_order_reads_each_step_at_both_places():
    near = [E(0.988, 0.0001), E(0.9865, 0.0001), E(0.990, 0.0001), E(0.996, 0.0001)]
    # v8's T 1.8 s: the 5 -> 10 mm step falls at both places, the others rise at both
    far = [E(0.854, 0.0002), E(0.844, 0.0005), E(0.918, 0.0006), E(0.975, 0.0003)]
    verdict, evidence = estimates.same_order(near, far)
    assert verdict == HOLDS, evidence
    # T 1.2 s's reversal: rising near the edge, falling far downwave: every step flips
    rev = [E(0.65, 0.001), E(0.57, 0.001), E(0.47, 0.001), E(0.43, 0.001)]
    verdict, evidence = estimates.same_order(near, rev)
    assert verdict == FAILS and "flips" in evidence, evidence
    # one flipped step whose far difference is within its error bar: not a flip
    far2 = [E(0.854, 0.0002), E(0.8545, 0.001), E(0.918, 0.0006), E(0.975, 0.0003)]
    assert estimates.same_order(near, far2)[0] == INCONCLUSIVE
    # ends that do not differ at one place cannot show the same order
    flat = [E(0.9, 0.01)] * 4
    assert estimates.same_order(near, flat)[0] == INCONCLUSIVE


def test_ordering_fails_when_the_ends_are_significantly_reversed():
    # every step slightly wrong (|z| < 2), the ends clearly wrong
    steps = [E(0.80 + 0.015 * i) for i in range(5)]
    verdict, evidence = estimates.ordering(steps, increasing=False)
    assert verdict == FAILS, evidence


def test_ordering_inconclusive_cases():
    # right signs, ends within 2 combined SE
    assert estimates.ordering([E(0.8), E(0.81), E(0.82)], increasing=True)[0] == INCONCLUSIVE
    # ends clear but one step the wrong way (not significantly)
    assert estimates.ordering([E(0.9), E(0.91), E(0.7)], increasing=False)[0] == INCONCLUSIVE
    # no error bar and no floor: never decided, however large the effect
    verdict, evidence = estimates.ordering([E(10.0, math.nan), E(0.0, math.nan)], increasing=False)
    assert verdict == INCONCLUSIVE and "no error bar" in evidence
    # points without a value are left out; one left is not an ordering
    verdict, evidence = estimates.ordering([E(math.nan, label="a"), E(0.5, label="b")],
                                    increasing=True)
    assert verdict == INCONCLUSIVE and "left out (no value): a" in evidence


def test_floor_decides_only_large_effects():
    def floored(values):
        return [Estimate(f"p{i}", v).floored(4.0) for i, v in enumerate(values)]

    assert all(e.source == "floor" and e.se == 4.0 for e in floored([1.0]))
    assert estimates.ordering(floored([30.0, 15.0]), increasing=False)[0] == HOLDS      # z = 2.65
    assert estimates.ordering(floored([30.0, 25.0]), increasing=False)[0] == INCONCLUSIVE  # 0.9
    assert estimates.ordering(floored([15.0, 30.0]), increasing=False)[0] == FAILS
    # a stored SE is kept, not replaced by the floor
    assert E(1.0, 0.5).floored(4.0).se == 0.5


# ---------------------------------------------------------------------- pairs
def test_pairs_three_verdicts_and_stouffer():
    assert estimates.pairs([(E(0.7), E(0.8)), (E(0.6), E(0.75))])[0] == HOLDS
    assert estimates.pairs([(E(0.7), E(0.8)), (E(0.75), E(0.6))])[0] == FAILS
    assert estimates.pairs([(E(0.7), E(0.71))])[0] == INCONCLUSIVE
    # each pair z = 1.5 alone is inconclusive; two independent ones combine to 2.1
    one = (E(0.0, 0.1), E(0.15 * math.sqrt(2), 0.1))
    assert estimates.pairs([one])[0] == INCONCLUSIVE
    verdict, evidence = estimates.pairs([one, one])
    assert verdict == HOLDS and "combined z = +2.1" in evidence
    # significantly wrong in combination although no single pair is
    bad = (one[1], one[0])
    assert estimates.pairs([bad, bad])[0] == FAILS
    assert estimates.pairs([(E(math.nan), E(1.0))])[0] == INCONCLUSIVE


# ---------------------------------------------------------------------- ranges
def test_in_range_three_verdicts():
    assert estimates.in_range([E(1.0, 0.05)], 0.8, 1.25)[0] == HOLDS
    assert estimates.in_range([E(1.5, 0.05)], 0.8, 1.25)[0] == FAILS
    assert estimates.in_range([E(1.2, 0.05)], 0.8, 1.25)[0] == INCONCLUSIVE
    # over several points: one failing point fails the claim, one undecided leaves it open
    assert estimates.in_range([E(1.0, 0.05), E(0.5, 0.05)], 0.8, 1.25)[0] == FAILS
    assert estimates.in_range([E(1.0, 0.05), E(1.2, 0.05)], 0.8, 1.25)[0] == INCONCLUSIVE
    # open-ended and exact values
    assert estimates.in_range([E(5.0, 0.1)], 4.0, math.inf)[0] == HOLDS
    assert estimates.in_range([E(3.0, 0.0)], 3.5, 4.5)[0] == FAILS
    assert estimates.in_range([E(4.0, math.nan)], 3.5, 4.5)[0] == INCONCLUSIVE


def test_z_critical_uses_student_t_for_fitted_errors():
    assert estimates.z_critical(math.inf) == 2.0
    assert estimates.z_critical(2) == pytest.approx(4.53, abs=0.01)
    assert estimates.z_critical(1000) == pytest.approx(2.0, abs=0.01)
    # a fitted SE with 2 degrees of freedom needs |z| >= 4.5
    fitted = Estimate("m", 4.0 + 3.0 * 0.1, 0.1, "fit", 2)
    assert estimates.in_range([fitted], 3.5, 4.3)[0] == INCONCLUSIVE
    assert estimates.in_range([replace_dof(fitted, math.inf)], 4.5, 5.0)[0] == FAILS


def replace_dof(e, dof):
    from dataclasses import replace
    return replace(e, dof=dof)


# ---------------------------------------------------------------------- exponents
def test_power_exponent_weighted_unweighted_and_too_few_periods():
    om = 2 * np.pi / np.array([1.1, 1.2, 1.4, 1.5])
    al = 0.3 * om ** 2.2
    rng = np.random.default_rng(1)
    noisy = al * np.exp(rng.normal(0.0, 0.01, al.size))
    m = estimates.power_exponent(om, noisy, 0.01 * noisy)
    assert m.source == "fit" and abs(m.value - 2.2) < 4 * m.se
    assert m.se == pytest.approx(0.01 / math.sqrt(((np.log(om) - np.log(om).mean()) ** 2)
                                                  .sum()), rel=0.5)
    # without SEs: the residuals' SE, n - 2 degrees of freedom
    u = estimates.power_exponent(om, noisy)
    assert u.dof == 2 and math.isfinite(u.se)
    # SEs too small for the scatter: inflated by sqrt(chi^2/dof) (the Birge ratio); every
    # fit is judged with t_(n-2), whatever chi^2/dof (one critical value per fit size, so a
    # verdict does not jump between z_c 2 and 4.5 with the seed)
    s = estimates.power_exponent(om, noisy, 1e-4 * noisy)
    naive = 1e-4 / math.sqrt(((np.log(om) - np.log(om).mean()) ** 2).sum())
    assert s.dof == 2 and s.se > 5 * naive
    assert m.dof == 2 and estimates.z_critical(m.dof) == pytest.approx(4.53, abs=0.01)
    assert math.isnan(estimates.power_exponent(om[:2], al[:2]).value)
    # NaN and non-positive rates are left out
    assert math.isnan(estimates.power_exponent(om, np.array([1.0, np.nan, -1.0, 2.0])).value)


# ---------------------------------------------------------------------- claims on tables
def _row(h, **kw):
    base = dict(hash=h, status="converged", L_x=0.5, T=1.2, a0=0.0125, C_sd=0.05, eps=0.6,
                d_f=0.005, dispersion="ml", W_c=20.0, compact_zone="edge", compact_end=42.0,
                alpha_all=0.4, alpha_all_resid=1e-3, alpha_edge=1.0, alpha_inner=0.4,
                alpha_exp=0.01, alpha_exp_resid=2e-3, alpha_c=0.4, a_end=0.01, L_sheet=42.0)
    base.update(kw)
    return base


def _fig2(W_c, *, ensemble=True, a_end=None):
    rows = []
    for disp in ("ml", "ep"):
        for i, eps in enumerate((0.2, 0.4, 0.6, 0.8)):
            r = _row(f"{disp}{eps}", eps=eps, dispersion=disp, W_c=W_c[i],
                     a_end=(a_end or [0.011, 0.010, 0.009, 0.008])[i]
                     * (1.0 if disp == "ml" else 1.1),
                     alpha_inner=0.4 * (1.0 + 0.05 * i))
            if ensemble:
                r.update(W_c_stderr=0.5, W_c_n=8, a_end_stderr=2e-5,
                         alpha_inner_stderr=0.01, replicas=8)
            rows.append(r)
    return pd.DataFrame(rows)


#: Every claim of the table (the rows per period of Fig. 6 appear once per stored period).
CLAIMS = {c.claim for c in claims.paper_checks({})}


def _by(checks, claim, campaign=None):
    out = [c for c in checks if c.claim.startswith(claim)
           and (campaign is None or c.campaign == campaign)]
    assert out, claim
    return out


def test_claims_use_the_ensemble_columns():
    checks = claims.paper_checks({"fig2": _fig2([30.0, 25.0, 20.0, 15.0])})
    w = _by(checks, "higher eps -> narrower collisional zone W_c (ml)")[0]
    assert w.verdict == HOLDS, w.evidence
    assert all(e.source == "replicas" and e.se == 0.5 for e in w.estimates)
    assert "n=8" in w.estimates[0].label
    a = _by(checks, "higher eps -> lower a/a0 (ml)")[0]
    assert a.verdict == HOLDS and a.estimates[0].se == pytest.approx(2e-5 / 0.0125)
    assert "R=8" in a.estimates[0].label
    assert _by(checks, "ep attenuates less than ml", "fig2")[0].verdict == HOLDS
    inner = _by(checks, "inner zone attenuates like confined ice (ml)")[0]
    # ratios 1.0, 1.05, 1.1, 1.15 +- 0.025: all inside [0.8, 1.25] by >= 2 SE except 1.15
    assert [round(e.value, 2) for e in inner.estimates] == [1.0, 1.05, 1.1, 1.15]
    assert inner.verdict == HOLDS, inner.evidence


def test_claims_fail_when_the_data_contradict_them():
    checks = claims.paper_checks({"fig2": _fig2([15.0, 20.0, 25.0, 30.0],
                                            a_end=[0.008, 0.009, 0.010, 0.011])})
    assert _by(checks, "higher eps -> narrower collisional zone W_c (ml)")[0].verdict == FAILS
    assert _by(checks, "higher eps -> lower a/a0 (ep)")[0].verdict == FAILS


def test_without_ensemble_columns_the_floors_and_profiles_decide():
    t = _fig2([24.0, 22.0, 20.0, 18.0], ensemble=False)
    prof = {h: {"a_stderr": np.full(84, 1e-5), "a": np.full(84, 0.01),
                "x_mean": np.arange(84) * 0.505 + 0.25,
                "F_w_mean": np.full(84, 100.0),
                "F_d_mean": np.where(np.arange(84) * 0.505 < 20.0, 10.0, 1.0)}
            for h in t["hash"]}
    checks = claims.paper_checks({"fig2": t}, lambda name, h: prof[h])
    w = _by(checks, "higher eps -> narrower collisional zone W_c (ml)")[0]
    assert w.verdict == INCONCLUSIVE and all(e.source == "floor" for e in w.estimates)
    a = _by(checks, "higher eps -> lower a/a0 (ml)")[0]
    assert {e.source for e in a.estimates} == {"profile"} and a.verdict == HOLDS
    inner = _by(checks, "inner zone attenuates like confined ice (ml)")[0]
    assert inner.verdict == INCONCLUSIVE and "(floor)" in pc.format_table([inner])
    force = _by(checks, "Fig. 3: drag about two orders")[0]
    assert [e.value for e in force.estimates] == [2.0] * 4 and force.verdict == HOLDS
    near = _by(checks, "Fig. 3: drag a larger part")[0]
    assert near.verdict == HOLDS, near.evidence          # 1 decade vs 2 decades
    # profiles unavailable: the force claims cannot be decided
    bare = claims.paper_checks({"fig2": t})
    assert _by(bare, "Fig. 3: drag about two orders")[0].verdict == INCONCLUSIVE


def test_fig6a_reversal_and_near_edge():
    rows = []
    for T in (1.2, 1.8):
        for i, d_f in enumerate((0.005, 0.01, 0.02, 0.05)):
            short = T == 1.2
            # near the edge a/a0 grows with d_f at both periods; at the far end it falls
            # with d_f for short waves (the reversal) and grows for long waves
            a_end = (0.010 - 0.001 * i) if short else (0.013 + 0.0005 * i)
            rows.append(_row(f"{T}{d_f}", T=T, d_f=d_f, a0=0.015, a_end=a_end,
                             a_end_stderr=1e-5))
    t = pd.DataFrame(rows)
    prof = {r["hash"]: {"x_mean": np.arange(84) * 0.5, "a_stderr": np.full(84, 1e-5),
                        "a": np.full(84, 0.012 + 0.0005 * (i % 4))}
            for i, r in enumerate(rows)}
    checks = claims.paper_checks({"fig6a": t}, lambda name, h: prof[h])
    near = _by(checks, "smaller d_f attenuates more near the edge", "fig6a")
    assert [c.verdict for c in near] == [HOLDS, HOLDS]
    assert _by(checks, "Fig. 6a reversal")[0].verdict == HOLDS
    assert _by(checks, "Fig. 6a: no reversal")[0].verdict == HOLDS
    # no reversal at the short period: the reversal claim fails, it is not hidden
    t2 = t.copy()
    t2.loc[t2["T"] == 1.2, "a_end"] = [0.010, 0.011, 0.012, 0.013]
    assert _by(claims.paper_checks({"fig6a": t2}, lambda n, h: prof[h]),
               "Fig. 6a reversal")[0].verdict == FAILS


def test_exponents_from_the_periods_table():
    rows = []
    for disp, m in (("ow", 4.0), ("ml", 4.6), ("ep", 2.2)):
        for T in (1.1, 1.2, 1.4, 1.5, 1.6):
            om = 2 * np.pi / T
            rows.append(_row(f"{disp}{T}", T=T, dispersion=disp, alpha_c=1e-3 * om ** m,
                             alpha_inner=1.1e-3 * om ** m, alpha_inner_stderr=1e-5 * om ** m))
    table = pd.DataFrame(rows)
    checks = claims.paper_checks({"periods": table, "periods_fine": table})
    verdicts = {c.claim: c.verdict for c in checks
                if c.campaign in ("periods", "periods_fine")}
    assert set(verdicts.values()) == {HOLDS}, verdicts
    m, mc, diff = [c for c in checks if c.claim.endswith("the same periods (ep)")][0].estimates
    assert m.value == pytest.approx(2.2) and m.source == "fit" and m.dof == 3    # 5 periods
    # alpha_c's exponent over the same periods is exact (no SE); the difference is the
    # weighted fit of alpha_inner / alpha_c (here a constant 1.1: m - m_c = 0)
    assert mc.value == pytest.approx(2.2) and mc.se == 0 and mc.source == "exact"
    assert diff.value == pytest.approx(0.0, abs=1e-9) and diff.dof == 3


def test_missing_tables_are_inconclusive_not_hidden():
    checks = claims.paper_checks({}, missing={"fig2": "no store x.h5"})
    stored = [c for c in checks if c.campaign != "analytic"]    # Fig. 1's tails need none
    assert stored and {c.verdict for c in stored} == {INCONCLUSIVE}
    assert {c.campaign for c in stored} == set(claims.PAPER_CAMPAIGNS)
    assert any("no store x.h5" in c.evidence for c in checks)
    assert "0 hold, 0 fail" in pc.format_table(stored)


def test_table_marks_failures_in_its_count_line():
    c = claims.Check("c", "§4", "fig2", "pts", "q", "range", (E(1.5, 0.05),),
                 *estimates.in_range([E(1.5, 0.05)], 0.8, 1.25))
    table = pc.format_table([c, c])
    assert table.count("| fails |") == 2 and "0 hold, 2 fail (#1, #2)" in table


# ---------------------------------------------------------------------- end to end
@pytest.fixture(scope="module")
def stores(tmp_path_factory):
    """The shipped paper campaigns run with the stand-in fake_point."""
    d = tmp_path_factory.mktemp("paper")
    with pytest.MonkeyPatch.context() as mp:     # a short Fig. 4 trace: not tested here
        mp.setattr("herman2019.traces.PERIODS", 4)
        mp.setattr("herman2019.traces.SPIN_UP", 1)
        assert main(["check", "--stores", str(d), "--run", "--compute",
                     "sweep.testing:fake_point", "--json"]) == 0
    return d


def test_cli_runs_and_checks_the_paper_campaigns(stores, capsys):
    for name in claims.PAPER_CAMPAIGNS:
        assert (stores / f"{name}.h5").exists()
    assert main(["check", "--stores", str(stores), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["problems"] == {} and sum(out["counts"].values()) == len(out["checks"])
    assert {c["claim"] for c in out["checks"]} == CLAIMS
    by = {(c["claim"], c["campaign"]): c for c in out["checks"]}
    # fake_point: W_c = x[N_f // 3] whatever eps -> no difference at all
    w = by["higher eps -> narrower collisional zone W_c (ml)", "fig2"]
    assert w["verdict"] == INCONCLUSIVE and "ends z = +0.0" in w["evidence"]
    # fake_point: alpha doubles for ml; a_stderr = 1 % of a
    assert by["ep attenuates less than ml (all else equal)", "fig2"]["verdict"] == HOLDS
    assert main(["check", "--stores", str(stores)]) == 0
    table = capsys.readouterr().out
    assert table.startswith("| # | claim") and "hold," in table.splitlines()[-1]


@pytest.mark.slow  # fast: tests/sweep/test_report.py::test_an_extra_section_from_outside_and_missing_store
# (a report with a section from outside) and this module's tables
def test_report_adds_the_paper_check_table(stores, tmp_path, capsys):
    """``herman2019 report``: sweep's report of a store with the table as its last section
    (moved from ``sweep report --paper-check``)."""
    out = tmp_path / "r.html"
    empty = tmp_path / "paper"
    empty.mkdir()
    assert main(["report", str(stores / "fig2.h5"), "--out", str(out), "--stores", str(empty),
                 "--max", "1"]) == 0
    html = out.read_text()
    assert ">Paper check</h2>" in html and 'href="#paper-check"' in html
    assert "inconclusive" in html
    assert "no store" in html                       # each missing paper store is named
    assert capsys.readouterr().out == f"herman2019: wrote {out}\n"
    assert main(["report", str(stores / "fig2.h5"), "--out", str(out), "--stores",
                 str(stores), "--max", "1"]) == 0
    assert "| holds |" not in out.read_text() and "<td>holds</td>" in out.read_text()
    assert main(["report", str(tmp_path / "nope.h5"), "--out", str(out), "--stores",
                 str(empty)]) == 3
    assert "no such store" in capsys.readouterr().err


def test_cli_missing_store_exits_3_and_still_prints(stores, tmp_path, capsys):
    import shutil

    for name in ("fig2", "fig5"):
        shutil.copy(stores / f"{name}.h5", tmp_path / f"{name}.h5")
    assert main(["check", "--stores", str(tmp_path)]) == 3
    cap = capsys.readouterr()
    assert "no store" in cap.err and "fig6a" in cap.err
    assert "higher eps -> lower a/a0 (ml)" in cap.out and "not checked" in cap.out


def test_cli_bad_input_exits_2(tmp_path, capsys):
    assert main(["check", "--stores", str(tmp_path / "nowhere")]) == 2
    assert main(["check", "--stores", str(tmp_path), "--run", "--configs",
                 str(tmp_path)]) == 2
    assert "no such campaign file" in capsys.readouterr().err


def test_cli_unreadable_store_exits_3(tmp_path, capsys):
    (tmp_path / "fig2.h5").write_text("not hdf5")
    assert main(["check", "--stores", str(tmp_path)]) == 3
    assert "cannot read" in capsys.readouterr().err


def test_fill_values_are_not_read_as_replica_counts():
    """-1 in replicas / W_c_n is the store's 'unknown' (failed points, older schemas)."""
    row = pd.Series({"replicas": -1, "W_c_n": -1, "W_c": 3.0, "W_c_stderr": np.nan})
    assert math.isnan(points.col(row, "replicas")) and math.isnan(points.col(row, "W_c_n"))
    assert "R=" not in points.label_of(row, "eps", 0.4)
    assert "n=" not in points.w_c(row, "eps=0.4").label


def test_a_partial_fig6a_store_is_not_compared_with_itself():
    t = pd.DataFrame({"L_x": 0.5, "T": [1.2, 1.8, 1.8], "a0": 0.015, "C_sd": 0.05,
                      "eps": 0.6, "d_f": [0.02, 0.005, 0.05], "dispersion": "ml",
                      "status": "converged_noisy", "a_end": [0.01, 0.012, 0.013],
                      "a_end_stderr": 1e-4, "replicas": 8, "L_sheet": 42.0, "W_c": np.nan,
                      "compact_zone": "none", "alpha_inner": np.nan, "alpha_c": 0.4,
                      "alpha_edge": np.nan, "alpha_all": 0.5, "alpha_exp": 0.01,
                      "alpha_all_resid": 0.01, "alpha_exp_resid": 0.02})
    checks = [c for c in claims.paper_checks({"fig6a": t}) if "Fig. 6a" in c.claim
              and "reversal" in c.claim]
    short = [c for c in checks if "1.2" in c.points]
    assert short and short[0].verdict == INCONCLUSIVE
    assert "fewer than 2 points with a value" in short[0].evidence


# ---------------------------------------------------------------------- --seeds
def test_a_verdict_across_seeds_stands_only_where_every_seed_gives_it():
    from herman2019.seeds import SEED_DEPENDENT, across_seeds

    assert across_seeds([HOLDS, HOLDS]) == HOLDS
    assert across_seeds([FAILS, FAILS, FAILS]) == FAILS
    assert across_seeds([FAILS, INCONCLUSIVE]) == SEED_DEPENDENT       # #26 in issue 23
    assert across_seeds([HOLDS, HOLDS, INCONCLUSIVE]) == SEED_DEPENDENT


def test_seeded_campaign_files_differ_only_in_their_seed(tmp_path):
    """The seeds are swept (the last dimension); everything else is the shipped file's,
    and the swept seed 0 points are the shipped campaign's points."""
    from sweep.config import load_campaign
    from herman2019.seeds import seeded_configs

    out = seeded_configs(pc.default_configs(), (0, 7), tmp_path / "c")
    for name in claims.PAPER_CAMPAIGNS:
        old = load_campaign(pc.default_configs() / f"{name}.toml")
        new = load_campaign(out[name])
        assert old.base.seed == 0 and new.base == old.base
        assert new.sweep == {**old.sweep, "seed": (0, 7)} and new.run == old.run
        assert {p.hash for p in old.points()} == {p.hash for p in new.points()
                                                  if p.swept["seed"] == 0}
    bad = tmp_path / "bad"
    bad.mkdir()
    for name in claims.PAPER_CAMPAIGNS:
        (bad / f"{name}.toml").write_text("[base]\n[sweep]\neps = [0.2]\n")
    with pytest.raises(ValueError, match="seed = N"):
        seeded_configs(bad, (1,), tmp_path / "c2")


def test_cli_seeds_runs_the_seeds_swept_into_one_store_per_campaign(tmp_path, capsys,
                                                                   monkeypatch):
    # the Fig. 4 trace's length is not what this test is about (tests of its own: above
    # and in test_paper_claims_new.py)
    monkeypatch.setattr("herman2019.traces.PERIODS", 4)
    monkeypatch.setattr("herman2019.traces.SPIN_UP", 1)
    d = tmp_path / "paper"
    assert main(["check", "--stores", str(d), "--run", "--seeds", "0", "1",
                 "--compute", "sweep.testing:fake_point"]) == 0
    table = capsys.readouterr().out
    from sweep.analysis.load import load
    for name in claims.PAPER_CAMPAIGNS:
        assert set(load(d / f"{name}.h5")["seed"]) == {0, 1}
    lines = table.splitlines()
    assert lines[0].startswith("| # | claim") and "seed 0 | seed 1 | across seeds" in lines[0]
    rows = [ln for ln in lines if ln.startswith("| ") and ln[2].isdigit()]
    assert len(rows) > len(CLAIMS)       # a row per claim and per stored period of Fig. 6
    # fake_point ignores the seed: both seeds give the same verdicts, none seed-dependent
    assert "0 seed-dependent" in lines[-1]
    assert main(["check", "--stores", str(d), "--seeds", "0", "1", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out["seeds"]) == {"0", "1"} and len(out["across_seeds"]) == len(rows)
    assert main(["check", "--stores", str(d), "--seeds", "3", "3"]) == 2
    # a plain check never mixes a settling's seeds: each such store is a problem
    assert main(["check", "--stores", str(d)]) == 3
    assert "holds 2 seeds" in capsys.readouterr().err
