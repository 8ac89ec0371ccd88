"""``sweep figures``: the paper's figure kinds from a hand-built and from a real store."""
import numpy as np
import pytest

from sweep import load, parse_campaign, run_campaign
from sweep.cli import main

pytest.importorskip("matplotlib")

PNG = b"\x89PNG\r\n\x1a\n"

REAL = """\
[base]
L_sheet = 9.0
n0 = 1
nT = 1
max_iterations = 4
replicas = 2
[sweep]
L_x = [1.5, 3.0]
eps = [0.2, 0.8]
dispersion = ["ml"]
"""

FAKE = """\
[base]
L_sheet = 6.0
[sweep]
L_x = [0.5, 1.0]
T = [1.0, 1.5, 2.0]
a0 = [0.0125, 0.02]
eps = [0.2, 0.8]
d_f = [0.005, 0.02]
dispersion = ["ep", "ml"]
"""


def _pngs(out):
    files = sorted(out.iterdir())
    for f in files:
        data = f.read_bytes()
        assert data[:8] == PNG and len(data) > 10_000, f
    return [f.name for f in files]


@pytest.fixture(scope="module")
def fake_store(power_store):
    return power_store(FAKE, "f.toml")


def test_every_kind_from_a_hand_built_store(fake_store, tmp_path, capsys):
    out = tmp_path / "figs"
    assert main(["figures", str(fake_store), "--out", str(out), "--max", "1"]) == 0
    names = _pngs(out)
    # one per kind (fig6: one per d_f and one per a0) + the three summary figures
    assert len(names) == 8, names
    # groups closest to the paper's setup come first (only T differs: 1.0 sorts first)
    assert "fig2_L_x=0.5_T=1.0_a0=0.0125_C_sd=0.05_d_f=0.005.png" in names
    assert "fig3_L_x=0.5_T=1.0_a0=0.0125_C_sd=0.05_d_f=0.005_dispersion=ml.png" in names
    assert sum(n.startswith("fig5_") for n in names) == 1
    assert sum(n.startswith("fig6_df_") for n in names) == 1
    assert sum(n.startswith("fig6_a0_") for n in names) == 1
    assert {"collision_zone.png", "collision_stats.png", "alpha_omega.png"} <= set(names)
    assert f"wrote 8 figures to {out}" in capsys.readouterr().out


def test_only_and_max(fake_store, tmp_path):
    out = tmp_path / "f"
    assert main(["figures", str(fake_store), "--out", str(out), "--only", "fig5",
                 "--max", "3"]) == 0
    names = _pngs(out)
    assert len(names) == 3 and all(n.startswith("fig5_") for n in names)


def test_bad_figure_arguments_write_nothing(fake_store, tmp_path, capsys):
    out = tmp_path / "o"
    assert main(["figures", str(fake_store), "--out", str(out), "--only", "fig4"]) == 2
    assert "unknown figure kind 'fig4'" in capsys.readouterr().err
    assert main(["figures", str(fake_store), "--out", str(out), "--max", "0"]) == 2
    assert "--max 0" in capsys.readouterr().err
    assert not out.exists()


def test_compact_ice_line_and_zone_dot_follow_eq_25():
    """The dashed line starts at the W_c dot, a(W_c), and follows 1/a = 1/a_W + alpha_c dx."""
    import matplotlib.pyplot as plt
    import pandas as pd

    from sweep.analysis.plotting import draw_amplitude as _amplitude
    from sweep.analysis.plotting import draw_confined as _confined

    x = np.linspace(0.25, 9.75, 20)
    a = 0.01 / (1 + 3.0 * x)
    row = pd.Series({"a0": 0.01, "W_c": 4.0, "alpha_c": 50.0})
    fig, ax = plt.subplots()
    _amplitude(ax, row, {"x": x, "a": a, "a_stderr": 0.01 * a}, "C0", zone=True)
    _confined(ax, row, 10.0)
    lines = ax.get_lines()
    dot = [ln for ln in lines if ln.get_marker() == "o"][0]
    dashed = [ln for ln in lines if ln.get_linestyle() == "--"][0]
    solid = lines[-1]
    a_w = np.interp(4.0, x, a)
    assert dot.get_xdata()[0] == 4.0 and dot.get_ydata()[0] == pytest.approx(a_w / 0.01)
    xd, yd = dashed.get_xdata(), dashed.get_ydata()
    assert xd[0] == 4.0 and yd[0] == pytest.approx(a_w / 0.01)
    np.testing.assert_allclose(1 / (yd * 0.01), 1 / a_w + 50.0 * (xd - 4.0), rtol=1e-12)
    xs, ys = solid.get_xdata(), solid.get_ydata()
    np.testing.assert_allclose(1 / (ys * 0.01), 1 / 0.01 + 50.0 * xs, rtol=1e-12)  # eq. 25
    plt.close(fig)


