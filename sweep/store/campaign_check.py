"""Is this campaign the store's? The check of a campaign against the definition a
store's file or journal holds, and what ``--extend`` accepts (same base and model
version, same swept dimensions, grid values only added)."""
from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from sweep.errors import CampaignMismatchError
from sweep.identity import canonical_json, sha256_hex
from sweep.store.schema import SCHEMA_VERSION

__all__ = ["check_campaign", "check_legacy_journal"]


def check_campaign(path: Path, old: dict[str, Any], campaign: Any, extend: bool,
                   where: str, file_schema: Any = "?") -> None:
    """Refuse ``campaign`` unless it is the one whose definition ``old`` the store's
    file or journal (``where``) holds, or (``extend``) an extension of it: the same base
    and model version, the same swept dimensions, no swept value dropped.

    Raises
    ------
    CampaignMismatchError
        Naming what differs (another model version: its points have other hashes).
    """
    if sha256_hex(canonical_json(old)) == campaign.definition_hash():
        return
    new = campaign.definition()
    if str(old.get("model_version")) != str(new.get("model_version")):
        # another model version: none of its points is a point of this model
        raise CampaignMismatchError(
            f"{path}: the {where} holds points of model version"
            f" {old.get('model_version')} (store schema"
            f" {file_schema}); this"
            f" sweep computes model version {new.get('model_version')} (schema"
            f" {SCHEMA_VERSION}), whose points have other hashes. Use another --store;"
            " the old one stays readable (sweep.load, sweep status, sweep export)")
    problems = _extend_problems(old, new)
    if not extend:
        diff = sorted(k for k in set(old["base"]) | set(new["base"])
                      if old["base"].get(k) != new["base"].get(k))
        sweep_diff = sorted(k for k in set(old["sweep"]) | set(new["sweep"])
                            if old["sweep"].get(k) != new["sweep"].get(k))
        what = ", ".join([f"[base] {k}" for k in diff] + [f"[sweep] {k}" for k in
                                                          sweep_diff]) or "model_version"
        # suggest --extend only where it would be accepted
        advice = ("use another --store, or --extend to add grid values to this one"
                  if not problems else "use another --store (--extend cannot take it: "
                  + "; ".join(problems) + ")")
        raise CampaignMismatchError(
            f"{path}: the {where} belongs to a different campaign (differs in"
            f" {what}); {advice}")
    if problems:
        raise CampaignMismatchError(f"{path}: cannot --extend this {where}: "
                                    + "; ".join(problems))


def _extend_problems(old: dict[str, Any], new: dict[str, Any]) -> list[str]:
    """Why ``--extend`` would refuse ``new`` on a store of ``old`` (empty: it accepts it):
    one store holds one [base] and model version; grid values may only be added."""
    problems = []
    if old["base"] != new["base"] or old["model_version"] != new["model_version"]:
        problems.append("its [base] (or model version) differs, and a store holds one")
    if set(old["sweep"]) != set(new["sweep"]):
        problems.append("its swept dimensions differ")
    else:
        for k, values in old["sweep"].items():
            missing = [v for v in values if v not in new["sweep"][k]]
            if missing:
                problems.append(f"[sweep] {k} drops {missing}")
    return problems


def check_legacy_journal(journal: Path, hashes: Iterable[str], campaign: Any) -> None:
    """A journal without a campaign line (written before version 2) is used to rebuild
    only if every point it holds (``hashes``) belongs to the campaign's grid."""
    grid = {p.hash for p in campaign.points()}
    foreign = [h for h in hashes if h not in grid]
    if foreign:
        raise CampaignMismatchError(
            f"{journal}: holds {len(foreign)} point(s) that are not in this"
            f" campaign's grid (e.g. {foreign[0][:12]}): it belongs to another campaign;"
            " use another --store, or move the journal away")


def grid_hashes(campaign: Any) -> frozenset[str] | None:
    """The hashes of every point of ``campaign``'s grid (all shards: a shard's store may
    hold points of the others after a merge); ``None`` without a campaign. An
    ``--extend``-ed campaign's grid holds every grid of its history."""
    if campaign is None:
        return None
    if getattr(campaign, "shard_of", None) is not None:
        campaign = dataclasses.replace(campaign, shard_of=None)
    return frozenset(p.hash for p in campaign.points())
