"""sweep.store.journal: checksummed lines, a torn tail cut, bad lines set aside with their
reasons, the last record of a point by seq, hand-outs counted until its next record."""
from __future__ import annotations

import json

import pytest

from floewave import MODEL_VERSION
from sweep.errors import BadJournalLineError
from sweep.store.journal import (
    Journal,
    check_record,
    decode,
    encode,
    journal_path,
    rejected_path,
)
from sweep.store.schema import STATUSES

TOML = "[base]\nL_sheet = 6.0\n[sweep]\neps = [0.2, 0.4]\n"


def record(p, seq, status="converged"):
    return {"row": {"hash": p.hash, "status": status, "seq": seq, "run": 0,
                    "config_json": json.dumps(p.config.to_dict(), sort_keys=True,
                                              separators=(",", ":"))},
            "profiles": {}, "residual_history": []}


def test_encode_decode_round_trip_and_the_checksum_catches_a_change():
    line = encode({"release": "ab", "n": 1})
    assert line.endswith(b'"}\n') and b'"crc32":"' in line
    assert decode(line) == ({"release": "ab", "n": 1}, True)
    with pytest.raises(BadJournalLineError, match="checksum mismatch"):
        decode(line.replace(b'"n":1', b'"n":2'))
    with pytest.raises(BadJournalLineError, match="no checksum"):
        decode(b'{"release": "ab"}\n')
    assert decode(b'{"release": "ab"}\n', require_checksum=False) == ({"release": "ab"}, False)


def test_a_torn_last_line_is_cut_on_open(tmp_path):
    path = tmp_path / "s.h5.journal"
    path.write_bytes(encode({"release": "a"}) + b'{"row":{"hash":"01')
    j = Journal(path)
    assert j.trim_torn_tail() == len(b'{"row":{"hash":"01')
    assert path.read_bytes() == encode({"release": "a"})


def test_scan_keeps_the_highest_seq_and_counts_hand_outs_since(tmp_path, campaign):
    p, q = campaign.points()
    j = Journal(journal_path(tmp_path / "s.h5"))
    j.open_for_append()
    j.append([encode(record(p, 5)), encode(record(p, 3, "failed")),  # older seq, later line
              encode({"handout": q.hash, "run": 1, "worker": 2, "alone": True}),
              encode({"handout": p.hash, "run": 1, "worker": 1, "alone": False})])
    j.close()
    scan = j.scan(MODEL_VERSION, STATUSES)
    assert scan.latest[p.hash][0] == 5 and scan.latest[p.hash][2] == "converged"
    assert scan.handouts == {q.hash: [(1, 2, True)], p.hash: [(1, 1, False)]}
    assert scan.max_seq == 5 and scan.max_run == 1 and not scan.bad


def test_bad_lines_are_set_aside_with_their_reasons(tmp_path, campaign):
    p, q = campaign.points()
    wrong = record(p, 1)
    wrong["row"]["hash"] = q.hash  # p's config under q's hash
    j = Journal(journal_path(tmp_path / "s.h5"), tmp_path / "s.h5.journal.rejected")
    j.open_for_append()
    j.append([encode(record(p, 0)), encode(wrong),
              encode(record(q, 2)).replace(b'"seq":2', b'"seq":9')])
    scan = j.scan(MODEL_VERSION, STATUSES)
    reasons = [r for _, _, r in scan.bad]
    assert len(reasons) == 2 and "does not hash to its hash" in reasons[0]
    assert "checksum" in reasons[1]
    j.set_aside(scan.bad)
    j.close()
    assert list(j.scan(MODEL_VERSION, STATUSES).latest) == [p.hash]
    rejected = [json.loads(x) for x in (tmp_path / "s.h5.journal.rejected").read_text()
                .splitlines()]
    assert [r["reason"] for r in rejected] == reasons and all(r["time"] for r in rejected)


def test_check_record_names_what_is_wrong(campaign):
    p = campaign.points()[0]
    assert check_record(record(p, 0), MODEL_VERSION, STATUSES) == ""
    bad = record(p, 0, "exploded")
    assert "exploded" in check_record(bad, MODEL_VERSION, STATUSES)


