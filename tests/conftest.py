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


# ------------------------------------------------------------------ parallel runs (xdist)
#: Modules whose tests share a module- or session-scoped fixture worth computing once: under
#: ``pytest -n 2`` each runs whole on one worker (see :func:`pytest_xdist_make_scheduler`).
GROUPED = ("tests/test_slurm.py",  # one Slurm cluster and one reference job per session
           "tests/paper/test_herman2019_qualitative.py", "tests/floewave/test_iteration.py",
           "tests/sweep/test_papercheck.py", "tests/sweep/test_ensemble_store.py",
           "tests/sweep/test_config.py", "tests/sweep/test_stats.py",
           "tests/sweep/test_figures.py")
#: The longest tests and modules, handed out first under xdist so that no long one is left
#: alone at the end (longest first); the rest keep pytest's order.
FIRST = ("tests/test_slurm.py",
         "tests/test_reproducible.py::test_campaign_bits_in_process_mpi_and_after_kill_and_resume",
         "tests/sweep/test_torture.py::test_kill_9_whole_mpi_campaign_torture",
         "tests/test_docs.py::test_every_code_block_runs[docs/guide.md]",
         "tests/test_docs.py::test_every_code_block_runs[README.md]",
         "tests/paper/test_herman2019_qualitative.py",
         "tests/test_reproducible.py::test_point_bits_do_not_depend_on_the_jit_cache")


def pytest_xdist_make_scheduler(config, log):
    """``pytest -n N``: tests are handed out one by one (xdist's ``load``), except that each
    module of :data:`GROUPED` goes whole to one worker, in the order of the collection
    (:data:`FIRST` first). (xdist's own ``--dist loadgroup`` cannot be used: its
    ``xdist_group`` marks do not reach the scheduler under pytest 9.)"""
    from xdist.scheduler import LoadScopeScheduling

    class Scheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            module = nodeid.split("::")[0]
            return module if module in GROUPED else nodeid

    config.option.loadscopereorder = False  # keep the order of the collection
    return Scheduling(config, log)


def pytest_collection_modifyitems(config, items):
    """In an xdist worker: :data:`FIRST` first (a plain run keeps pytest's order)."""
    if not hasattr(config, "workerinput"):
        return

    def rank(item) -> int:
        for i, key in enumerate(FIRST):
            if item.nodeid == key or item.nodeid.split("::")[0] == key:
                return i
        return len(FIRST)

    items.sort(key=rank)  # stable: a module's tests stay together


def pytest_terminal_summary(terminalreporter):
    """The ``("summary", line)`` user properties of the tests (what Slurm reported in
    tests/test_slurm.py), after the results, in the order of the tests."""
    lines = []
    for reports in terminalreporter.stats.values():
        for rep in reports:
            for name, value in getattr(rep, "user_properties", ()):
                if name == "summary" and getattr(rep, "when", "") == "teardown":
                    lines.append(value)
    if lines:
        terminalreporter.write_line("")
        for line in lines:
            terminalreporter.write_line(line)


@pytest.fixture(scope="session")
def compiled_kernels():
    """The numba kernels of the small real campaigns (:data:`sweep.testing.SMALL_REAL_BASE`)
    compiled in this process, and so in the on-disk cache the test's subprocesses load: for
    tests that time a subprocess (the torture test sets its kill times from an uninterrupted
    run, which must not include the compilation)."""
    from floewave import run_point
    from sweep import parse_campaign
    from sweep.testing import SMALL_REAL_BASE

    run_point(parse_campaign(SMALL_REAL_BASE + "[sweep]\nL_x = [3.0]\n").points()[0].config)
