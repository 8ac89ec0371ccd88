"""sweep.store.journal: checksummed lines, a torn tail cut, bad lines set aside with their
reasons, the last record of a point by seq, hand-outs counted until its next record."""
from __future__ import annotations

import json

import pytest

from floewave import MODEL_VERSION
from sweep.errors import BadJournalLineError
from sweep.store.journal import Journal, check_record, decode, encode, journal_path
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
