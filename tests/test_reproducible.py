"""One configuration, one result, bit for bit, whatever the numba cache holds (issue *trust*).

The kernels used to be compiled with fast-math, and a process that compiled them ran other
machine code than a process that loaded them from the on-disk cache (see
:mod:`floewave._jit`): the Fig. 2 ``ml`` eps 0.6 point gave W_c 18.42 m cold and 15.92 m
warm. Here short DEM points (every kernel path: closed-form and prefix-sum quadrature drag
with one and two roots per floe, exact drag, the amplitude iteration; ensembles of 2
replicas, random and uniform placement, mean and independent coupling) run in fresh
interpreters:

- A: an empty cache directory, the quadrature point first, then the exact-drag point;
- B: the cache A left (everything loaded, nothing compiled);
- C: another empty cache directory, compiled in the other order (exact first) by two
  interpreters at once (as the ranks of an MPI job compile with a cold cache).

Every array and scalar of every point must be equal bit for bit across A, B and C. The
points are chaotic: a last-bit difference in any force moves the trajectory (and so the
digests) within a few steps.

Both tests here start fresh interpreters with cold caches: the slow tier. The fast tier
proves the same machinery in-process: the cache key of every kernel file's functions
(:func:`test_every_kernel_file_is_keyed_by_all_kernel_files`), a point's bits repeated in
one process (tests/floewave/test_iteration.py::test_run_point_is_deterministic), replica
invariance (tests/floewave/test_kernels.py), one rank = three ranks
(tests/sweep/test_mpi.py) and kill -9 then resume (tests/sweep/test_store.py).
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import pytest

SCRIPT = textwrap.dedent("""
    import hashlib, json, sys
    import numpy as np
    from floewave import ModelConfig, run_point

    POINTS = {
        # 84 floes of 0.5 m: closed-form and prefix-sum floes (one root of each family)
        "quadrature": dict(L_x=0.5, T=1.2, a0=0.015, eps=0.6, d_f=0.005, dispersion="ml"),
        # 28 floes of 1.5 m: nearly every floe by the prefix sums
        "long": dict(L_x=1.5, T=1.2, a0=0.02, eps=0.8, d_f=0.005, dispersion="ep"),
        "exact": dict(L_x=0.5, T=1.2, a0=0.015, eps=0.6, d_f=0.005, dispersion="ml",
                      drag_integration="exact"),
        # 1.5 m floes, exact drag: most floes need the root-finding evaluation
        "exact-long": dict(L_x=1.5, T=1.2, a0=0.02, eps=0.8, d_f=0.005, dispersion="ep",
                           drag_integration="exact", integrator="half_step"),
        # an ensemble of independently iterated replicas from the paper's arrangement
        # (3 m floes: two roots of a family on a floe)
        "independent": dict(L_x=3.0, T=1.2, a0=0.02, eps=0.6, d_f=0.005, dispersion="ml",
                            coupling="independent", placement="uniform"),
    }
    SHORT = dict(n0=2, nT=1, max_iterations=4, noise_window=2, n_average=2, n0_warm=0,
                 replicas=2)

    out = {}
    for name in sys.argv[1:]:
        r = run_point(ModelConfig(**POINTS[name], **SHORT))
        d = {}
        for key, val in r.to_dict().items():
            if key == "wall_time":
                continue
            if isinstance(val, np.ndarray):
                d[key] = hashlib.sha256(np.ascontiguousarray(val).tobytes()).hexdigest()
            elif isinstance(val, float):
                d[key] = val.hex()
            else:
                d[key] = val
        out[name] = d
    print(json.dumps(out))
