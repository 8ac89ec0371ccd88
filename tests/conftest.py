"""Fixtures shared by the test modules, the two tiers, and the kernels compiled once.

**Tiers.** ``python -m pytest -q -n 2`` runs the fast tier: every test not marked ``slow``.
``-m slow`` runs the slow tier (fresh interpreters, Slurm, MPI torture, docs walks with a
launcher, paper campaigns, long physics runs), ``--all`` both; any ``-m`` expression, or a
test named by its node id, overrides the default. Every behaviour a slow test proves is also
proven in the fast tier, by a smaller configuration (see each slow test's marker comment).

**Kernels compiled once.** Under xdist (``-n N``) the controller compiles the numba kernels
the tests use into the on-disk cache before it starts the workers
(:func:`pytest_sessionstart`), so that the workers load them instead of each compiling the
same kernels at the same time.

``campaign``: the module's ``TOML`` parsed as a campaign (file name ``CAMPAIGN_FILE`` of the
module, default ``t.toml``). ``power_store``: a store of a campaign computed by the hand-set
``sweep.testing:power_point`` (each TOML text run once per session). ``run_main``: a
command-line ``main(argv)`` run in-process as a subprocess would run it.
``refused_at_once``: no wait for a killed writer before a live one is refused.

**Commands in processes of their own** (``python -m sweep …``) are forked from an interpreter
that imported sweep once (tests/forkserver.py) where the test is about the command's life,
not the interpreter's start-up.
"""
from __future__ import annotations

import os
import subprocess
import time
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


@pytest.fixture
def refused_at_once(monkeypatch):
    """A store held by a live writer is refused after 0.05 s instead of
    :data:`sweep.store.lock.KILLED_WRITER_WAIT` (1 s, the time a writer killed a moment
    ago may take to exit: tests/sweep/test_lock.py proves that wait), in this process:
    for the tests whose holder is alive throughout."""
    import sweep.store.lock

    monkeypatch.setattr(sweep.store.lock, "KILLED_WRITER_WAIT", 0.05)


# ------------------------------------------------------------------ parallel runs (xdist)
#: Modules whose tests share a module- or session-scoped fixture worth computing once: under
#: ``pytest -n 2`` each runs whole on one worker (see :func:`pytest_xdist_make_scheduler`).
GROUPED = ("tests/test_slurm.py",  # one Slurm cluster and one reference job per session
           "tests/herman2019/test_qualitative.py", "tests/floewave/test_iteration.py",
           "tests/herman2019/test_check.py", "tests/sweep/test_ensemble_store.py",
           "tests/sweep/test_config.py", "tests/sweep/test_stats.py",
           "tests/sweep/test_figures.py",
           "tests/sweep/test_report.py")  # its report page, built once
#: Modules that call jitted kernels directly (not through ``run_point``, whose kernels the
#: controller compiles first: :func:`pytest_sessionstart`): numba compiles each such entry
#: point for its own signature, so they run on one worker, which compiles each once.
KERNEL_CALLERS = ("tests/floewave/test_kernels.py", "tests/floewave/test_drag.py",
                  "tests/floewave/test_forces.py", "tests/floewave/test_exact_drag.py",
                  "tests/floewave/test_drag_every.py")
#: The longest tests and modules, handed out first under xdist so that no long one is left
#: alone at the end (longest first); the rest keep pytest's order.
FIRST = ("tests/test_slurm.py",
         "tests/test_reproducible.py::test_point_bits_do_not_depend_on_the_jit_cache",
         "tests/sweep/test_torture.py::test_kill_9_whole_mpi_campaign_torture",
         "tests/test_docs.py::test_every_code_block_runs[docs/guide.md-launcher]",
         "tests/test_docs.py::test_every_code_block_runs[README.md-launcher]",
         "tests/test_reproducible.py::test_a_change_in_a_callee_file_recompiles_the_cached_callers",
         "tests/test_docs.py::test_every_code_block_runs[docs/guide.md-in-process]",
         "tests/test_docs.py::test_every_code_block_runs[README.md-in-process]",
         "tests/sweep/test_mpi.py::test_mpiexec_3_real_points_equal_one_rank",
         "tests/herman2019/test_qualitative.py")


def pytest_xdist_make_scheduler(config, log):
    """``pytest -n N``: tests are handed out one by one (xdist's ``load``), except that each
    module of :data:`GROUPED` goes whole to one worker, and so do all of
    :data:`KERNEL_CALLERS` together, in the order of the collection
    (:data:`FIRST` first). (xdist's own ``--dist loadgroup`` cannot be used: its
    ``xdist_group`` marks do not reach the scheduler under pytest 9.)"""
    from xdist.scheduler import LoadScopeScheduling

    class Scheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            module = nodeid.split("::")[0]
            if module in KERNEL_CALLERS:
                return "kernel callers"
            return module if module in GROUPED else nodeid

    config.option.loadscopereorder = False  # keep the order of the collection
    return Scheduling(config, log)


