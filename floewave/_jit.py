"""The one definition of the numba JIT flags of floewave's kernels.

**No fast-math, on purpose.** A kernel's result must be a function of its inputs alone: the
same configuration gives the same bits on one machine whatever the JIT cache holds, the
order in which functions were first compiled, or the number of MPI ranks. With
``fastmath=True`` it was not (issue *trust*, 2026-11-30: the Fig. 2 ``ml`` eps 0.6 point
gave W_c 18.42 m and 16 iterations when the kernels were compiled in the process, 15.92 m and
27 iterations when they were loaded from the cache). The cause, found by comparing the two
paths state by state (the forces differed in the last bit after one step) and reading the
generated code:

- numba compiles every ``@njit`` function into its own code library and links each callee's
  *optimised* module into its caller's, which is optimised again as a whole;
- a callee that LLVM does not inline (then ``eval_forces``, ``drag_pass``, ``general_floes``
  … were called out of line from ``advance``) exists twice in a cold process: its own library,
  compiled first, and the copy inside the caller's library. The JIT linker resolves the call
  to the first definition of the symbol it loaded — the callee's own library. A warm process
  loads only the caller's cached object and runs the other copy;
- under fast-math the two copies are *different programs*: the second optimisation of the
  linked copy re-associates and contracts (FMA) differently (seen:
  ``(1 + C_m) F_w + F_d`` differing by 1 ulp). A chaotic DEM makes that a different
  trajectory.

Without the value-changing fast-math flags every copy of a function computes the IEEE result
of its source, so it does not matter which copy runs. What fast-math bought (vectorised cell
sums, a reduction that needs re-association) is won back explicitly: the cell sums are
vectorised *across floes and replicas* instead, and the sums of floes with a root on them
are closed forms (``floewave._prefix.prefix_sums``) rather than re-associated loops.
"""
from __future__ import annotations

#: Flags of every jitted kernel: cached on disk, IEEE arithmetic (see the module docstring),
#: the GIL released, and numpy's error model: a float division by zero gives inf or nan as
#: IEEE says instead of raising ZeroDivisionError. Same bits for every other division; but
#: Python's model puts a test and an exception path on every division, and a loop with an
#: exception path is not vectorised (measured: the prefix-sum drag and the contact loop,
#: 2026-12-01). The kernels check their results for non-finite values instead
#: (``FloeChain.check``).
JIT = dict(cache=True, fastmath=False, nogil=True, error_model="numpy")

#: Per-step functions that never allocate: compiled without numba's reference counting
#: (``_nrt=False``). With it, every call of the (then) ``eval_forces`` paid ~40 atomic NRT
#: incref/decref operations on its array arguments: measured ~110 ns per step, 15 % of a
#: step of 84 floes (benchmarks/bench_kernel.py, 2026-11-22). Such a function must not
#: create or return arrays (numba refuses to compile one that does).
JITN = dict(JIT, _nrt=False)


# --------------------------------------------------------------------------- the cache key
#
# numba keys a cached function by the SHA-256 of *its own* source file: a change in a callee
# in another file (``_exact.py`` called from ``_kernels.py``) or in the flags above left the
# caller's cached machine code in use, so a warm process ran the old callee and a cold one
# the new: two results for one configuration (issue *trust*, noticed 2026-12-01). Every
# kernel file's functions are therefore keyed by the SHA-256 of all of them: any change in
# any kernel file recompiles every kernel, once.

import functools  # noqa: E402
import hashlib  # noqa: E402
import os  # noqa: E402
import warnings  # noqa: E402

from numba.core import caching as _caching  # noqa: E402

#: the files whose jitted functions call each other (and these flags), and the file of the
#: constants they read (numba freezes a module global into the compiled code). Every file of
#: floewave that imports this module is one (tests/floewave/test_kernel_sources.py).
KERNEL_SOURCES = ("_jit.py", "_layout.py", "_contact.py", "_prefix.py", "_drag.py",
                  "_exact.py", "_exact_pass.py", "_force_terms.py", "_kernels.py", "_respa.py",
                  "_march.py")
_HERE = os.path.dirname(os.path.abspath(__file__))


@functools.cache
def kernel_fingerprint() -> str:
    """SHA-256 (hex) of the kernel files' names and bytes (read once per process)."""
    h = hashlib.sha256()
    for name in KERNEL_SOURCES:
        with open(os.path.join(_HERE, name), "rb") as f:
            h.update(name.encode() + b"\0" + f.read() + b"\0")
    return h.hexdigest()