# ---------------------------------------------------------------- packed arrays (version 3)
FAKE = "sweep.testing:fake_point"


def _stored(tmp_path):
    """A campaign of TOML run into a store: (campaign, store path, journal path, lines)."""
    from sweep import parse_campaign, run_campaign

    campaign = parse_campaign(TOML)
    path = tmp_path / "s.h5"
    run_campaign(campaign, str(path), compute=FAKE)
    jp = journal_path(path)
    return campaign, path, jp, jp.read_bytes().splitlines(keepends=True)


def _as_version_2(line):
    """A journal line again with its arrays as JSON lists, as journal version 2 wrote it."""
    return encode(json.loads(json.dumps(decode(line)[0], default=lambda a: a.tolist())))
def test_packed_arrays_round_trip_to_the_bit():
    """NaN payloads, signed zeros, infinities, subnormals, 2-D and empty arrays: the same
    bytes after encode and decode; lists (records of before version 3) stay lists."""
    import numpy as np

    from sweep.store.packed import pack_array, unpack_array

    odd = np.array([0.0, -0.0, np.inf, -np.inf, 5e-324, 1 / 3, -1.7976931348623157e308])
    payload = np.frombuffer(np.uint64(0x7FF8_0000_DEAD_BEEF).tobytes(), dtype=np.float64)
    arrays = {"a": np.concatenate([odd, payload]),
              "b": np.arange(12.0).reshape(3, 4) / 7, "c": np.zeros(0)}
    line = encode({"row": {"hash": "x"}, "profiles": arrays,
                   "residual_history": np.array([1e-3, np.nan])})
    obj, checked = decode(line)
    assert checked
    for name, arr in arrays.items():
        got = obj["profiles"][name]
        assert got.dtype == np.float64 and got.shape == arr.shape and got.flags.writeable
        assert got.tobytes() == arr.tobytes(), name
    assert obj["residual_history"].tobytes() == np.array([1e-3, np.nan]).tobytes()
    assert decode(encode(obj))[0]["profiles"]["b"].tobytes() == arrays["b"].tobytes()
    old = decode(encode({"row": {"hash": "x"}, "profiles": {"a": [1.0, 2.5]},
                         "residual_history": []}))[0]
    assert old["profiles"]["a"] == [1.0, 2.5] and old["residual_history"] == []
    assert unpack_array([1.0]) == [1.0]
    packed = pack_array(np.array([1.5, -2.0]))
    assert set(packed) == {"f8", "shape"} and packed["shape"] == [2]
    zero_d = unpack_array(pack_array(np.array(-0.0)))
    assert zero_d.shape == () and zero_d.tobytes() == np.array(-0.0).tobytes()
    fortran = np.asfortranarray(np.arange(6.0).reshape(2, 3))
    assert unpack_array(pack_array(fortran[:, ::2])).tolist() == [[0.0, 2.0], [3.0, 5.0]]
    # big-endian or integer input is stored as float64, little-endian
    assert unpack_array(pack_array(np.array([3, 4], dtype=">i4"))).tolist() == [3.0, 4.0]


@pytest.mark.parametrize("bad", [{"f8": "***", "shape": [1]}, {"f8": None, "shape": [1]},
                                 {"f8": "AAAAAAAAAAA=", "shape": [2]},
                                 {"f8": "AAAAAAAAAAA=", "shape": "x"},
                                 {"f8": "AAAAAAAAAAA=", "shape": "1"},
                                 {"f8": "AAAAAAAAAAA=", "shape": [-1]},
                                 {"f8": "AAAAAAAAAAA=", "shape": [True]},
                                 {"f8": "AAAAAAAAAAA=", "shape": [1.0]},
                                 {"f8": "AAAAAAAAAAA=", "shape": [float("inf")]},
                                 {"f8": "AAAAAAAAAAA=", "shape": [1e999]},
                                 {"f8": "AAAAAAAAAAA="},
                                 {"f8": "", "shape": [0] * 40}])