def test_figures_from_a_real_store(tmp_path, capsys):
    store = tmp_path / "s.h5"
    run_campaign(parse_campaign(REAL, "t.toml"), str(store))
    out = tmp_path / "figs"
    assert main(["figures", str(store), "--out", str(out)]) == 0
    names = _pngs(out)
    # fig2 and fig3: one per L_x; fig5: one per eps; no fig6 (d_f, a0 fixed); W_c and
    # collision-statistics summaries; no alpha_omega (a single T)
    assert sum(n.startswith("fig2_") for n in names) == 2
    assert sum(n.startswith("fig3_") for n in names) == 2
    assert sum(n.startswith("fig5_") for n in names) == 2
    assert "collision_zone.png" in names and "alpha_omega.png" not in names
    # collision_stats needs a compact zone somewhere (this short sheet may have none)
    has_zone = bool(load(store)["W_c"].notna().any())
    assert ("collision_stats.png" in names) == has_zone
    assert len(names) == 7 + has_zone
    assert ("collision_stats not drawn" in capsys.readouterr().err) == (not has_zone)


def test_figures_of_a_missing_store_is_an_error(tmp_path, capsys):
    assert main(["figures", str(tmp_path / "nope.h5"), "--out", str(tmp_path / "o")]) == 3
    assert "no such store" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_only_takes_one_argument_so_the_store_is_not_swallowed(fake_store, tmp_path, capsys):
    """``--only fig5 STORE --out DIR`` (issue *first hour* 9): the store stays positional.
    (Every kind asked for is drawn: no "not drawn" on stderr.)"""
    out = tmp_path / "f"
    assert main(["figures", "--only", "fig5", str(fake_store), "--out", str(out),
                 "--max", "1"]) == 0
    assert [n[:5] for n in _pngs(out)] == ["fig5_"]
    assert "not drawn" not in capsys.readouterr().err
    out2 = tmp_path / "g"
    assert main(["figures", "--only", "fig5,fig2", "--only", "fig6", str(fake_store),
                 "--out", str(out2), "--max", "1"]) == 0
    assert {n[:4] for n in _pngs(out2)} == {"fig5", "fig2", "fig6"}
    assert "not drawn" not in capsys.readouterr().err


def test_unusable_out_is_refused_before_drawing(fake_store, tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["figures", str(fake_store), "--out", str(blocker / "figs")]) == 2
    assert "--out" in capsys.readouterr().err
    assert main(["figures", str(fake_store), "--out", str(blocker)]) == 2
    assert "not a directory" in capsys.readouterr().err


def test_one_figure_is_singular(fake_store, tmp_path, capsys):
    out = tmp_path / "one"
    assert main(["figures", str(fake_store), "--out", str(out), "--only", "fig5",
                 "--max", "1"]) == 0
    assert f"wrote 1 figure to {out}" in capsys.readouterr().out


def test_not_converged_curves_are_marked():
    """Issue *first hour* 6: a not-converged point does not look like a converged one."""
    import matplotlib.pyplot as plt
    import pandas as pd

    from sweep.analysis.plotting import draw_amplitude as _amplitude

    x = np.linspace(0.25, 9.75, 20)
    prof = {"x": x, "a": 0.01 / (1 + x), "a_stderr": 1e-4 + 0 * x}
    fig, ax = plt.subplots()
    for status in ("converged", "not_converged"):
        _amplitude(ax, pd.Series({"a0": 0.01, "status": status}), prof, "C0",
                   label=f"eps {status}")
    ok, bad = ax.get_lines()
    assert ok.get_marker() in ("None", "", None) and ok.get_label() == "eps converged"
    assert bad.get_marker() == "x" and bad.get_label() == "eps not_converged"
    plt.close(fig)


# ---------------------------------------------------------------------- what each figure draws
MIXED = """\
[base]
L_sheet = 6.0
[sweep]
L_x = [0.5]
T = [1.0, 1.5, 2.0]
eps = [0.2, 0.8]
d_f = [0.005, 0.02]
dispersion = ["ml", "ep"]
"""


def ep_unconverged_point(cfg):
    """``power_point``, not converged for ``ep`` (panel (b) of Fig. 2) and converged for
    ``ml`` (panel (a))."""
    from sweep.testing import power_point

    out = power_point(cfg)
    out["status"] = "not_converged" if cfg.dispersion == "ep" else "converged"
    # two replicas whose own W_c straddle the mean (Fig. 3 draws them at the threshold)
    out["replicas"] = 2
    out["W_c_replicas"] = np.array([0.8, 1.2]) * out["W_c"]
    out["compact_end_replicas"] = np.full(2, out["compact_end"])
    for name in ("x_mean", "gap_mean", "S_sd"):
        out[f"{name}_replicas"] = np.vstack([out[name], out[name]])
    return out