""")


def _start(cache_dir, order):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache_dir))
    env.pop("NUMBA_DISABLE_JIT", None)
    return subprocess.Popen([sys.executable, "-c", SCRIPT, *order], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _result(proc):
    out, err = proc.communicate(timeout=600)
    assert proc.returncode == 0, err
    return json.loads(out)


def _run(cache_dir, order):
    return _result(_start(cache_dir, order))


@pytest.mark.slow  # fresh interpreters compiling with cold caches (module docstring)
@pytest.mark.skipif(os.environ.get("NUMBA_DISABLE_JIT") == "1", reason="needs the JIT")
def test_point_bits_do_not_depend_on_the_jit_cache(tmp_path):
    names = ["quadrature", "long", "exact", "exact-long", "independent"]
    cold = _run(tmp_path / "cache-a", names)
    assert any((tmp_path / "cache-a").rglob("*.nbc")), "nothing was cached"
    warm = _run(tmp_path / "cache-a", names)
    # two interpreters compiling into one empty cache at once, in opposite orders
    together = [_start(tmp_path / "cache-c", order) for order in (names[::-1], names)]
    other_order, concurrent = (_result(p) for p in together)
    for name in names:
        assert cold[name]["iterations"] >= 2
        # the points are chaotic: contacts happen (a last-bit change would move them)
        assert warm[name] == cold[name], f"{name}: warm cache differs from the cold compile"
        assert other_order[name] == cold[name], f"{name}: compile order changes the bits"
        assert concurrent[name] == cold[name], f"{name}: a concurrent compile changes the bits"


def test_two_processes_saving_one_kernel_at_once_never_mix_their_code(tmp_path):
    """The race of the concurrent compile above, replayed in order: process 2 saves the
    ``True`` specialisation of a kernel; in the middle of it (after it chose its data file,
    before it wrote it) process 1, which read the index before process 2 wrote it, saves the
    ``False`` one. With numba's counter-named data files both chose ``.1.nbc``: the index
    named process 1's key and the file held process 2's code, and a load of ``False`` ran
    ``True`` (CI, 2026-12-07). Each key must load its own data, and both entries be kept.
    A function of another file keeps numba's names (``<base>.1.nbc``)."""
    from numba.core import caching

    from floewave import _jit

    assert caching.IndexDataCacheFile is _jit.KernelCacheFile  # what numba's Cache builds
    stamp = ((1.0, 2), _jit.kernel_fingerprint())
    base = "_drag.drag_pass-191.py311"
    one, two, reader = (caching.IndexDataCacheFile(str(tmp_path), base, stamp)
                        for _ in range(3))
    key_false, key_true = ("sig", "Literal[bool](False)"), ("sig", "Literal[bool](True)")
    before = one._load_index()  # process 1 read the index before process 2 wrote it
    one._load_index = lambda: dict(before)
    save_data = two._save_data

    def interrupted(name, data):  # process 1 saves while process 2 is in its save
        one.save(key_false, "code for False")
        save_data(name, data)

    two._save_data = interrupted
    two.save(key_true, "code for True")
    assert reader.load(key_false) == "code for False"
    assert reader.load(key_true) == "code for True"
    assert set(reader._load_index()) == {key_false, key_true}
    other = caching.IndexDataCacheFile(str(tmp_path), "elsewhere.f-1.py311", (1.0, 2))
    other.save(key_true, "x")
    assert other._load_index() == {key_true: "elsewhere.f-1.py311.1.nbc"}


CALLEE_SCRIPT = textwrap.dedent("""
    import json
    import numpy as np
    import floewave
    from floewave import ModelConfig, solve_dispersion
    from floewave import _kernels as K

    cfg = ModelConfig(L_x=0.5, T=1.2, drag_integration="exact")
    k, _ = solve_dispersion(cfg)
    P = K.kernel_params(cfg, k)
    x = 0.3 + 0.55 * np.arange(4)
    c, s = np.cos(k * x), np.sin(k * x)
    cells = np.zeros(1)                # (the cell tables: unused by the exact drag)
    s2 = [K.floe_drag(cfg.a0 * P.u_amp, c[i], s[i], 1.0, True, K.DRAG_EXACT, P, cells,
                      cells)[0]
          for i in range(4)]           # |v| > A: no root, the closed form of _exact.py
    hits = sum(K.floe_drag.stats.cache_hits.values())
    print(json.dumps(dict(file=floewave.__file__, s2=s2, hits=hits)))
""")