def test_an_unreadable_packed_array_is_a_bad_line(bad):
    """A packed array that is not base64 or does not fill its shape: the line is bad (set
    aside on open, as any line that does not parse), whatever its checksum says."""
    line = encode({"row": {"hash": "x"}, "profiles": {"a": bad}, "residual_history": []})
    with pytest.raises(BadJournalLineError, match="unreadable packed array"):
        decode(line)


def test_a_store_is_rebuilt_whole_from_a_journal_of_lists(tmp_path):
    """A journal whose records hold their arrays as JSON lists (version 2, as stores of
    before version 3 have them) rebuilds the store to the same table and the same profile
    bytes as the journal of packed arrays that the run wrote."""
    import h5py
    import numpy as np

    from sweep import run_campaign
    from sweep.store import reader
    from tests.sweep.helpers import table

    campaign, path, jp, lines = _stored(tmp_path)
    ref = table(path)
    with h5py.File(path, "r") as f:
        before = {h: reader.profile_group(f, h) for h in ref.index}
    assert sum(b'"f8":"' in line for line in lines) >= 2  # written packed
    as_lists = [_as_version_2(line) for line in lines]
    assert not any(b'"f8":"' in line for line in as_lists)
    jp.write_bytes(b"".join(as_lists))
    path.unlink()
    assert run_campaign(campaign, str(path), compute=FAKE).computed == 0
    assert table(path).equals(ref)
    with h5py.File(path, "r") as f:
        for h, (profiles, history) in before.items():
            got, got_history = reader.profile_group(f, h)
            assert got.keys() == profiles.keys()
            assert all(np.asarray(got[k]).tobytes() == np.asarray(v).tobytes()
                       for k, v in profiles.items())
            assert np.asarray(got_history).tobytes() == np.asarray(history).tobytes()


def test_a_journal_of_a_newer_version_is_refused_and_left_alone(tmp_path):
    """A campaign line of a journal version beyond this sweep's: the store is not opened,
    no line is set aside, the files are unchanged, and ``sweep run`` exits 3."""
    from sweep import run_campaign
    from sweep.cli import main
    from sweep.errors import StoreError
    from sweep.store.journal import JOURNAL_VERSION

    campaign, path, jp, lines = _stored(tmp_path)
    head = decode(lines[0])[0]
    assert head["version"] == JOURNAL_VERSION
    head["version"] = JOURNAL_VERSION + 1
    jp.write_bytes(encode(head) + b"".join(lines[1:]))
    before = (path.read_bytes(), jp.read_bytes())
    with pytest.raises(StoreError, match=f"journal version {JOURNAL_VERSION + 1}"):
        run_campaign(campaign, str(path), compute=FAKE)
    cfg = tmp_path / "c.toml"
    cfg.write_text(TOML)
    assert main(["run", str(cfg), "--store", str(path), "--no-bar", "--compute", FAKE]) == 3
    assert (path.read_bytes(), jp.read_bytes()) == before
    assert not rejected_path(path).exists()


def test_resuming_a_journal_of_an_older_version_marks_it_with_this_version(tmp_path):
    """A journal whose last campaign line is of version 2 gets a campaign line of this
    version (same campaign) before this sweep's records, so that a sweep that reads only
    version 2 would see a newer journal, not records to set aside."""
    from sweep import run_campaign
    from sweep.store.journal import JOURNAL_VERSION

    campaign, path, jp, lines = _stored(tmp_path)
    head = decode(lines[0])[0]
    head["version"] = 2
    records = [i for i, line in enumerate(lines) if b'"row"' in line]
    old = [_as_version_2(line) for line in lines[1:records[-1]]]  # the last record dropped
    jp.write_bytes(encode(head) + b"".join(old))
    path.unlink()
    assert run_campaign(campaign, str(path), compute=FAKE).computed == 1
    scan = Journal(jp).scan(MODEL_VERSION, STATUSES)
    assert [h["version"] for h in scan.headers] == [2, JOURNAL_VERSION]
    assert scan.headers[0]["campaign_hash"] == scan.headers[1]["campaign_hash"]
    after = jp.read_bytes().splitlines()
    second = after.index(encode(scan.headers[1])[:-1])
    assert all(b'"f8":"' not in line for line in after[:second])  # the lists before it
    assert any(b'"f8":"' in line for line in after[second:])      # this sweep's after it