@pytest.fixture(scope="module")
def mixed_figures(tmp_path_factory):
    """Every figure of the MIXED store, as matplotlib Figures by file name."""
    from pathlib import Path

    from matplotlib.figure import Figure

    from sweep import load

    store = tmp_path_factory.mktemp("mixed") / "m.h5"
    run_campaign(parse_campaign(MIXED, "m.toml"), str(store),
                 compute="tests.sweep.test_figures:ep_unconverged_point", progress_bar=False)
    seen = {}
    original = Figure.savefig

    def savefig(self, fname, *args, **kwargs):
        seen[Path(fname).name] = self
        return original(self, fname, *args, **kwargs)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(Figure, "savefig", savefig)
        assert main(["figures", str(store), "--out", str(store.parent / "f"),
                     "--max", "1"]) == 0
    return seen, load(store)


def _one(figures, prefix):
    names = [n for n in figures if n.startswith(prefix)]
    assert len(names) == 1, names
    return figures[names[0]]


def _legend_texts(fig):
    legends = list(fig.legends) + [ax.get_legend() for ax in fig.axes if ax.get_legend()]
    return [t.get_text() for leg in legends for t in leg.get_texts()]


def _crossed(ax):
    return [ln for ln in ax.get_lines() if ln.get_marker() == "x" and len(ln.get_xdata()) > 1]


def _rings(fig):
    return [(x, y) for ax in fig.axes for ln in ax.get_lines()
            if ln.get_marker() == "s" and ln.get_markerfacecolor() == "none"
            for x, y in zip(ln.get_xdata(), ln.get_ydata(), strict=True)]


def test_fig2_legend_comes_from_every_panel(mixed_figures):
    """Issue 25: panel (a) (ML) has no not-converged curve, panel (b) (EP) has two; their
    crosses are explained in the legend all the same."""
    from sweep.analysis.plotting import NOT_CONVERGED

    fig = _one(mixed_figures[0], "fig2_")
    ml, ep = fig.axes
    assert ml.get_title(loc="left") == "(a) ML" and not _crossed(ml)
    assert len(_crossed(ep)) == 2
    texts = _legend_texts(fig)
    assert NOT_CONVERGED in texts
    assert {"ε = 0.2", "ε = 0.8", "eq. 25 (confined ice)",
            "start of the compact zone (x = W_c, per averaging window)"} <= set(texts)
    # the averaged-gap W_c (open diamonds) is explained once when a point has one
    gap = "W_c from the gaps averaged over all windows"
    extra = int(gap in texts)
    assert len(texts) == len(set(texts)) == 6 + extra   # one entry per ε, not per panel
    legend = fig.legends[0]
    eps_entries = [h for h, t in zip(legend.legend_handles, texts, strict=True)
                   if t.startswith("ε")]
    assert [h.get_marker() for h in eps_entries] == ["None", "None"]   # crosses: own entry


def test_fig3_gap_axis_is_logarithmic_with_the_W_c_threshold(mixed_figures):
    fig = _one(mixed_figures[0], "fig3_")
    gap_ax = fig.axes[0]
    assert gap_ax.get_yscale() == "log"
    threshold = [ln for ln in gap_ax.get_lines()
                 if ln.get_linestyle() == ":" and set(ln.get_ydata()) == {1e-4}]
    assert len(threshold) == 1
    texts = _legend_texts(fig)
    assert any(t.startswith("gap_threshold = 0.0001 m") for t in texts)
    dots = sorted(ln.get_xdata()[0] for ln in gap_ax.get_lines() if ln.get_marker() == "o")
    assert dots == pytest.approx([1.0, 4.0])          # W_c = 10 eps L_x (power_point)
    # each replica's own W_c, at the threshold it crossed there
    ticks = [ln for ln in gap_ax.get_lines() if ln.get_marker() == "|"]
    assert sorted(x for ln in ticks for x in ln.get_xdata()) == pytest.approx(
        [0.8, 1.2, 3.2, 4.8])
    assert all(set(ln.get_ydata()) == {1e-4} for ln in ticks)
    from sweep.analysis.figures import REPLICA_W_C

    assert REPLICA_W_C in texts


