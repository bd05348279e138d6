"""numba compilation with an on-disk cache that lives outside the package.

numba's default cache (``cache=True``) writes ``*.nbi``/``*.nbc`` files into the package's own
``__pycache__``. For a regular (non-editable) install that folder is in site-packages, and pip
does not know about those files: when the package is later replaced by an editable install,
pip removes its own files and leaves the folder behind with only the cache in it, and Python
then imports that folder as an empty namespace package that shadows the real one. So meshlap
keeps its compiled kernels in the user's cache directory instead (``$NUMBA_CACHE_DIR`` when the
user set one, else ``$XDG_CACHE_HOME/meshlap/numba`` or ``~/.cache/meshlap/numba``), one
sub-folder per installed copy of the sources, and never writes into the package.

The kernels are compiled serially (no ``parallel=True``) and released from the GIL; their
parallel loops run on a small pool of Python threads, as many as ``numba.get_num_threads()``
(:func:`each_thread`, :func:`in_blocks`). numba's parallel transformation makes a kernel
several times slower to compile (measured 2-5×: 6 s instead of 2 s for the widest one) and
gives nothing that these loops, one independent row per iteration, need; the threads run the
same machine code, and each row is still written by one thread, so results do not depend on
the number of threads.

A wheel built by ``pip install .`` ships the kernels of the first default builds, compiled
at build time (:mod:`meshlap._prebuilt`); before the first kernel is decorated, they are copied
into this cache folder, so that the first call loads them. Where they do not apply (an
editable install, another numba or CPU) or a call needs others, the first time this process
compiles one of meshlap's kernels (seconds, once per installed copy), a one-line notice on
stderr says so. numba reports only real compilations (cache misses), so a warm cache prints
nothing.
"""

from __future__ import annotations

import contextlib
import functools
import os
import sys
import tempfile
import threading
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numba
import numpy as np
from numba.core import config, event

from meshlap import _prebuilt

__all__ = ["cache_dir", "each_thread", "in_blocks", "jit"]

#: What the notice says: the first compilations cost about this long on a quiet machine.
NOTICE = "meshlap: compiling kernels for first use (once, a few seconds; later runs load them from {})…"


def cache_dir() -> Path:
    """Folder that holds meshlap's compiled kernels.

    Examples
    --------
    >>> cache_dir().name in {"numba"} or "NUMBA_CACHE_DIR" in os.environ
    True
    """
    if config.CACHE_DIR:
        return Path(config.CACHE_DIR)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    path = Path(base) / "meshlap" / "numba"
    try:
        path.mkdir(parents=True, exist_ok=True)
        probe = path / f".probe-{os.getpid()}"
        probe.touch()
        probe.unlink()
    except OSError:  # a read-only home: a per-user temporary folder still keeps site-packages clean
        path = Path(tempfile.gettempdir()) / f"meshlap-numba-{os.getuid() if hasattr(os, 'getuid') else 0}"
        path.mkdir(parents=True, exist_ok=True)
    return path


@contextlib.contextmanager
def _cache_in(path: Path) -> Iterator[None]:
    # numba picks a function's cache locator when the function is decorated, from
    # numba.config.CACHE_DIR; setting it only for that moment leaves the caller's own numba
    # functions where they were.
    old = config.CACHE_DIR
    config.CACHE_DIR = str(path)
    try:
        yield
    finally:
        config.CACHE_DIR = old


_seeded: set[Path] = set()  # the cache folders this process has seeded with the shipped kernels


def jit(**options: Any) -> Callable[[Callable[..., Any]], Any]:
    """``numba.njit(cache=True, nogil=True, **options)`` with the cache in :func:`cache_dir`.

    Use it as ``@jit()`` on a function in a module of meshlap (numba caches only functions
    whose source is in a file); run a parallel loop with :func:`each_thread` or
    :func:`in_blocks` rather than ``parallel=True``, which costs seconds more to compile.

    Examples
    --------
    >>> from meshlap.assembly import grid as kernel
    >>> cache_dir() in Path(kernel._fill_rows._cache._cache_path).parents
    True
    """

    def decorate(fn: Callable[..., Any]) -> Any:
        path = cache_dir()
        if path not in _seeded:
            _seeded.add(path)
            _prebuilt.seed(path)
        with _cache_in(path):
            return numba.njit(cache=True, nogil=True, **options)(fn)

    return decorate


