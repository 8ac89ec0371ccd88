"""The ensemble seed as a campaign dimension (``[sweep] seed = [0, 1, 2]``, schema 5).

A swept seed is one more key of a point's configuration: the point with seed 0 swept is
the point with seed 0 in ``[base]`` (same hash); a campaign that sweeps no seed keeps its
grid, hashes and campaign hash; the store has a ``seed`` column (schema 5; older stores
read it from each row's ``config_json`` and are migrated so), ``load_xarray`` a ``seed``
dimension when it is swept, and ``--extend`` adds seeds to a campaign.
"""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

import sweep
from sweep import parse_campaign, run_campaign
from sweep.identity import DIMENSIONS
from sweep.store.merge import merge
from sweep.store.schema import SCHEMA_VERSION

ROOT = Path(__file__).resolve().parents[2]
FAKE = "sweep.testing:fake_point"
BASE = "[base]\nL_sheet = 6.0\nreplicas = 2\n"
SEEDS = BASE + "[sweep]\nL_x = [0.5, 1.5]\neps = [0.2, 0.6]\nseed = [0, 1, 2]\n"


def test_seed_is_the_last_dimension_and_a_swept_seed_hashes_as_the_base_one():
    assert DIMENSIONS == (*sweep.identity.floewave.SWEPT_FIELDS, "seed")
    swept = parse_campaign(SEEDS)
    assert swept.swept_fields == ("L_x", "eps", "seed") and swept.size == 12
    assert [p.swept["seed"] for p in swept.points()[:3]] == [0, 1, 2]   # fastest
    plain = parse_campaign(BASE + "seed = 1\n[sweep]\nL_x = [0.5, 1.5]\neps = [0.2, 0.6]\n")
    by_hash = {p.hash: p for p in swept.points()}
    for p in plain.points():
        assert by_hash[p.hash].config == p.config and by_hash[p.hash].swept["seed"] == 1


def test_a_campaign_without_seeds_keeps_its_campaign_hash():
    """configs/demo.toml's campaign hash is pinned: made before seed became a dimension
    (model version 8: f1abe24e...) it did not move when seed did; re-pinned at model
    version 9 (a new field and the version are in the definition)."""
    demo = sweep.load_campaign(ROOT / "configs" / "demo.toml")
    assert "seed" not in demo.sweep
    assert demo.definition_hash() == \
        "1334850a91553a25fabb82b4fc39a9da7977c58d7c4aa7a773774e2c5e7ad9a4"


@pytest.mark.parametrize("bad", ["[1.5]", "[-1]", "[0, 0]", '["a"]'])
def test_bad_seeds_are_refused(bad):
    with pytest.raises(sweep.ConfigError, match=r"\[sweep\] seed"):
        parse_campaign(BASE + f"[sweep]\neps = [0.2]\nseed = {bad}\n")


def test_swept_seeds_stored_loaded_and_extended(tmp_path):
    path = tmp_path / "s.h5"
    first = parse_campaign(BASE + "[sweep]\nL_x = [0.5, 1.5]\neps = [0.2, 0.6]\n"
                           "seed = [0, 1]\n")
    assert run_campaign(first, str(path), compute=FAKE).computed == 8
    more = parse_campaign(SEEDS)
    assert run_campaign(more, str(path), compute=FAKE, extend=True).computed == 4
    assert sweep.validate(path) == []
    df = sweep.load(path)
    assert sorted(df["seed"]) == [0] * 4 + [1] * 4 + [2] * 4
    assert all(json.loads(c)["seed"] == s for c, s in zip(df["config_json"], df["seed"],
                                                          strict=True))
    ds = sweep.load_xarray(path)
    assert ds.sizes["seed"] == 3 and list(ds["seed"].values) == [0, 1, 2]
    assert list(ds["a_end"].dims) == ["L_x", "eps", "seed"]
    assert dict(sweep.load_profiles(path, seed=2).sizes) == {"L_x": 2, "eps": 2, "floe": 12}
    assert sweep.load_profiles(path, seed=[0, 2]).sizes["seed"] == 2
    # shards of a seeded campaign split its points, seeds included, and merge back
    parts = []
    for k in range(2):
        parts.append(tmp_path / f"part{k}.h5")
        run_campaign(more.shard(k, 2), str(parts[-1]), compute=FAKE)
    merged = tmp_path / "merged.h5"
    merge(merged, parts)
    assert sorted(sweep.load(merged)["hash"]) == sorted(df["hash"])


