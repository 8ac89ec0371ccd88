"""``herman2019 check --settle``: the group-sequential rule (its false-verdict rate
measured on simulated looks where the truth is known), the pooling of seeds, and the
command."""
from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from herman2019.cli import main
from herman2019 import claims, pooling, sequential, settle
from herman2019.estimates import FAILS, HOLDS, INCONCLUSIVE, Estimate, critical, in_range
from herman2019.estimates import observing, pairs
from herman2019.points import Check
from tests.herman2019.test_check import _fig2 as fig2_table

FRACTIONS = (1 / 8, 1 / 4, 1 / 2, 1.0)
DATA = Path(__file__).resolve().parents[1] / "data"


# ---------------------------------------------------------------------- the boundaries
@pytest.mark.parametrize("kind", [sequential.POCOCK, sequential.OBRIEN_FLEMING])
def test_boundaries_spend_exactly_alpha(kind):
    c = sequential.boundaries(FRACTIONS, kind=kind)
    assert sequential.crossing_rate(FRACTIONS, c) == pytest.approx(sequential.ALPHA, rel=1e-6)
    # the first look spends alpha(1/8) alone: its boundary is the normal quantile of that
    from scipy.stats import norm
    assert c[0] == pytest.approx(norm.isf(sequential.spent(FRACTIONS[0], kind=kind)))
    if kind == sequential.POCOCK:
        assert all(2.0 < x < 2.7 for x in c) and list(c) == sorted(c, reverse=True)
    else:                                   # strict early, about z_(alpha) at the end
        assert c[0] > 5 and c[-1] == pytest.approx(2.0, abs=0.02)


def test_looking_again_at_two_inflates_the_rate():
    naive = sequential.crossing_rate(FRACTIONS, [2.0] * 4)
    assert 0.06 < naive < 0.07                      # about 2.9 times the one-look rate
    assert sequential.crossing_rate([1.0], [2.0]) == pytest.approx(sequential.ALPHA)


@pytest.mark.parametrize("fractions", [FRACTIONS, (1 / 16, 1 / 8, 1 / 4, 1 / 2, 1.0)])
def test_boundaries_checked_by_simulated_brownian_looks(fractions):
    """An independent check of the integration: Brownian paths simulated directly."""
    rng = np.random.default_rng(20261203)
    n = 200_000
    steps = rng.standard_normal((n, len(fractions))) * np.sqrt(np.diff((0.0, *fractions)))
    z = np.cumsum(steps, axis=1) / np.sqrt(fractions)
    for kind in (sequential.POCOCK, sequential.OBRIEN_FLEMING):
        c = np.array(sequential.boundaries(fractions, kind=kind))
        alive = np.ones(n, bool)
        up = np.zeros(n, bool)
        for k in range(len(fractions)):
            hit, low = alive & (z[:, k] >= c[k]), alive & (z[:, k] <= -c[k])
            up |= hit
            alive &= ~(hit | low)
        se = math.sqrt(sequential.ALPHA * (1 - sequential.ALPHA) / n)
        assert abs(up.mean() - sequential.ALPHA) < 4 * se, (kind, up.mean())


def test_bad_looks_are_refused():
    for fr in ((0.5, 0.25, 1.0), (0.5,), (0.0, 1.0)):
        with pytest.raises(ValueError):
            sequential.boundaries(fr)
    with pytest.raises(ValueError):
        sequential.spent(0.5, kind="linear")


