"""numba compilation with an on-disk cache that lives outside the package.

numba's default cache (``cache=True``) writes ``*.nbi``/``*.nbc`` files into the package's own
``__pycache__``. For a regular (non-editable) install that folder is in site-packages, and pip
does not know about those files: when the package is later replaced by an editable install,
pip removes its own files and leaves the folder behind with only the cache in it, and Python
then imports that folder as an empty namespace package that shadows the real one. So meshlap
keeps its compiled kernels in the user's cache directory instead (``$NUMBA_CACHE_DIR`` when the
user set one, else ``$XDG_CACHE_HOME/meshlap/numba`` or ``~/.cache/meshlap/numba``), one
sub-folder per installed copy of the sources, and never writes into the package.

Compiling takes a while (tens of seconds for the first mesh and the first point cloud on a
fresh cache, once per installed copy): the first time this process compiles one of meshlap's
kernels, a one-line notice on stderr says so. numba reports only real compilations (cache
misses), so a warm cache prints nothing.
"""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numba
from numba.core import config, event

__all__ = ["cache_dir", "jit"]

#: What the notice says: the first compilations cost about this long on a quiet machine.
NOTICE = ("meshlap: compiling kernels for first use (once, ~15-30 s; later runs load them from {})…")


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


def jit(**options: Any) -> Callable[[Callable[..., Any]], Any]:
    """``numba.njit(cache=True, **options)`` with the cache in :func:`cache_dir`.

    Use it as ``@jit(parallel=True)`` on a function in a module of meshlap (numba caches only
    functions whose source is in a file).

    Examples
    --------
    >>> from meshlap.assembly import grid as kernel
    >>> cache_dir() in Path(kernel._fill_rows._cache._cache_path).parents
    True
    """

    def decorate(fn: Callable[..., Any]) -> Any:
        with _cache_in(cache_dir()):
            return numba.njit(cache=True, **options)(fn)

    return decorate


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