class KernelSourcesLocator(_caching._CacheLocator):
    """numba's own cache locator for a function of a kernel file (same directory, same
    file names), with the source stamp extended by :func:`kernel_fingerprint`: the cached
    code of every kernel is stale as soon as any kernel file changes."""

    def __init__(self, inner, fingerprint):
        self._inner = inner
        self._fingerprint = fingerprint

    def ensure_cache_path(self):
        self._inner.ensure_cache_path()

    def get_cache_path(self):
        return self._inner.get_cache_path()

    def get_source_stamp(self):
        return (self._inner.get_source_stamp(), self._fingerprint)

    def get_disambiguator(self):
        return self._inner.get_disambiguator()

    @classmethod
    def from_function(cls, py_func, py_file):
        path = os.path.abspath(py_file)
        if os.path.dirname(path) != _HERE or os.path.basename(path) not in KERNEL_SOURCES:
            return None
        try:
            fingerprint = kernel_fingerprint()
        except OSError:     # not plain files (a zip, a frozen application): numba's own
            warnings.warn("floewave: kernel sources not readable as files; the numba cache"
                          " is keyed by each function's own file only", stacklevel=2)
            return None
        for other in _IMPL._locator_classes:
            if other is cls:
                continue
            inner = other.from_function(py_func, py_file)
            if inner is not None:
                return cls(inner, fingerprint)
        return None


# numba >= 0.61 calls it CacheImpl, earlier versions _CacheImpl. (NUMBA_CACHE_LOCATOR_CLASSES,
# where numba has it, replaces this list: then the user's locators decide, without this key.)
_IMPL = getattr(_caching, "CacheImpl", None) or _caching._CacheImpl
if KernelSourcesLocator not in _IMPL._locator_classes:
    _IMPL._locator_classes.insert(0, KernelSourcesLocator)


# ------------------------------------------------------------------ the cache's data files
#
# numba names a function's cached code by a counter: the first signature saved goes to
# ``<function>.1.nbc``, the next to ``.2.nbc``, and so on, the number chosen from the index
# file as the saving process last read it, the index written before the data. Two processes
# compiling one function for *different* signatures into one empty cache at once (the ranks of
# an MPI job with a cold cache; the kernels are compiled per literal flag, e.g. a drag pass for
# Literal[bool](False) and (True)) both chose ``.1.nbc``; the index of one could end up naming
# the other's code, and a third load of that signature ran the other specialisation: another
# result for one configuration (tests/test_reproducible.py's concurrent compile, intermittent
# in CI, 2026-12-07). For the kernel files' functions the data file is named by the key
# (signature, target, closure) and the kernel sources' fingerprint, so different keys, or
# two versions of the kernels sharing a NUMBA_CACHE_DIR, never share a file; and it is
# written before the index entry that names it. The index is re-read just before it is
# written, which keeps most of another process's entries; one saved in between is lost
# from the index (its file stays): a later process compiles that signature again, never
# runs other code. Files of keys no longer in use (another CPU, an edited kernel) stay
# in the cache directory, as numba's numbered files of a stale index did; deleting the
# cache directory is always safe.

class KernelCacheFile(_caching.IndexDataCacheFile):
    """numba's index-and-data cache file; for a kernel file's function (its source stamp
    holds :func:`kernel_fingerprint`) a save is safe against other processes saving the same
    function at once (see above). Other functions keep numba's own behaviour."""

    def __init__(self, cache_path, filename_base, source_stamp):
        super().__init__(cache_path=cache_path, filename_base=filename_base,
                         source_stamp=source_stamp)
        self._base = filename_base
        try:
            self._keyed = (isinstance(source_stamp, tuple) and len(source_stamp) == 2
                           and source_stamp[1] == kernel_fingerprint())
        except OSError:
            self._keyed = False

    def save(self, key, data):
        if not self._keyed:
            return super().save(key, data)
        taken = {name for k, name in self._load_index().items() if k != key}
        digest = hashlib.sha256(f"{self._source_stamp[1]}\0{key!r}".encode()).hexdigest()
        name = f"{self._base}.{digest[:16]}.nbc"
        stem, n = name[:-4], 1
        while name in taken:  # two keys of one repr: never seen, but never one file
            name, n = f"{stem}-{n}.nbc", n + 1
        self._save_data(name, data)
        overloads = self._load_index()
        if overloads.get(key) != name:
            overloads[key] = name
            self._save_index(overloads)


if _caching.IndexDataCacheFile is not KernelCacheFile:
    _caching.IndexDataCacheFile = KernelCacheFile