def test_alpha_omega_fits_each_seed_apart_unless_pooled(tmp_path):
    path = tmp_path / "s.h5"
    run_campaign(parse_campaign(BASE + "[sweep]\nT = [1.0, 1.2, 1.4]\nseed = [0, 1]\n"),
                 str(path), compute=FAKE)
    df = sweep.load(path)
    per_seed = sweep.alpha_omega(df, "alpha_all")
    assert sorted(per_seed["seed"]) == [0, 1] and (per_seed["n_points"] == 3).all()
    pooled = sweep.alpha_omega(df, "alpha_all", by=[])
    assert len(pooled) == 1 and int(pooled["n_points"].iloc[0]) == 6
    one = parse_campaign(BASE + "[sweep]\nT = [1.0, 1.2, 1.4]\n")
    run_campaign(one, str(tmp_path / "one.h5"), compute=FAKE)
    assert "seed" not in sweep.alpha_omega(sweep.load(tmp_path / "one.h5"), "alpha_all")


def _as_schema_4(path: Path) -> None:
    with h5py.File(path, "r+") as f:
        f.attrs["schema_version"] = 4
        del f["table"]["seed"]


def test_schema_4_store_reads_seed_from_config_and_is_migrated(tmp_path):
    store = tmp_path / "s.h5"
    run_campaign(parse_campaign(BASE + "seed = 7\n[sweep]\neps = [0.2, 0.6]\n"), str(store),
                 compute=FAKE)
    before = sweep.load(store)
    old = tmp_path / "old.h5"
    shutil.copy(store, old)
    _as_schema_4(old)
    assert sweep.validate(old) == []
    got = sweep.load(old)                       # a reader: read as it is
    assert (got["seed"] == 7).all() and got["seed"].dtype == before["seed"].dtype
    with h5py.File(old, "r") as f:
        assert int(f.attrs["schema_version"]) == 4 and "seed" not in f["table"]
    more = parse_campaign(BASE + "seed = 7\n[sweep]\neps = [0.2, 0.4, 0.6]\n")
    assert run_campaign(more, str(old), compute=FAKE, extend=True).computed == 1
    with h5py.File(old, "r") as f:             # a writer: migrated, seed from config_json
        assert int(f.attrs["schema_version"]) == SCHEMA_VERSION == 5
        n = int(f["table"].attrs["n_rows"])
        assert list(f["table"]["seed"][:n]) == [7, 7, 7]
    assert sweep.validate(old) == []


def test_an_older_journal_line_without_seed_is_stored_with_its_seed(tmp_path):
    """A journal record of schema 4 (no seed in its row) replayed into a store gets its
    seed from its config_json."""
    from sweep.store.cells import normalise_record
    cfg = json.dumps({"config": {"seed": 3, "eps": 0.2}, "model_version": 8})
    row = normalise_record({"row": {"hash": "ab", "config_json": cfg}})["row"]
    assert row["seed"] == 3
    assert normalise_record({"row": {"hash": "ab", "config_json": cfg, "seed": 5}}
                            )["row"]["seed"] == 5
    assert np.int64(normalise_record({"row": {"hash": "ab", "config_json": "{"}})["row"]
                    ["seed"]) == -1


def test_status_plan_and_figures_of_a_seeded_campaign(tmp_path, capsys):
    """``sweep plan`` and ``sweep status`` count a seeded grid's points; ``sweep figures``
    draws each seed's points apart, in OUT/seed=<seed>/, and says so."""
    pytest.importorskip("matplotlib")
    from sweep.cli import main
    toml = tmp_path / "c.toml"
    toml.write_text(BASE + "[sweep]\neps = [0.2, 0.8]\nseed = [0, 1]\n")
    assert main(["plan", str(toml), "--rate", "1e7"]) == 0
    assert "4 points" in capsys.readouterr().out.replace(",", "")
    path = tmp_path / "s.h5"
    run_campaign(sweep.load_campaign(toml), str(path), compute=FAKE)
    assert main(["status", str(path)]) == 0
    assert "4" in capsys.readouterr().out
    out = tmp_path / "figs"
    assert main(["figures", str(path), "--out", str(out), "--only", "fig2"]) == 0
    assert "seeds are not pooled" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == ["seed=0", "seed=1"]
    assert all(len(list((out / d).glob("fig2_*.png"))) == 1 for d in ("seed=0", "seed=1"))


def test_a_table_exported_before_schema_5_gets_its_seed_from_config(tmp_path):
    import pandas as pd

    from sweep.analysis.export import export_table
    store = tmp_path / "s.h5"
    run_campaign(parse_campaign(BASE + "seed = 4\n[sweep]\neps = [0.2, 0.6]\n"), str(store),
                 compute=FAKE)
    table = tmp_path / "t.csv"
    export_table(store, table)
    old = pd.read_csv(table, dtype=str).drop(columns="seed")
    old.to_csv(table, index=False)
    got = sweep.load(table)
    assert list(got["seed"]) == [4, 4] and got.columns.get_loc("seed") == \
        got.columns.get_loc("dispersion") + 1