# ---------------------------------------------------------------------- pooling
def test_pool_stated_errors_floors_exact_and_missing():
    p = pooling.pool([Estimate("x", 1.0, 0.3, "replicas"), Estimate("x", 2.0, 0.4,
                                                                   "replicas")])
    assert (p.value, p.se, p.source) == (1.5, pytest.approx(0.25), "replicas")
    assert math.isinf(p.dof)
    # one seed shares 1 of 8 replicas with the others: variance x (1 + (S - 1) / 8)
    q = pooling.pool([Estimate("x", 1.0, 0.3, "replicas")] * 4, shared=1 / 8)
    assert q.se == pytest.approx(0.3 / 2 * math.sqrt(1 + 3 / 8))
    fl = [Estimate("f", v, 0.02, "floor") for v in (0.10, 0.12)]
    assert pooling.pool(fl).se == pytest.approx(0.02 / math.sqrt(2))   # too few: the floor
    fl4 = [Estimate("f", v, 0.02, "floor") for v in (0.10, 0.12, 0.11, 0.13)]
    p4 = pooling.pool(fl4)                          # four: the seeds' own spread
    assert (p4.source, p4.dof) == ("seeds", 3.0)
    assert p4.se == pytest.approx(np.std([0.10, 0.12, 0.11, 0.13], ddof=1) / 2)
    ex = pooling.pool([Estimate("m", 4.0, 0.0, "exact")] * 3)
    assert (ex.value, ex.se, ex.source) == (4.0, 0.0, "exact")
    mixed = pooling.pool([Estimate("w", math.nan), Estimate("w n=8", 20.0, 1.0, "replicas")])
    assert (mixed.value, mixed.se) == (20.0, 1.0)
    fits = pooling.pool([Estimate("m", 3.0, 0.1, "fit", 2.0), Estimate("m", 3.2, 0.1, "fit",
                                                                       2.0)])
    assert fits.dof == pytest.approx(4.0)          # Welch-Satterthwaite of equal SEs
    # the audit's factor widens the stated SE before the spread is compared with it
    four = [Estimate("x", v, 0.01, "replicas") for v in (1.0, 1.1, 0.9, 1.0)]
    spread = np.std([1.0, 1.1, 0.9, 1.0], ddof=1) / 2
    assert pooling.pool(four).se == pytest.approx(spread)              # spread > 0.005
    assert pooling.pool(four, widen=20.0).se == pytest.approx(0.1)     # 20 x 0.005 > spread
    # seeds sharing a replica: their spread shrinks by 1 - rho, their mean's variance grows
    assert pooling.pool(four, shared=1 / 8).se == pytest.approx(
        spread * math.sqrt((1 + 3 / 8) / (1 - 1 / 8)))


def test_seeds_align_whatever_their_counts_of_replicas_with_a_value():
    assert pooling._base("eps=0.2 n=8") == pooling._base("eps=0.2 n=0 (marginal zone)")
    assert pooling._base("eps=0.2 n=8") != pooling._base("eps=0.4 n=8")
    a = Check("c", "s", "periods_fine", "T 1.1-1.5 s: 10 with a value", "q", "r", (), "x", "")
    b = Check("c", "s", "periods_fine", "T 1.1-1.5 s: 9 with a value", "q", "r", (), "x", "")
    assert pooling._key(a) == pooling._key(b)


def _fig2(shift):
    t = fig2_table([30.0, 25.0, 20.0, 15.0])
    t["W_c"] = t["W_c"] + shift
    return t


def test_pooled_checks_read_the_seeds_mean_and_its_error():
    recs = []
    for shift in (0.0, 1.0):
        rec = pooling.Recorder()
        with observing(rec):
            claims.paper_checks({"fig2": _fig2(shift)}, trace=False)
        recs.append(rec)
    assert len(recs[0].groups) == len(recs[1].groups) > 30
    pooler = pooling.Pooler(recs)
    with observing(pooler), critical(2.5):
        pooled = claims.paper_checks({"fig2": _fig2(0.0)}, trace=False)
    w = next(c for c in pooled if c.claim.startswith("higher eps -> narrower") and "(ml)"
             in c.claim)
    assert [e.value for e in w.estimates] == [30.5, 25.5, 20.5, 15.5]
    assert all(e.se == pytest.approx(0.5 / math.sqrt(2)) for e in w.estimates)
    assert "z_c 2.5" in w.evidence and w.verdict == HOLDS
    assert pooler.used[0] == 2 and len(pooler.used) == len(pooled)
    # a seed whose table lacks the campaign is left out of those rows, not misaligned
    rec = pooling.Recorder()
    with observing(rec):
        claims.paper_checks({}, trace=False)
    pooler = pooling.Pooler([recs[0], rec])
    with observing(pooler):
        again = claims.paper_checks({"fig2": _fig2(0.0)}, trace=False)
    on_fig2 = [u for u, c in zip(pooler.used, recs[0].campaigns, strict=True) if "fig2" in c]
    assert on_fig2 and set(on_fig2) == {1}
    assert [c.verdict for c in again] == [c.verdict for c in claims.paper_checks(
        {"fig2": _fig2(0.0)}, trace=False)]


