"""The HDF5 side of a store: create, open, write points, close (no policy here).

:class:`H5Writer` owns one open ``h5py.File`` of a sweep store and knows its layout
(:mod:`sweep.store.schema`); :class:`sweep.store.store.Store` decides when to create, open, repair
or rebuild it. Records are converted to the schema's column kinds by
:func:`sweep.store.cells.normalise_record` *before* they are journaled, so a record that
reaches the journal can be written.
HDF5's own file locking is off (``locking=False``): :mod:`sweep.store.lock` is the lock, and
HDF5's fails on NFS (h5py issue #1101).
"""
from __future__ import annotations

import contextlib
import json
import os
from pathlib import Path
from typing import Any

import h5py
import numpy as np
from h5py import h5a, h5d, h5g, h5s, h5t

from sweep.identity import canonical_json
from sweep.store.cells import text
from sweep.store.schema import (
    COLUMNS,
    FORMAT,
    HISTORY_VAR,
    PROFILE_VARS,
    REPLICA_VARS,
    SCHEMA_VERSION,
    profile_path,
)
from sweep.system import utc_now

__all__ = ["H5Writer", "HDF5_SIGNATURE"]

HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
_STR = h5py.string_dtype("utf-8")
_DTYPES = {"float": np.float64, "int": np.int64, "str": _STR}
_NP_DTYPES = {"float": np.float64, "int": np.int64, "str": object}
#: The table datasets grow by whole chunks (rows beyond ``n_rows`` are not committed).
_TABLE_CHUNK = 1024
def _cell(col: Any, row: dict[str, Any]) -> Any:
    return row.get(col.name, col.fill)


_F64 = h5t.IEEE_F64LE
_STR_TYPE = h5t.py_create(_STR, logical=True)
_DCPL = h5py.h5p.create(h5py.h5p.DATASET_CREATE)
_DCPL.set_obj_track_times(False)  # as h5py's create_dataset does by default


def _write_rows(dsid: Any, mtype: Any, start: int, values: np.ndarray) -> None:
    """Write ``values`` to rows ``start, start + 1, ...`` of a 1-D dataset (low level)."""
    fspace = dsid.get_space()
    fspace.select_hyperslab((start,), (len(values),))
    dsid.write(h5s.create_simple((len(values),)), fspace, values, mtype=mtype)


def _dataset(gid: Any, name: str, data: Any) -> None:
    """A contiguous float64 dataset ``name`` in group ``gid`` holding ``data``."""
    arr = np.ascontiguousarray(data, dtype=np.float64)
    space = h5s.create_simple(arr.shape) if arr.ndim else h5s.create(h5s.SCALAR)
    dset = h5d.create(gid, name.encode(), _F64, space, dcpl=_DCPL)
    if arr.size:
        dset.write(h5s.ALL, h5s.ALL, arr)


def set_campaign(f: h5py.File, campaign: Any) -> None:
    """Write the campaign identity attributes of the store root."""
    f.attrs["campaign_toml"] = campaign.text
    f.attrs["campaign_json"] = canonical_json(campaign.definition())
    f.attrs["campaign_hash"] = campaign.definition_hash()
    f.attrs["swept_fields"] = json.dumps(list(campaign.swept_fields))