@pytest.mark.parametrize("kind", ["fig5", pytest.param("fig6", marks=pytest.mark.slow)])
# fig6: slow tier (fast: fig5 here; fig6 drawn by test_every_kind_from_a_hand_built_store)
def test_fig5_and_fig6_mark_and_explain_not_converged_curves(kind, fake_store, tmp_path,
                                                             monkeypatch):
    """FAKE's eps = 0.8 points are not converged (power_point): their curves carry crosses,
    the legend explains them once, and no other entry shows crosses."""
    from pathlib import Path

    from matplotlib.figure import Figure

    from sweep.analysis.plotting import NOT_CONVERGED

    seen = {}
    original = Figure.savefig

    def savefig(self, fname, *args, **kwargs):
        seen[Path(fname).name] = self
        return original(self, fname, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", savefig)
    assert main(["figures", str(fake_store), "--out", str(tmp_path), "--only", kind,
                 "--max", "6"]) == 0
    marked = {n: sum(len(_crossed(ax)) for ax in f.axes) for n, f in seen.items()}
    assert 0 < sum(m > 0 for m in marked.values()) < len(marked), marked
    assert all((m > 0) == ("eps=0.8" in n) for n, m in marked.items()), marked
    # the legend is built from every panel: the crosses of any panel are explained, once
    assert all((NOT_CONVERGED in _legend_texts(f)) == ("eps=0.8" in n) for n, f in seen.items())
    for fig in seen.values():
        for legend in [*fig.legends, *(ax.get_legend() for ax in fig.axes if ax.get_legend())]:
            crossed = [t.get_text() for h, t in zip(legend.legend_handles, legend.get_texts(),
                                                    strict=True)
                       if getattr(h, "get_marker", lambda: None)() == "x"]
            assert crossed in ([], [NOT_CONVERGED]), crossed


def test_collision_zone_curves_are_distinguishable_and_status_marked(mixed_figures):
    from sweep.analysis.plotting import NOT_CONVERGED_RING

    figures, df = mixed_figures
    fig = figures["collision_zone.png"]
    ax = fig.axes[0]
    curves = [ln for ln in ax.get_lines() if not ln.get_label().startswith("_")]
    styles = {(tuple(np.round(np.asarray(ln.get_color(), float), 6)), ln.get_marker())
              for ln in curves}
    assert len(curves) == 12 and len(styles) == 12        # T x d_f x dispersion groups
    # every not-converged point (all of EP) has a square: 6 groups x 2 eps
    assert len(_rings(fig)) == int((df["status"] == "not_converged").sum()) == 12
    assert NOT_CONVERGED_RING in _legend_texts(fig)
    # equal W_c values stay visible: no two curves share an eps position
    xs = [tuple(ln.get_xdata()) for ln in curves]
    assert len(set(xs)) == len(xs)


def test_collision_stats_markers_and_rings(mixed_figures):
    from sweep.analysis.plotting import NOT_CONVERGED_RING

    fig = mixed_figures[0]["collision_stats.png"]
    ax1 = fig.axes[0]
    curves = [c for c in ax1.containers]                  # one errorbar per curve
    markers = {c.lines[0].get_marker() for c in curves}
    assert len(curves) == 2 and len(markers) == 2         # ML and EP at one L_x
    assert len(_rings(fig)) == 4                          # EP at two eps, in both panels
    assert NOT_CONVERGED_RING in _legend_texts(fig)
    assert {"L_x = 0.5 m, ML", "L_x = 0.5 m, EP"} <= set(_legend_texts(fig))


def test_alpha_omega_marks_not_converged_points(mixed_figures):
    from sweep.analysis.plotting import NOT_CONVERGED_RING

    fig = mixed_figures[0]["alpha_omega.png"]
    assert _rings(fig)
    texts = _legend_texts(fig)
    assert NOT_CONVERGED_RING in texts
    # every fit keeps its own alpha_c entry, even where two read the same
    fits = [t for t in texts if ": m = " in t and not t.strip().startswith("α_c")]
    assert len(fits) >= 2 and sum(t.strip().startswith("α_c") for t in texts) == len(fits)


def test_nothing_drawable_says_why_and_exits_2(power_store, tmp_path, capsys):
    store = power_store("[base]\nL_sheet = 6.0\n[sweep]\nL_x = [0.5]\n", "one.toml")
    assert main(["figures", str(store), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "fig2 not drawn: needs points that differ only in eps" in err
    assert "alpha_omega not drawn: needs >= 3 wave periods" in err
    assert "no figure of fig2, fig3, fig5, fig6, summary can be drawn" in err
    assert list((tmp_path / "o").iterdir()) == []


def test_collision_stats_without_any_compact_zone_is_not_drawn_and_says_why(power_store,
                                                                            tmp_path, capsys):
    """power_point has no compact zone where 10 eps L_x >= L_sheet: here nowhere."""
    store = power_store("[base]\nL_sheet = 3.0\n[sweep]\nL_x = [0.5]\neps = [0.6, 0.8]\n",
                        "wide.toml")
    assert main(["figures", str(store), "--out", str(tmp_path), "--only", "summary"]) == 0
    assert "collision_stats not drawn: needs more than one eps and points with a compact" \
           " zone" in capsys.readouterr().err
    assert [f.name for f in tmp_path.iterdir()] == ["collision_zone.png"]