def test_shared_replica_campaigns_are_the_uniform_placement_ones():
    configs = Path(__file__).resolve().parents[2] / "configs"
    uniform = {}
    for name in claims.PAPER_CAMPAIGNS:
        base = tomllib.loads((configs / f"{name}.toml").read_text())["base"]
        if base["placement"] == "uniform":
            uniform[name] = base["replicas"]
    assert uniform == pooling.SHARED_REPLICA0


# ---------------------------------------------------------------------- the rule's error rate
LOOKS = settle.looks_for(64)                       # 4, 8, 16, 32, 64 seeds


def _settle_draws(mu, sigma, *, draws, rng, zs=None, rule="range", hi=1.0, stated=None):
    """The sequential verdicts of ``draws`` simulated claims: each seed's estimate
    N(mu, sigma) with its stated SE ``stated`` (default sigma), pooled at the looks of
    ``settle.looks_for(64)`` and read against ``zs`` (default: the Pocock boundaries);
    "range": value in [-inf, hi]; "pair": b > a with a ~ N(0, sigma)."""
    zs = zs or sequential.boundaries([n / LOOKS[-1] for n in LOOKS])
    stated = sigma if stated is None else stated
    out = []
    for _ in range(draws):
        x = rng.normal(mu, sigma, LOOKS[-1])
        y = rng.normal(0.0, sigma, LOOKS[-1])
        verdict = INCONCLUSIVE
        for n, z in zip(LOOKS, zs, strict=True):
            est = pooling.pool([Estimate("x", v, stated, "replicas") for v in x[:n]])
            with critical(z):
                if rule == "range":
                    verdict = in_range([est], -math.inf, hi)[0]
                else:
                    ref = pooling.pool([Estimate("y", v, stated, "replicas") for v in y[:n]])
                    verdict = pairs([(ref, est)])[0]
            if verdict != INCONCLUSIVE:
                break
        out.append(verdict)
    return np.array(out)


@pytest.mark.parametrize("rule", [
    "range",
    # slow tier (fast: "range", the same sequential reading and boundaries on a range rule)
    pytest.param("pair", marks=pytest.mark.slow)])
def test_sequential_false_verdict_rate_on_synthetic_claims(rule):
    """The truth on the claim's bound (range: mu = hi; pair: no difference): "holds" and
    "fails" are both false verdicts. The looks keep each at most alpha (the seeds'
    spread, used where it exceeds the stated SE, makes the rule a little conservative);
    reading every look at 2 does not."""
    rng = np.random.default_rng(7 if rule == "range" else 8)
    draws = 3000
    mu = 1.0 if rule == "range" else 0.0
    se = math.sqrt(sequential.ALPHA * (1 - sequential.ALPHA) / draws)
    v = _settle_draws(mu, 0.1, draws=draws, rng=rng, rule=rule)
    for wrong in (HOLDS, FAILS):
        rate = np.mean(v == wrong)
        assert sequential.ALPHA / 3 < rate < sequential.ALPHA + 4 * se, (wrong, rate)
    naive = _settle_draws(mu, 0.1, draws=draws, rng=rng, rule=rule, zs=[2.0] * len(LOOKS))
    assert np.mean(naive == HOLDS) > sequential.ALPHA + 6 * se


def test_too_small_error_bars_are_caught_by_the_seeds_spread(monkeypatch):
    draws = 3000
    se = math.sqrt(sequential.ALPHA * (1 - sequential.ALPHA) / draws)
    # stated SEs 1.6 times too small: the spread keeps the false "holds" at alpha ...
    v = _settle_draws(1.0, 0.16, draws=draws, rng=np.random.default_rng(11), stated=0.1)
    assert np.mean(v == HOLDS) < sequential.ALPHA + 4 * se
    # ... which the stated SEs alone would not (16.6 % with this draw, 7 times alpha)
    monkeypatch.setattr(pooling, "EMPIRICAL_MIN", 10 ** 9)
    v = _settle_draws(1.0, 0.16, draws=draws, rng=np.random.default_rng(11), stated=0.1)
    assert np.mean(v == HOLDS) > 4 * sequential.ALPHA