_pool: tuple[int, ThreadPoolExecutor] | None = None
_pool_lock = threading.Lock()


def _threads() -> tuple[int, ThreadPoolExecutor | None]:
    # numba's thread count (numba.set_num_threads applies), and a pool with at least that many
    global _pool
    n = numba.get_num_threads()
    if n == 1:
        return 1, None
    with _pool_lock:
        if _pool is None or _pool[0] < n:
            if _pool is not None:
                _pool[1].shutdown(wait=False)
            _pool = (n, ThreadPoolExecutor(n, thread_name_prefix="meshlap"))
        return n, _pool[1]


def each_thread(kernel: Callable[..., None], *args: Any) -> None:
    """Run ``kernel(*args)`` once on each of ``numba.get_num_threads()`` threads, and wait.

    The kernel shares the work out itself (an atomic counter in ``args``, as in
    :mod:`meshlap.assembly.grid`); it must be compiled with ``nogil`` (:func:`jit` is).

    Examples
    --------
    >>> import numpy as np
    >>> from meshlap.assembly._intrinsics import _fetch_add
    >>> @numba.njit(nogil=True)
    ... def claim(counter, seen):
    ...     while True:
    ...         i = _fetch_add(counter, 0, 1)
    ...         if i >= len(seen):
    ...             break
    ...         seen[i] += 1
    >>> seen = np.zeros(100, dtype=np.int64)
    >>> each_thread(claim, np.zeros(1, dtype=np.int64), seen)
    >>> bool((seen == 1).all())
    True
    """
    n, pool = _threads()
    if pool is None:
        kernel(*args)
        return
    for done in [pool.submit(kernel, *args) for _ in range(n)]:
        done.result()


def in_blocks(kernel: Callable[..., None], n_items: int, *args: Any) -> None:
    """Run ``kernel(start, stop, *args)`` over blocks that cover ``range(n_items)``, in parallel.

    About four blocks per thread, so that a slow block or a busy core does not hold the rest
    back; the kernel must treat its items independently of the others.

    Examples
    --------
    >>> import numpy as np
    >>> @numba.njit(nogil=True)
    ... def square(start, stop, x):
    ...     for i in range(start, stop):
    ...         x[i] = x[i] * x[i]
    >>> x = np.arange(10.0)
    >>> in_blocks(square, len(x), x)
    >>> float(x[-1])
    81.0
    """
    n, pool = _threads()
    if pool is None or n_items < 2:
        kernel(0, n_items, *args)
        return
    edges = np.linspace(0, n_items, min(4 * n, n_items) + 1).astype(np.int64)
    blocks = zip(edges[:-1].tolist(), edges[1:].tolist(), strict=True)
    for done in [pool.submit(kernel, a, b, *args) for a, b in blocks]:
        done.result()


class _FirstCompileNotice(event.Listener):
    """Prints :data:`NOTICE` once per process, when numba starts compiling a meshlap function."""

    def __init__(self) -> None:
        self.told = False

    def on_start(self, ev: event.Event) -> None:
        if self.told:
            return
        module = getattr(getattr(ev.data.get("dispatcher"), "py_func", None), "__module__", "")
        if module.startswith("meshlap."):
            self.told = True
            print(NOTICE.format(cache_dir()), file=sys.stderr, flush=True)

    def on_end(self, ev: event.Event) -> None:
        pass


event.register("numba:compile", _FirstCompileNotice())


@functools.cache
def _blas_pools() -> Any:
    # the loaded BLAS libraries, found once: each new controller reads /proc/self/maps again
    # (2 ms, once per part of a 100-part mesh's eigs)
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


def one_blas_thread() -> contextlib.AbstractContextManager:
    """Keep BLAS on one thread while meshlap's threads share the products' rows.

    The dense steps here are small (n × a few k); a threaded BLAS between two parallel
    products competed with their spinning OpenMP workers and was measured 3-10× slower.
    """
    try:
        pools = _blas_pools()
    except ImportError:  # optional: without it BLAS keeps its own setting
        return contextlib.nullcontext()
    return pools.limit(limits=1, user_api="blas")
