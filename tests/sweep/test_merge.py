"""sweep.store.merge: shard stores of one campaign combine into one store, one row per
point (a success beats a failure); other campaigns and newer schemas are refused."""
from __future__ import annotations

import h5py
import pytest

import sweep
from sweep import parse_campaign, run_campaign
from sweep.errors import CampaignMismatchError, StoreError
from sweep.store.merge import merge
from sweep.store.validate import validate
from tests.sweep.helpers import split_shards

TOML = "[base]\nL_sheet = 6.0\n[sweep]\nL_x = [0.5, 1.5]\neps = [0.2, 0.4, 0.6]\n"


def shards(tmp_path, campaign):
    """The campaign run as shards (``--shard K/N``, the fewest N of which two or more hold
    points: tests/sweep/helpers.split_shards), one store each; the non-empty ones first."""
    paths = []
    for k, part in enumerate(split_shards(campaign)):
        path = tmp_path / f"shard{k}.h5"
        run_campaign(part, str(path), compute="sweep.testing:fake_point", progress_bar=False)
        paths.append(path)
    return sorted(paths, key=lambda q: -len(sweep.load(q)))


def test_shards_merge_into_the_whole_campaign(tmp_path, campaign):
    paths = shards(tmp_path, campaign)
    sizes = [len(sweep.load(q)) for q in paths]
    assert sum(sizes) == 6 and sum(1 for n in sizes if n) >= 2
    merge(tmp_path / "all.h5", paths)
    df = sweep.load(tmp_path / "all.h5")
    assert sorted(df["hash"]) == sorted(p.hash for p in campaign.points())
    assert validate(tmp_path / "all.h5") == []
    merge(tmp_path / "all.h5", paths[:1])  # again: nothing duplicated
    assert len(sweep.load(tmp_path / "all.h5")) == 6


def test_a_success_replaces_a_failure(tmp_path, campaign):
    bad = tmp_path / "bad.h5"
    good = tmp_path / "good.h5"
    run_campaign(campaign, str(bad), compute="sweep.testing:raising_point",
                 progress_bar=False)
    run_campaign(campaign, str(good), compute="sweep.testing:fake_point", progress_bar=False)
    assert (sweep.load(bad)["status"] == "failed").sum() == 2
    merge(tmp_path / "m.h5", [bad, good])
    assert set(sweep.load(tmp_path / "m.h5")["status"]) == {"converged"}


def test_other_campaigns_and_newer_schemas_are_refused(tmp_path, campaign):
    a = shards(tmp_path, campaign)[0]
    other = tmp_path / "other.h5"
    run_campaign(parse_campaign(TOML.replace("6.0", "7.0")), str(other),
                 compute="sweep.testing:fake_point", progress_bar=False)
    with pytest.raises(CampaignMismatchError):
        merge(tmp_path / "m.h5", [a, other])
    with h5py.File(a, "r+") as f:
        f.attrs["schema_version"] = 99
    with pytest.raises(StoreError, match="schema version 99"):
        merge(tmp_path / "m2.h5", [a])
    with pytest.raises(StoreError, match="output store itself"):
        merge(other, [other])


def test_status_counts_a_shard_against_its_shard_and_the_merge_against_the_grid(
        tmp_path, campaign):
    from sweep.analysis.status import status_report, status_text

    parts = split_shards(campaign)
    n = len(parts)
    paths = []
    for k, part in enumerate(parts):
        path = tmp_path / f"shard{k}.h5"
        run_campaign(part, str(path), compute="sweep.testing:fake_point", progress_bar=False)
        paths.append(path)
        rep = status_report(path)
        # every point of the shard is stored: nothing remains of it (the whole grid's 6
        # would leave 6 - size remaining)
        assert (rep["grid_points"], rep["remaining"], rep["shard"]) == (part.size, 0, f"{k}/{n}")
        assert f"points (shard {k}/{n} of the grid) stored" in status_text(rep)
    merge(tmp_path / "all.h5", paths)
    rep = status_report(tmp_path / "all.h5")
    assert (rep["grid_points"], rep["remaining"], rep["shard"]) == (6, 0, None)


def test_an_open_shard_is_refused_and_the_merge_says_what_is_missing(tmp_path, campaign,
                                                                     run_main):
    """A shard whose writer died (its file still marked open: its journal may hold points
    the file lacks) is refused, naming it and how to finish it; nothing is written. A
    merge of unfinished shards says how many grid points are still to compute."""
    from sweep.cli import main
    from tests.sweep.helpers import make_unclean

    paths = shards(tmp_path, campaign)
    make_unclean(paths[0])
    out = tmp_path / "all.h5"
    got = run_main(main, ["merge", out, *paths])
    assert got.returncode == 3, got.stderr
    assert f"{paths[0]}: is open" in got.stderr and "sweep run CAMPAIGN" in got.stderr
    assert not out.exists()
    sweep.run_campaign(campaign.shard(*_shard_of(campaign, paths[0])), str(paths[0]),
                       compute="sweep.testing:fake_point", progress_bar=False)
    message = merge(out, paths[:1])
    n = len(sweep.load(paths[0]))
    assert f"{n} of the campaign's 6 grid points stored ({6 - n} still to compute" in message
    assert "still to compute" not in merge(out, paths)


def _shard_of(campaign, path):
    """The (K, N) of the shard stored at ``path``: the split whose points it holds."""
    held = set(sweep.load(path)["hash"])
    for n in range(2, 7):
        for k in range(n):
            if {p.hash for p in campaign.shard(k, n).points()} == held:
                return k, n
    raise AssertionError("no shard holds these points")
