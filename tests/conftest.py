"""Fixtures shared by the test modules.

``campaign``: the module's ``TOML`` parsed as a campaign (file name ``CAMPAIGN_FILE`` of the
module, default ``t.toml``). ``power_store``: a store of a campaign computed by the hand-set
``sweep.testing:power_point`` (each TOML text run once per session). ``run_main``: a
command-line ``main(argv)`` run in-process as a subprocess would run it.
"""
from __future__ import annotations

import subprocess
from pathlib import Path

import pytest


@pytest.fixture
def campaign(request):
    """The campaign of the requesting module's ``TOML``."""
    from sweep import parse_campaign

    return parse_campaign(request.module.TOML, getattr(request.module, "CAMPAIGN_FILE", "t.toml"))


@pytest.fixture(scope="session")
def power_store(tmp_path_factory):
    """``power_store(toml, name)``: the path of a store of the campaign ``toml`` (file
    ``name``) computed by ``power_point``."""
    from sweep import parse_campaign, run_campaign

    made: dict[tuple[str, str], Path] = {}

    def make(toml: str, name: str = "t.toml") -> Path:
        if (toml, name) not in made:
            path = tmp_path_factory.mktemp("power") / "power.h5"
            run_campaign(parse_campaign(toml, name), str(path),
                         compute="sweep.testing:power_point")
            made[toml, name] = path
        return made[toml, name]

    return make


@pytest.fixture
def run_main(capsys, monkeypatch):
    """``run_main(main, argv, cwd=None)``: a command-line ``main(argv)`` run in this process as
    a subprocess would run it (in ``cwd``; ``SystemExit`` as the exit status); returns a
    :class:`subprocess.CompletedProcess` with ``returncode``, ``stdout`` and ``stderr``."""
    def call(main, argv, cwd=None) -> subprocess.CompletedProcess:
        argv = [str(a) for a in argv]
        if cwd is not None:
            monkeypatch.chdir(cwd)
        capsys.readouterr()
        try:
            code = main(argv)
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
        out = capsys.readouterr()
        return subprocess.CompletedProcess(argv, code, out.out, out.err)

    return call