def test_sequential_rule_decides_a_real_effect():
    rng = np.random.default_rng(9)
    # an effect of one seed's SE: 8 SE at 64 seeds, decided (the right way) by then
    v = _settle_draws(1.0 - 0.1, 0.1, draws=500, rng=rng)
    assert np.mean(v == HOLDS) > 0.97 and np.mean(v == FAILS) < 0.01


# ---------------------------------------------------------------------- the command
@pytest.mark.slow  # 88 campaign runs of fake_point (56 s); fast: the bad-input tests
def test_cli_settle_runs_the_looks_and_reports(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("herman2019.traces.PERIODS", 4)
    monkeypatch.setattr("herman2019.traces.SPIN_UP", 1)
    d = tmp_path / "paper"
    assert main(["check", "--stores", str(d), "--run", "--settle", "--max-seeds", "8",
                 "--compute", "sweep.testing:fake_point", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["looks"] == [4, 8] and len(out["boundaries"]) == 2
    assert sum(out["counts"].values()) == len(out["rows"])
    from sweep.analysis.load import load
    for name in claims.PAPER_CAMPAIGNS:     # one store per campaign, its seeds swept
        assert {0, 1, 2, 3} <= set(load(d / f"{name}.h5")["seed"])
    # the second look ran only the campaigns of rows still open after the first
    second = [r for r in out["runs"] if max(r["seeds"]) >= 4]
    open_after_1 = {n for r in out["rows"] if r["look"] == 2 and r["extendable"]
                    for n in pooling.campaigns_of(_check(r))}
    assert {n for r in second for n in r["campaigns"]} <= open_after_1 | set()
    assert out["cost"]["points_added"] == sum(r["points"] for r in out["runs"]) > 0
    # resumed: nothing is recomputed, the same table
    assert main(["check", "--stores", str(d), "--run", "--settle", "--max-seeds", "8",
                 "--compute", "sweep.testing:fake_point", "--json"]) == 0
    again = json.loads(capsys.readouterr().out)
    assert again["cost"]["points_added"] == 0
    assert [r["verdict"] for r in again["rows"]] == [r["verdict"] for r in out["rows"]]
    assert main(["check", "--stores", str(d), "--settle", "--max-seeds", "8"]) == 0
    table = capsys.readouterr().out
    assert "| seeds (look) |" in table and "this run added 0 points" in table
    # a budget beyond the stored seeds, without --run: no row is read past the seeds it
    # has (seed 8 and up missing), and the audit runs on what is there
    assert main(["check", "--stores", str(d), "--settle", "--max-seeds", "16",
                 "--json"]) == 0
    wide = json.loads(capsys.readouterr().out)
    assert all(r["look"] <= 2 and r["seeds"] <= 8 for r in wide["rows"])
    assert all(r["audited_look"] <= 2 for r in wide["rows"])


def _check(row):
    return Check(row["claim"], row["source"], row["campaign"], row["points"],
                        row["quantity"], row["rule"], (), row["verdict"], row["evidence"])


@pytest.mark.parametrize("argv, message", [
    (["--settle", "--max-seeds", "12"], "--max-seeds 12: 4 times a power of 2"),
    (["--settle", "--seeds", "0", "1"], "--settle and --seeds: give one"),
    (["--max-seeds", "8"], "--max-seeds 8: only with --settle"),
    (["--first-seed", "64"], "--first-seed 64: only with --settle"),
    (["--settle", "--first-seed", "-1"], "--first-seed -1: a seed is >= 0"),
    (["--settle", "--run", "--jobs", "0"], "--jobs 0: at least 1"),
    (["--settle", "--jobs", "2"], "--jobs: only with --run"),
    (["--jobs", "2"], "--jobs 2: only with --settle"),
    (["--floor", "0.01"], "--floor 0.01: only with --settle"),
    (["--settle", "--floor", "0"], "--floor 0.0: a fraction of a0 in (0, 1)"),
    (["--settle", "--run", "--first-seed", str(2 ** 63 - 10)], "must lie in 0 to"),
    (["--settle", "--run", "--configs", "nowhere"], "no such campaign file")])
def test_cli_settle_bad_input_exits_2_and_writes_nothing(tmp_path, capsys, argv, message):
    d = tmp_path / "paper"
    assert main(["check", "--stores", str(d), *argv]) == 2
    assert message in capsys.readouterr().err
    assert not d.exists()

def test_widening_finds_too_small_error_bars_and_the_pooler_applies_it():
    rng = np.random.default_rng(3)
    recs = []
    for _ in range(16):                      # stated SE 0.5, true scatter 1.5 (3x)
        rec = pooling.Recorder()
        shift = float(rng.normal(0.0, 1.5))
        with observing(rec):
            claims.paper_checks({"fig2": _fig2(shift)}, trace=False)
        recs.append(rec)
    widen = pooling.widening(range(16), dict(enumerate(recs)))
    w_rows = [k for k in widen if k[0][0].startswith("higher eps -> narrower") and
              "(ml)" in k[0][0]]
    assert w_rows and all(1.8 < widen[k] < 4.5 for k in w_rows)   # ~3 (chi2, 15 dof)
    assert pooling.widening(range(4), dict(enumerate(recs))) == {}  # too few seeds
    pooler = pooling.Pooler(recs, widen)
    with observing(pooler):
        pooled = claims.paper_checks({"fig2": _fig2(0.0)}, trace=False)
    w = next(c for c in pooled if c.claim.startswith("higher eps -> narrower") and "(ml)"
             in c.claim)
    plain = 0.5 / 4                          # sqrt(16 x 0.5^2) / 16, unwidened
    assert all(1.8 * plain < e.se < 4.5 * plain for e in w.estimates)
    # a factor the spread does not reach: the SE is exactly the widened stated one
    big = {k: 40.0 for k in widen}
    pooler = pooling.Pooler(recs, big)
    with observing(pooler):
        pooled = claims.paper_checks({"fig2": _fig2(0.0)}, trace=False)
    w = next(c for c in pooled if c.claim.startswith("higher eps -> narrower") and "(ml)"
             in c.claim)
    assert all(e.se == pytest.approx(40.0 * plain) for e in w.estimates)


# ---------------------------------------------------------------------- resolution floor
def _chain(values, se, quantity="a/a0 at x = 5 m", verdict=INCONCLUSIVE, dof=63.0):
    ses = se if isinstance(se, (list, tuple)) else [se] * len(values)
    est = tuple(Estimate(f"d_f={i}", v, e, "seeds", dof) for i, (v, e) in
                enumerate(zip(values, ses, strict=True)))
    return Check("smaller d_f attenuates more near the edge", "§4.2", "fig6a", "T 1.2 s",
                 quantity, "chain, increasing in d_f", est, verdict, "")


def test_resolution_floor_stops_a_chain_whose_open_step_is_below_it():
    c = 2.5
    # the open step: -0.0008 +- 0.00085 (|z| ~ 0.9): |d| + z_c se ~ 0.003 < 0.01
    flat = _chain([0.50, 0.4992, 0.55, 0.60], 0.0006)
    assert [round(d, 6) for d, *_ in settle.open_steps(flat, c)] == [-0.0008]
    assert settle.below_floor(flat, c)
    assert not settle.below_floor(flat, c, floor=0.002)       # the floor is a parameter
    # the same step, its SE 5x: |d| + z_c se ~ 0.011 > 0.01: more seeds may still show it
    wide = _chain([0.50, 0.4992, 0.55, 0.60], 0.003)
    assert settle.open_steps(wide, c) and not settle.below_floor(wide, c)
    # a step of 0.9 % of a0, open (z = -2.1 < 2.5), not resolved below the 1 % floor
    near = _chain([0.50, 0.491, 0.55, 0.60], 0.003)
    (d, se, *_), = settle.open_steps(near, c)
    assert abs(d / se) < c and not settle.below_floor(near, c)
    # Student-t: with 3 dof the rule reads z_c ~ 12 at the first look's c = 3.24, so the
    # step's interval (0.0008 + 12 x 0.00085) is not inside the floor, though
    # 0.0008 + 3.24 x 0.00085 is
    t3 = _chain([0.50, 0.4992, 0.55, 0.60], 0.0006, dof=3.0)
    zc = settle.open_steps(t3, 3.24)[0][4]
    assert 10 < zc < 14 and not settle.below_floor(t3, 3.24)
    assert settle.below_floor(_chain([0.50, 0.4992, 0.55, 0.60], 0.0006, dof=math.inf), 3.24)
    # a point without an SE: its steps are open and never inside the floor
    gap = _chain([0.50, 0.4992, 0.55, 0.60], [0.0006, math.nan, 0.0006, 0.0006])
    assert len(settle.open_steps(gap, c)) == 2 and not settle.below_floor(gap, c)
    # not a chain of a/a0, or decided: never floored
    assert not settle.below_floor(_chain([0.50, 0.4992, 0.55], 0.0006, quantity="W_c [m]"), c)
    assert not settle.below_floor(_chain([0.50, 0.4992, 0.55], 0.0006, verdict=FAILS), c)
    # every step decided (none open): nothing to floor
    assert not settle.below_floor(_chain([0.50, 0.55, 0.60], 0.0006), c)


def test_the_floor_stops_a_row_only_when_asked(tmp_path, monkeypatch):
    calls = []

    def fake_checks(stores, seeds, z, recorded, widen=None):
        calls.append(len(seeds))
        return [_chain([0.50, 0.4992, 0.55, 0.60], 0.0006)], [len(seeds)]

    monkeypatch.setattr(settle, "pooled_checks", fake_checks)
    floored = settle.settle(tmp_path, max_seeds=16, floor=0.01)
    assert calls == [4, 4] and floored.rows[0].floored          # one look, its audit
    assert (floored.rows[0].look, floored.rows[0].check.verdict) == (1, INCONCLUSIVE)
    calls.clear()
    plain = settle.settle(tmp_path, max_seeds=16)
    assert calls == [4, 8, 16, 4, 8, 16] and not plain.rows[0].floored
    assert plain.rows[0].look == 3


@pytest.mark.slow  # fast: test_check.py::test_cli_seeds_runs_the_seeds_swept_into_one_store_per_campaign
# (the seeds swept in one store, in-process) and tests/sweep/test_mpi.py's mpiexec runs
def test_run_seeds_in_processes_stores_what_one_process_stores(tmp_path):
    """A look's seeds run by ``sweep run`` under mpiexec (2 workers) store what one
    process stores; a later look extends the campaign by its seeds."""
    from sweep.analysis.load import load
    from sweep.testing import find_mpiexec
    from herman2019.check import default_configs
    from herman2019.seeds import run_seeds

    if find_mpiexec() is None:
        pytest.skip("no mpiexec")
    names = ["spring_soft", "fig2"]
    seeds = (5, 6)
    one = run_seeds(tmp_path / "one", default_configs(), seeds, names,
                    "sweep.testing:seeded_point", None, 1)
    two = run_seeds(tmp_path / "two", default_configs(), seeds, names,
                    "sweep.testing:seeded_point", None, 2)
    assert two["seeds"] == list(seeds) and two["campaigns"] == names
    assert two["per_seed"] == one["per_seed"] == {5: 9, 6: 9}
    for n in names:
        a = load(tmp_path / "one" / f"{n}.h5").set_index("hash").sort_index()
        b = load(tmp_path / "two" / f"{n}.h5").set_index("hash").sort_index()
        cols = [k for k in a.columns if k.startswith(("seed", "a_end", "W_c", "alpha"))]
        assert cols and a[cols].equals(b[cols]) and set(a["seed"]) == set(seeds)
    more = run_seeds(tmp_path / "one", default_configs(), (5, 6, 7), names[:1],
                     "sweep.testing:seeded_point", None, 1)
    assert more["per_seed"] == {5: 0, 6: 0, 7: 1}
    assert sorted(set(load(tmp_path / "one" / "spring_soft.h5")["seed"])) == [5, 6, 7]


def _same(got, want, rel: float = 1e-12) -> bool:
    """``got == want`` for JSON values, but floats equal to ``rel``: the last bits of a
    fitted number are the machine's (seen: a fit's degrees of freedom 30.98852733987941 on
    an AMD EPYC with AVX2 against 30.988527339879415 where the file was made)."""
    if isinstance(want, dict):
        return (isinstance(got, dict) and got.keys() == want.keys()
                and all(_same(got[k], want[k], rel) for k in want))
    if isinstance(want, list):
        return (isinstance(got, list) and len(got) == len(want)
                and all(_same(g, w, rel) for g, w in zip(got, want, strict=True)))
    if isinstance(want, float) and isinstance(got, (int, float)) and not isinstance(got, bool):
        return got == want or math.isclose(got, want, rel_tol=rel, abs_tol=0.0)
    return type(got) is type(want) and got == want


def test_same_is_exact_but_for_the_last_bits_of_floats():
    assert _same({"a": [1, "x", 30.988527339879415]}, {"a": [1, "x", 30.98852733987941]})
    assert not _same({"a": [1, "x", 30.98853]}, {"a": [1, "x", 30.98852733987941]})
    assert not _same({"a": [2, "x", 1.0]}, {"a": [1, "x", 1.0]})
    assert not _same({"a": "holds"}, {"a": "fails"})
    assert not _same({"a": 1.0, "b": 2}, {"a": 1.0})


@pytest.mark.slow  # 2 looks of 11 paper campaigns on seeded_point (~20 s)
def test_settled_verdicts_and_numbers_are_those_of_the_seed_stores(tmp_path, capsys,
                                                                  monkeypatch):
    """The settling of the paper campaigns on seeded_point gives the table and
    settled.json (timings apart) of tests/data/settle_seeded_point.*: made at 8d0a81e
    with seeds in <stores>/seed<S>/ and a process pool of their own, which the settling
    with its seeds swept in one store per campaign reproduced; remade by these same calls
    on 2026-12-07 at model version 9 (new hashes, so seeded_point's values are new) with
    the rows' readings of herman2019/readings.py (41 rows)."""
    monkeypatch.setattr("herman2019.traces.PERIODS", 4)
    monkeypatch.setattr("herman2019.traces.SPIN_UP", 1)
    d = tmp_path / "paper"
    argv = ["check", "--stores", str(d), "--settle", "--max-seeds", "8"]
    assert main([*argv, "--run", "--compute", "sweep.testing:seeded_point", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    got.pop("runs")
    timing = {"cpu_s", "wall_s", "elapsed_s", "stored_core_s", "stored_core_s_seeds_2_up"}
    got["cost"] = {k: v for k, v in got["cost"].items() if k not in timing}
    want = json.loads((DATA / "settle_seeded_point.json").read_text())
    assert _same(got, want)
    assert main(argv) == 0
    table = [line for line in capsys.readouterr().out.splitlines()
             if not line.startswith("Settling's cost")]
    assert table == (DATA / "settle_seeded_point.md").read_text().splitlines()


def test_a_floored_row_says_why_in_numbers():
    from herman2019.thresholds import undecided_reason

    row = settle.Settled(_chain([0.50, 0.4992, 0.55, 0.60], 0.0006, dof=math.inf), 1, 4,
                         3.2, floored=True)
    why = undecided_reason(row, budget=256, floor=0.01)
    assert "the step d_f=1 -> d_f=2 is" not in why            # only the open step
    assert "the step d_f=0 -> d_f=1 is -0.00080 ± 0.00085" in why
    assert "within ±0.0035 at z_c 3.20" in why                 # 0.0008 + 3.2 x 0.00085
    assert "below the resolution floor ±0.01 of a0" in why and "at 4 seeds (the budget: 256)" in why
