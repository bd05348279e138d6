"""Installing meshlap one way and then another never breaks it: numba's compiled-kernel cache
is kept out of the package folder (see meshlap/_jit.py for why). A wheel's build requires what
meshlap requires (its build step compiles the kernels: meshlap/_prebuilt.py)."""

import re
import sys
from pathlib import Path

import numba
import pytest

import meshlap
from meshlap import _jit, spectral
from meshlap.assembly import grid as kernel

PACKAGE = Path(meshlap.__file__).resolve().parent


def _compiled(module):
    return [f for f in vars(module).values() if isinstance(f, numba.core.registry.CPUDispatcher)]


def test_every_compiled_function_goes_through_meshlap_jit():
    # a bare cache=True would put the cache in the package's __pycache__ again
    for path in PACKAGE.glob("*.py"):
        if path.name != "_jit.py":
            assert not re.search(r"cache\s*=\s*True", path.read_text()), path.name


def test_compiled_kernels_cache_outside_the_package():
    functions = _compiled(kernel) + _compiled(spectral)
    assert len(functions) >= 10
    for f in functions:
        where = Path(f._cache._cache_path).resolve()
        assert PACKAGE not in where.parents, (f.__name__, where)
        assert _jit.cache_dir().resolve() in where.parents


def test_the_user_s_numba_cache_dir_is_left_as_it_was(monkeypatch, tmp_path):
    monkeypatch.setattr(numba.core.config, "CACHE_DIR", "")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert _jit.cache_dir() == tmp_path / "meshlap" / "numba"

    @_jit.jit()
    def one():
        return 1

    assert one() == 1
    assert numba.core.config.CACHE_DIR == ""  # set only while meshlap's function was decorated
    assert tmp_path in Path(one._cache._cache_path).parents


def test_a_wheel_s_build_requires_what_meshlap_requires():
    # the wheel's build step imports meshlap (build_backend.py adds these for a wheel only)
    tomllib = pytest.importorskip("tomllib")
    root = PACKAGE.parent
    project = tomllib.loads((root / "pyproject.toml").read_text())
    sys.path.insert(0, str(root))
    try:
        import build_backend
    finally:
        sys.path.remove(str(root))
    assert project["build-system"]["build-backend"] == "build_backend"
    assert build_backend.DEPENDENCIES == project["project"]["dependencies"]
