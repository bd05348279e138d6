"""Installing meshlap one way and then another never breaks it: numba's compiled-kernel cache
is kept out of the package folder (see meshlap/_jit.py for why). A built wheel ships the
kernels of the first builds (meshlap/_prebuilt.py), and its first call compiles nothing."""

import os
import re
import shutil
import subprocess
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


FIRST_CALLS = """
import meshlap
V, F = meshlap.shapes.sphere(500, seed=0)
meshlap.laplacian(V, F)
meshlap.point_cloud_laplacian(meshlap.samples.sphere_points(500))
print(meshlap.__file__)
"""


@pytest.mark.slow
def test_a_built_wheel_ships_the_kernels_and_compiles_nothing_at_first_call(tmp_path):
    # what `pip install .` does: a wheel built with build isolation (its build requirements
    # from the package index: about 25 s of CPU, 55 s of wall on a loaded 2-core machine),
    # installed where the build did not run, used with an empty cache
    root = PACKAGE.parent
    for name in ("pyproject.toml", "setup.py", "build_backend.py", "README.md", "LICENSE"):
        shutil.copy(root / name, tmp_path / name)
    shutil.copytree(PACKAGE, tmp_path / "meshlap", ignore=shutil.ignore_patterns("__pycache__", "_kernels"))
    built = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", "dist", "."],
                           cwd=tmp_path, capture_output=True, text=True, timeout=1200)
    if built.returncode and re.search(r"No matching distribution|Could not find a version", built.stderr):
        why = built.stderr.strip().splitlines()[-1]
        pytest.skip(f"the build requirements cannot be installed here: {why}")
    assert built.returncode == 0, built.stderr
    wheel = next((tmp_path / "dist").glob("meshlap-*.whl"))
    shutil.unpack_archive(wheel, tmp_path / "site", "zip")  # what pip install puts in site-packages
    shipped = tmp_path / "site" / "meshlap" / "_kernels"
    assert (shipped / "manifest.json").exists()
    names = {p.name.split("-")[0] for p in shipped.rglob("*.nbi")}
    assert {"variable._var_rows", "highorder._rows", "stars._masses2"} <= names, names
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(XDG_CACHE_HOME=str(tmp_path / "cache"), PYTHONPATH=str(tmp_path / "site"))
    done = subprocess.run([sys.executable, "-c", FIRST_CALLS], cwd=tmp_path / "site", env=env,
                          capture_output=True, text=True, timeout=600, check=True)
    assert done.stdout.strip() == str(tmp_path / "site" / "meshlap" / "__init__.py")
    assert "compiling" not in done.stderr, done.stderr  # meshlap._jit's notice of a compilation