class H5Writer:
    """One open store file: the table's column ids, the committed rows, the writes."""

    def __init__(self, f: h5py.File) -> None:
        self.file = f
        self.path = Path(f.filename)
        self.rows: dict[str, int] = {}
        self.seq_of: dict[str, int] = {}

    @classmethod
    def create(cls, path: str | Path, campaign: Any) -> H5Writer:
        """A new, empty store file at ``path`` (truncating whatever is there)."""

        f = h5py.File(path, "w", locking=False)
        f.attrs["schema_version"] = SCHEMA_VERSION
        f.attrs["format"] = FORMAT
        f.attrs["created"] = utc_now()
        f.attrs["writer_open"] = False
        set_campaign(f, campaign)
        table = f.create_group("table")
        table.attrs["n_rows"] = 0
        for col in COLUMNS:
            table.create_dataset(col.name, shape=(0,), maxshape=(None,), chunks=(_TABLE_CHUNK,),
                                 dtype=_DTYPES[col.kind])
        f.create_group("profiles")
        f.create_group("runs")
        return cls(f)

    @classmethod
    def open(cls, path: str | Path) -> H5Writer:
        return cls(h5py.File(path, "r+", locking=False))

    def prepare(self) -> int:
        """Drop uncommitted rows and profile groups; index the committed rows.

        Returns the number of orphan profile groups removed.
        """
        f = self.file
        self._parents: dict[str, Any] = {}  # /profiles/<hh> group ids, by hh
        table = f["table"]
        n = int(table.attrs["n_rows"])
        for col in COLUMNS:
            if table[col.name].shape[0] != n:
                table[col.name].resize((n,))
        # low-level ids of the table columns with their memory types (h5py's high-level
        # indexing costs ~50 us per write; ~10 us this way)
        self._columns = [(col, table[col.name].id, _NP_DTYPES[col.kind],
                          h5t.py_create(np.dtype(_DTYPES[col.kind]) if col.kind != "str"
                                        else _STR))
                         for col in COLUMNS]
        hashes = [text(h) for h in table["hash"][:n]]
        self.rows = {h: i for i, h in enumerate(hashes)}
        self.seq_of = {h: int(s) for h, s in zip(hashes, table["seq"][:n], strict=False)}
        removed = 0
        for hh in list(f["profiles"]):
            for h in list(f["profiles"][hh]):
                if h not in self.rows:
                    del f["profiles"][hh][h]
                    removed += 1
        return removed

    def status_of(self, h: str) -> str:
        return text(self.file["table"]["status"][self.rows[h]])

    def write_many(self, records: list[dict[str, Any]]) -> None:
        """Write normalised records (profiles, then rows, then ``n_rows``); no sync."""
        if not records:
            return
        f = self.file
        table = f["table"]
        n = int(table.attrs["n_rows"])
        new_rows: list[dict[str, Any]] = []  # appended at n, n + 1, ...
        old_rows: dict[int, dict[str, Any]] = {}  # committed rows written again
        index_of: dict[str, int] = {}
        for rec in records:
            row = rec["row"]
            h = row["hash"]
            index = index_of.get(h, self.rows.get(h))
            self._write_profiles(rec, replace=index is not None)
            if index is None:
                index = n + len(new_rows)
                new_rows.append(row)
            elif index >= n:
                new_rows[index - n] = row
            else:
                old_rows[index] = row
            index_of[h] = index
        k = len(new_rows)
        for col, dsid, dtype, mtype in self._columns:
            if k:
                if dsid.shape[0] < n + k:
                    dsid.set_extent((-(-(n + k) // _TABLE_CHUNK) * _TABLE_CHUNK,))
                _write_rows(dsid, mtype, n, np.array([_cell(col, row) for row in new_rows],
                                                     dtype=dtype))
            for index, row in old_rows.items():
                _write_rows(dsid, mtype, index, np.array([_cell(col, row)], dtype=dtype))
        if k:
            table.attrs["n_rows"] = n + k  # the commit point of the rows
        for rec in records:
            h = rec["row"]["hash"]
            self.rows[h] = index_of[h]
            self.seq_of[h] = int(rec["row"].get("seq", -1))

    def _write_profiles(self, record: dict[str, Any], replace: bool) -> None:
        """Write ``/profiles/<hh>/<hash>`` (low-level h5py: ~2x faster per point)."""
        f = self.file
        h = record["row"]["hash"]
        if replace:
            name = profile_path(h)
            if name in f:
                del f[name]
        profiles = record.get("profiles") or {}
        if not profiles:
            return
        parent = self._parents.get(h[:2])
        if parent is None:
            group = f["profiles"].get(h[:2])
            if group is None:
                group = f["profiles"].create_group(h[:2])
            parent = self._parents[h[:2]] = group.id
        try:
            gid = h5g.create(parent, h.encode())
        except ValueError:  # a leftover of a failed commit
            parent.unlink(h.encode())
            gid = h5g.create(parent, h.encode())
        attr = h5a.create(gid, b"hash", _STR_TYPE, h5s.create(h5s.SCALAR))
        attr.write(np.array(h, dtype=_STR))  # as h5py's attrs["hash"] = h writes it
        for name in PROFILE_VARS:
            _dataset(gid, name, profiles.get(name, ()))
        _dataset(gid, HISTORY_VAR[0], record.get("residual_history", ()))
        for name in REPLICA_VARS:
            if name in profiles:          # optional: ensembles of schema 3 write them
                _dataset(gid, name, profiles[name])

    def durable(self) -> None:
        """Flush the file and ``fsync`` it."""
        self.file.flush()
        with contextlib.suppress(Exception):
            os.fsync(self.file.id.get_vfd_handle())

    def trim(self) -> None:
        """Trim the chunk-sized growth of the table columns to ``n_rows``."""
        table = self.file["table"]
        n = int(table.attrs["n_rows"])
        for col in COLUMNS:
            if table[col.name].shape[0] != n:
                table[col.name].resize((n,))

    def close(self) -> None:
        with contextlib.suppress(Exception):
            self.file.close()