def test_every_kernel_file_is_keyed_by_all_kernel_files(tmp_path, monkeypatch):
    """In-process (fast tier) half of the next test: numba's cache locator for a function of
    a kernel file is :class:`floewave._jit.KernelSourcesLocator`, whose source stamp holds
    the fingerprint of all kernel files, and a change in any one of them (here the
    callee file ``_exact.py``, in a copy) changes that fingerprint; a function of another
    file keeps numba's own key."""
    import shutil
    from pathlib import Path

    from floewave import (
        _contact,
        _drag,
        _exact,
        _exact_pass,
        _jit,
        _kernels,
        _march,
        _prefix,
        dispersion,
    )

    for fn in (_kernels.floe_drag, _contact.contact_law, _drag.drag_pass, _exact.drag_sums_exact,
               _exact_pass.drag_pass_exact, _prefix.prefix_sums, _march._root):
        loc = _jit.KernelSourcesLocator.from_function(fn.py_func, fn.py_func.__code__.co_filename)
        assert isinstance(loc, _jit.KernelSourcesLocator)
        assert loc.get_source_stamp()[1] == _jit.kernel_fingerprint()
    assert _jit.KernelSourcesLocator.from_function(dispersion.solve_dispersion,
                                                   dispersion.__file__) is None
    src = Path(_jit.__file__).parent
    for name in _jit.KERNEL_SOURCES:
        shutil.copy(src / name, tmp_path / name)
    fingerprint = _jit.kernel_fingerprint.__wrapped__
    monkeypatch.setattr(_jit, "_HERE", str(tmp_path))
    assert fingerprint() == _jit.kernel_fingerprint()
    exact = tmp_path / "_exact.py"
    exact.write_text(exact.read_text() + "\n# changed\n")
    assert fingerprint() != _jit.kernel_fingerprint()


@pytest.mark.slow  # fresh interpreters compiling a copy of the package
def test_a_change_in_a_callee_file_recompiles_the_cached_callers(tmp_path):
    """``floe_drag`` (``_kernels.py``) calls ``drag_sums_exact`` (``_exact.py``). numba
    keys a cached function by its own file only, so a changed ``_exact.py`` left the cached
    ``floe_drag`` running the old callee in a warm process and the new one in a cold
    process (two results for one configuration): every kernel file's functions are keyed by
    all kernel files (:class:`floewave._jit.KernelSourcesLocator`). Here the callee's
    exact drag is doubled in a copy of the package, whose cache a first run filled."""
    import shutil
    from pathlib import Path

    src = Path(__file__).resolve().parent.parent / "floewave"
    pkg = tmp_path / "src" / "floewave"
    shutil.copytree(src, pkg, ignore=shutil.ignore_patterns("__pycache__"))
    cache = tmp_path / "cache"
    env = dict(os.environ, PYTHONPATH=str(pkg.parent), NUMBA_CACHE_DIR=str(cache))

    def run():
        out = subprocess.run([sys.executable, "-c", CALLEE_SCRIPT], env=env, cwd=tmp_path,
                             check=True, capture_output=True, text=True).stdout
        res = json.loads(out.strip().splitlines()[-1])
        assert Path(res["file"]).resolve().parent == pkg.resolve()
        return res

    cold = run()
    warm = run()
    assert cold["hits"] == 0 and warm["hits"] >= 1      # the cache is used at all
    assert warm["s2"] == cold["s2"]
    exact = pkg / "_exact.py"
    text = exact.read_text()
    old = "return geom[3] * I2, geom[3] * max(I3, 0.0)"
    assert text.count(old) == 1
    exact.write_text(text.replace(old, "return 2.0 * (geom[3] * I2), geom[3] * max(I3, 0.0)"))
    changed = run()
    assert changed["hits"] == 0                          # recompiled, not loaded
    assert changed["s2"] == [2.0 * v for v in cold["s2"]]
    assert all(v != 0.0 for v in cold["s2"])
