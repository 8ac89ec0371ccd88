"""sweep.store.campaign_check: a campaign against the definition a store holds (--extend)."""
from __future__ import annotations

from pathlib import Path

import pytest

from sweep import parse_campaign
from sweep.errors import CampaignMismatchError
from sweep.store.campaign_check import check_campaign, check_legacy_journal

TOML = "[base]\nL_sheet = 6.0\n[sweep]\neps = [0.2, 0.4]\n"
PATH = Path("s.h5")


def old():
    return parse_campaign(TOML).definition()


def test_the_same_campaign_passes(campaign):
    check_campaign(PATH, old(), campaign, False, "store")
    check_campaign(PATH, old(), campaign, True, "journal")


def test_another_campaign_is_named_by_what_differs():
    other = parse_campaign("[base]\nL_sheet = 7.0\n[sweep]\neps = [0.2, 0.5]\n")
    with pytest.raises(CampaignMismatchError, match=r"s.h5: the journal belongs to a different"
                       r" campaign \(differs in \[base\] L_sheet, \[sweep\] eps\)"):
        check_campaign(PATH, old(), other, False, "journal")


def test_extend_adds_values_only():
    more = parse_campaign(TOML.replace("[0.2, 0.4]", "[0.2, 0.4, 0.6]"))
    check_campaign(PATH, old(), more, True, "store")
    fewer = parse_campaign(TOML.replace("[0.2, 0.4]", "[0.2, 0.6]"))
    with pytest.raises(CampaignMismatchError, match=r"cannot --extend this store: \[sweep\]"
                       r" eps drops \[0.4\]"):
        check_campaign(PATH, old(), fewer, True, "store")
    rebased = parse_campaign(TOML.replace("6.0", "7.0"))
    with pytest.raises(CampaignMismatchError, match=r"\[base\] \(or model version\) differs"):
        check_campaign(PATH, old(), rebased, True, "store")
    dims = parse_campaign(TOML + "T = [1.2]\n")
    with pytest.raises(CampaignMismatchError, match="swept dimensions differ"):
        check_campaign(PATH, old(), dims, True, "store")


def test_another_model_version_names_both(campaign):
    definition = dict(old(), model_version="1")
    with pytest.raises(CampaignMismatchError, match=r"model version 1 \(store schema 2\);"
                       r" this sweep computes model version"):
        check_campaign(PATH, definition, campaign, True, "store", 2)


def test_legacy_journal_must_hold_only_grid_points(campaign):
    hashes = [p.hash for p in campaign.points()]
    check_legacy_journal(Path("s.h5.journal"), hashes, campaign)
    with pytest.raises(CampaignMismatchError, match=r"holds 1 point\(s\) that are not in"
                       r" this campaign's grid \(e.g. ffffffffffff\)"):
        check_legacy_journal(Path("s.h5.journal"), hashes + ["f" * 64], campaign)