# ------------------------------------------------------------------------------- the tiers
def pytest_addoption(parser):
    parser.addoption("--all", action="store_true", dest="all_tiers",
                     help="run both tiers (default: the fast tier only; -m slow: the slow one)")


def _deselect_slow(config, items) -> None:
    """The fast tier by default: ``slow`` tests are deselected unless ``--all``, a ``-m``
    expression, or the test's own node id on the command line selects them."""
    if config.getoption("all_tiers") or config.getoption("markexpr"):
        return
    named = [a for a in config.args if "::" in a]
    keep, slow = [], []
    for item in items:
        if item.get_closest_marker("slow") and not any(item.nodeid.startswith(a)
                                                        for a in named):
            slow.append(item)
        else:
            keep.append(item)
    if slow:
        config.hook.pytest_deselected(items=slow)
        items[:] = keep


def pytest_collection_modifyitems(config, items):
    """The fast tier unless told otherwise (:func:`_deselect_slow`); in an xdist worker
    :data:`FIRST` first (a plain run keeps pytest's order)."""
    _deselect_slow(config, items)
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


# ------------------------------------------------------------- kernels compiled once per run
#: Option sets (over :data:`_WARM_BASE`) whose kernels the controller compiles before the
#: workers start: the ones that tests on both workers, and the ``sweep run`` and ``mpiexec``
#: subprocesses of the tests, would otherwise each compile: the default time loops (spin-up
#: and averaging), the exact drag's, the confined window and the march of both couplings.
#: (The contact-law and integrator options are compiled by the one worker that runs
#: :data:`KERNEL_CALLERS`, where they are used.)
WARM = ({}, {"drag_integration": "exact"}, {"confined": True},
        {"coupling": "mean", "protocol": "noise_floor"})
_WARM_BASE = dict(L_x=3.0, L_sheet=12.0, n0=1, n0_warm=0, nT=1, max_iterations=1,
                  replicas=1)


def compile_kernels(options=WARM) -> float:
    """Run one tiny point per option set of ``options`` in this process (compiling the
    kernels into the numba cache, or loading them from it); returns the seconds taken."""
    t0 = time.perf_counter()
    from floewave import ModelConfig, run_point

    for extra in options:
        run_point(ModelConfig(**_WARM_BASE, **extra))
    return time.perf_counter() - t0


@pytest.hookimpl(tryfirst=True)
def pytest_sessionstart(session):
    """Under xdist, in the controller only (before xdist's own ``pytest_sessionstart``
    starts the workers): :func:`compile_kernels`, the exact drag's kernels in a second
    interpreter at the same time as the rest here (numba compiles on one core), unless no test will
    be run (``--collect-only``), the JIT is off (``NUMBA_DISABLE_JIT=1``) or
    ``FLOEWAVE_TEST_COMPILE_FIRST=0`` (to measure what it saves). A failure is reported,
    not raised: the workers then compile what they need, and the tests say what fails."""
    import sys

    config = session.config
    if (hasattr(config, "workerinput") or not config.pluginmanager.hasplugin("dsession")
            or config.option.collectonly or os.environ.get("NUMBA_DISABLE_JIT") == "1"
            or os.environ.get("FLOEWAVE_TEST_COMPILE_FIRST") == "0"):
        return
    t0 = time.perf_counter()
    other = subprocess.Popen(    # the exact drag (the longest after the default)
        [sys.executable, "-c", "import tests.conftest as c; c.compile_kernels(c.WARM[1:2])"],
        cwd=Path(__file__).resolve().parent.parent, stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE, text=True)
    problem = ""
    try:
        compile_kernels(WARM[:1] + WARM[2:])
    except Exception as exc:  # noqa: BLE001 - reported; the tests will say what fails
        problem = f"{type(exc).__name__}: {exc}"
    err = other.communicate()[1]
    if other.returncode != 0:
        problem = problem or err.strip().splitlines()[-1]
    seconds = time.perf_counter() - t0
    reporter = config.pluginmanager.get_plugin("terminalreporter")
    if reporter is not None:
        reporter.write_line(f"numba kernels compiled (or loaded from the cache) before the"
                            f" workers start: {seconds:.1f} s"
                            + (f"; FAILED: {problem}" if problem else ""))


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
