"""A record of another campaign in a journal is never stored, whatever became of the
journal's campaign line, and ``sweep validate --deep`` reports it before a run sets it
aside (issue [harden] 1: when the only campaign line failed its checksum, every record was
read as a legacy one, without the grid check, and a foreign point replayed into the
intact file: ``129/128 points stored``)."""
from __future__ import annotations

import json

import pytest

import sweep
from sweep import parse_campaign, run_campaign
from sweep.cli import main
from sweep.store.journal import journal_path, rejected_path
from tests.sweep.helpers import make_unclean, table

TOML = "[base]\nL_sheet = 6.0\n[sweep]\nL_x = [0.5, 1.5]\neps = [0.2, 0.4, 0.6]\n"
FAKE = "sweep.testing:fake_point"


def _lines(path):
    return journal_path(path).read_bytes().splitlines(keepends=True)


def _corrupt_campaign_lines(path):
    """Alter one character inside every campaign line: each then fails its checksum."""
    out = []
    for line in _lines(path):
        if line.startswith(b'{"journal"'):
            i = line.index(b'"campaign_json":"') + len(b'"campaign_json":"') + 2
            line = line[:i] + (b"X" if line[i:i + 1] != b"X" else b"Y") + line[i + 1:]
        out.append(line)
    journal_path(path).write_bytes(b"".join(out))


@pytest.mark.parametrize("unclean", [False, True])
def test_a_foreign_record_after_a_corrupt_campaign_line_is_set_aside(tmp_path, unclean,
                                                                     capsys, run_main):
    path, other = tmp_path / "s.h5", tmp_path / "o.h5"
    campaign = parse_campaign(TOML)
    run_campaign(campaign, str(path), compute=FAKE)
    ref = table(path)
    # another campaign: another L_sheet, so every one of its points is foreign
    run_campaign(parse_campaign(TOML.replace("6.0", "7.0")), str(other), compute=FAKE)
    foreign = [x for x in _lines(other) if x.startswith(b'{"row"')][:1]
    _corrupt_campaign_lines(path)
    with open(journal_path(path), "ab") as fh:
        fh.write(b"".join(foreign))
    if unclean:
        make_unclean(path)
    else:  # validate --deep says what the next run will set aside, before it does
        got = run_main(main, ["validate", path, "--deep"])
        assert got.returncode != 0
        assert "not in this campaign's grid" in got.stdout + got.stderr
    capsys.readouterr()
    s = run_campaign(campaign, str(path), compute=FAKE)
    err = capsys.readouterr().err
    assert s.computed == 0
    assert "not in this campaign's grid" in err, err
    df = sweep.load(path)
    assert len(df) == 6 and set(df["L_x"]) == {0.5, 1.5}
    assert table(path).equals(ref)
    assert sweep.validate(path) == []
    reasons = [json.loads(x)["reason"] for x in rejected_path(path).read_text().splitlines()]
    assert any("not in this campaign's grid" in r for r in reasons), reasons
    assert run_main(main, ["validate", path, "--deep"]).returncode == 0


def test_validate_deep_reports_a_plain_out_of_grid_line(tmp_path, run_main):
    """A checksummed record of another campaign appended to an intact journal: the next
    run sets it aside; ``validate --deep`` says so first."""
    path, other = tmp_path / "s.h5", tmp_path / "o.h5"
    run_campaign(parse_campaign(TOML), str(path), compute=FAKE)
    run_campaign(parse_campaign(TOML.replace("0.2, 0.4, 0.6", "0.3")), str(other),
                 compute=FAKE)
    assert run_main(main, ["validate", path, "--deep"]).returncode == 0
    with open(journal_path(path), "ab") as fh:
        fh.write(b"".join(x for x in _lines(other) if x.startswith(b'{"row"')))
    got = run_main(main, ["validate", path, "--deep"])
    assert got.returncode != 0
    assert "would be set aside" in got.stdout + got.stderr
    assert "not in this campaign's grid" in got.stdout + got.stderr


def test_a_legacy_journal_is_still_read_without_checksums(tmp_path):
    """Records without checksums in a journal with no checksummed line (version 1) are
    still read: the store rebuilds from them."""
    path = tmp_path / "s.h5"
    campaign = parse_campaign(TOML)
    run_campaign(campaign, str(path), compute=FAKE)
    ref = table(path)
    legacy = []
    for line in _lines(path):
        if line.startswith(b'{"row"'):
            obj = json.loads(line)
            obj.pop("crc32")
            legacy.append(json.dumps(obj).encode() + b"\n")
    journal_path(path).write_bytes(b"".join(legacy))
    make_unclean(path)
    run_campaign(campaign, str(path), compute=FAKE)
    assert table(path).drop(columns=["message"]).equals(ref.drop(columns=["message"]))
