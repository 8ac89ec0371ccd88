"""``sweep merge``: combine shard stores of one campaign into one store, by hash."""
from __future__ import annotations

import contextlib
import os
import signal
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from sweep.config import parse_campaign
from sweep.errors import CampaignMismatchError, Interrupted, SchemaVersionError, StoreError
from sweep.identity import DIMENSIONS
from sweep.provenance import environment
from sweep.store import reader
from sweep.store.cells import text
from sweep.store.migrate import migration_steps
from sweep.store.record import Record
from sweep.store.schema import SCHEMA_VERSION
from sweep.store.store import Store
from sweep.system import STOP_SIGNALS, take_start_up_stop

__all__ = ["merge", "iter_records"]

#: Points per group commit (one journal fsync and one HDF5 flush for all of them).
_BATCH = 256


def iter_records(path: str | Path) -> Iterator[Record]:
    """Every committed point of a store as a :class:`sweep.store.record.Record`."""
    with reader.open_file(path) as f:
        yield from reader.iter_records(f)


class _Stop:
    """SIGINT/SIGTERM/SIGUSR1 during a merge: finish the current commit, then stop
    (:class:`Interrupted`, exit 6; the output is closed and consistent)."""

    def __init__(self) -> None:
        self.requested = ""
        self._old: dict[int, Any] = {}

    def __enter__(self) -> _Stop:
        self.requested = take_start_up_stop()  # a start-up stop whose exception was lost
        for sig in STOP_SIGNALS:
            with contextlib.suppress(ValueError):  # not the main thread
                self._old[sig] = signal.signal(sig, self._handle)
        return self

    def _handle(self, signum: int, frame: Any) -> None:
        self.requested = self.requested or signal.Signals(signum).name

    def check(self, merged: int) -> None:
        if self.requested:
            raise Interrupted(f"merge stopped by {self.requested} after {merged} points;"
                              " the output store is closed and consistent — the merge is"
                              " resumable: run the same command again")

    def __exit__(self, *exc: Any) -> None:
        for sig, old in self._old.items():
            with contextlib.suppress(ValueError, TypeError):
                signal.signal(sig, old)


def merge(output: str | Path, inputs: list[str | Path]) -> str:
    """Merge shard stores into ``output`` (created, or extended if it exists).

    All inputs (and an existing output) must hold the same campaign definition. A point
    present in several inputs is stored once; a ``failed`` copy is replaced by a
    successful one.

    Raises
    ------
    CampaignMismatchError
        When the inputs belong to different campaigns.
    """
    hashes, texts = [], []
    for path in inputs:
        if Path(output).exists() and Path(path).exists() and \
                os.path.samefile(output, path):
            raise StoreError(f"{path}: is the output store itself; merge other stores"
                             " into it")
        try:
            with reader.open_file(path) as f:
                version = f.attrs.get("schema_version")
                try:
                    number = int(version)
                except (TypeError, ValueError):
                    number = -1
                try:
                    migration_steps(number)
                except SchemaVersionError:
                    shown = number if number >= 0 else repr(version)
                    raise StoreError(f"{path}: schema version {shown}: this sweep"
                                     f" (schema version {SCHEMA_VERSION}) cannot merge it"
                                     ) from None
                if bool(f.attrs.get("writer_open", False)):
                    raise StoreError(
                        f"{path}: is open: a run is writing it, or its writer died (kill -9,"
                        " a lost node) and its journal may hold points its file lacks;"
                        " finish or resume that run first (`sweep run CAMPAIGN --store"
                        f" {path}` replays its journal), then merge; nothing was merged")
                hashes.append(text(f.attrs["campaign_hash"]))
                texts.append(text(f.attrs["campaign_toml"]))
                # every row still hashes to its hash: a merge never spreads a bad row
                cols = reader.table_columns(f, ("hash", "config_json", "provenance",
                                                *DIMENSIONS))
                reader.check_hashes(path, cols["hash"], cols["config_json"],
                                    reader.model_version(f), cols["provenance"],
                                    {k: cols[k] for k in DIMENSIONS if k in cols})
        except StoreError:
            raise
        except (OSError, KeyError, ValueError, RuntimeError, TypeError) as exc:
            why = reader.not_a_store(path) if isinstance(exc, OSError) else None
            raise StoreError(f"{path}: not a readable sweep store: {why or exc}") from None
    if len(set(map(os.path.realpath, inputs))) != len(inputs):
        raise StoreError("an input store is given twice")
    if len(set(hashes)) != 1:
        odd = [str(p) for p, h in zip(inputs, hashes, strict=False) if h != hashes[0]]
        raise CampaignMismatchError(f"cannot merge stores of different campaigns: "
                                    f"{', '.join(odd)} differ from {inputs[0]}")
    campaign = parse_campaign(texts[0], f"{inputs[0]}:campaign_toml")
    if campaign.definition_hash() != hashes[0]:
        raise CampaignMismatchError(f"{inputs[0]}: its campaign text no longer gives its"
                                    " campaign hash (model version or defaults changed)")
    added = replaced = duplicates = 0
    info = environment()
    info["command"] = f"sweep merge {output} " + " ".join(map(str, inputs))
    stop = _Stop()
    with stop, Store(output, campaign, run_info=info) as store:
        stop.check(0)  # a start-up stop whose exception was lost: nothing merged
        for path in inputs:
            # group commits of _BATCH points within an input (a store holds each hash
            # once, so no staged record can shadow another) and at its end (the next
            # input sees this one's points)
            for rec in iter_records(path):
                if store.staged >= _BATCH:
                    store.commit()
                    stop.check(added + replaced)
                h = rec["row"]["hash"]
                if h in store:
                    if store.status_of(h) == "failed" and rec["row"]["status"] != "failed":
                        store.add(rec)
                        replaced += 1
                    else:
                        duplicates += 1
                    continue
                store.add(rec)
                added += 1
            store.commit()
            stop.check(added + replaced)
        total = len(store)
    grid = len(campaign.points())
    rest = (f" ({grid - total} still to compute: finish the shards, then merge again)"
            if total < grid else "")
    return (f"merged {len(inputs)} store(s) into {output}: {added} points added,"
            f" {replaced} failed points replaced, {duplicates} duplicates skipped;"
            f" {total} of the campaign's {grid} grid points stored{rest}")
