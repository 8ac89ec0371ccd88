"""Legends that say only what the figure shows (issue [harden] 10): a series without a
single drawable value is not listed as if it were drawn, and a status mark's entry shows
its symbol once (the handle), not again in its text."""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402

import sweep  # noqa: E402
from sweep.analysis import plotting  # noqa: E402
from sweep.analysis.summary_figures import collision_stats_figure  # noqa: E402

# power_point: W_c = 10 eps L_x where it fits in the sheet: L_x = 1.5 m never does (no
# compact zone), L_x = 0.5 m always; eps = 0.8 is not converged
TOML = ("[base]\nL_sheet = 6.0\n[sweep]\nL_x = [0.5, 1.5]\neps = [0.4, 0.6, 0.8]\n"
        'dispersion = ["ml", "ep"]\n')


@pytest.fixture
def figure(power_store, tmp_path, monkeypatch):
    df = sweep.load(power_store(TOML))
    seen = []
    monkeypatch.setattr(plotting, "save_figure", lambda fig, path, written: seen.append(fig))
    import sweep.analysis.summary_figures as sf
    monkeypatch.setattr(sf, "save_figure", lambda fig, path, written: seen.append(fig))
    collision_stats_figure(df, tmp_path)
    assert len(seen) == 1
    yield seen[0]
    plt.close(seen[0])


def _entries(fig):
    return [(h, t.get_text()) for leg in fig.legends
            for h, t in zip(leg.legend_handles, leg.get_texts(), strict=True)]


def test_series_without_data_are_not_listed_as_drawn(figure):
    texts = [t for _, t in _entries(figure)]
    assert {"L_x = 0.5 m, ML", "L_x = 0.5 m, EP"} <= set(texts)
    drawn_at_15 = [t for t in texts if t.startswith("L_x = 1.5 m") and "no compact zone"
                   not in t]
    assert drawn_at_15 == [], texts
    assert any(t.startswith("L_x = 1.5 m") and "no compact zone" in t for t in texts), texts


def test_a_status_entry_shows_its_symbol_once(figure):
    marks = {"s": "□", "x": "×"}
    for handle, text in _entries(figure):
        marker = getattr(handle, "get_marker", lambda: None)()
        if marker in marks:
            assert marks[marker] not in text, text
    assert not plotting.NOT_CONVERGED.startswith(("×", "□"))
    assert not plotting.NOT_CONVERGED_RING.startswith(("×", "□"))
