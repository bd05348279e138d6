"""Kernels compiled when the package is built, so that a user's first call loads machine code.

Compiling meshlap's kernels takes about 8-12 s of CPU (numba: typing, lowering, LLVM), and a
user's first build on a fresh cache used to pay it. Compiled packages pay their compiler at
install time; meshlap does the same. ``pip install .`` builds a wheel, and the build step
(``setup.py``, :func:`build`) runs :func:`warm_up` in a subprocess with an empty numba cache,
which compiles what the first default builds use (meshes, point clouds, volumes, eigenpairs),
and ships the cache files in the package as ``meshlap/_kernels/``, with a manifest of the
versions they were made with.

At run time :mod:`meshlap._jit` calls :func:`seed` before it decorates the first kernel: it
copies the shipped files into the user's cache folder, into the sub-folder numba uses for this
installed copy of the sources, and never writes into the package. numba then loads them as if
it had compiled them itself: its index is stamped with a hash of the source file's contents
(not its time, which an install does not keep) and keyed by numba's version and the CPU.

Nothing is seeded where the shipped kernels cannot be used: another numba, numpy or Python
than the build's (the manifest), or no ``_kernels`` folder (an editable install, a source
checkout). numba itself refuses another CPU (the index key names the CPU and its features).
The kernels are then compiled on first use as before, with :mod:`meshlap._jit`'s notice.
"""

from __future__ import annotations

import hashlib
import json
import os
import pickle
import shutil
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

import numba
import numpy as np
from numba.core.caching import _CacheLocator

__all__ = ["SHIPPED", "build", "seed", "warm_up"]

#: The shipped kernels of this installed copy (present in a built wheel only).
SHIPPED = Path(__file__).resolve().parent / "_kernels"
MANIFEST = "manifest.json"


def _versions() -> dict[str, str]:
    return {"numba": numba.__version__, "numpy": np.__version__,
            "python": f"{sys.version_info[0]}.{sys.version_info[1]}{getattr(sys, 'abiflags', '')}"}


def _subpath(folder: Path) -> str:
    # the cache sub-folder numba gives the functions of the modules in `folder`
    return _CacheLocator.get_suitable_cache_subpath(os.path.join(os.path.abspath(folder), "x.py"))


def _module_folders(package: Path) -> dict[str, Path]:
    # each folder of the package that holds modules, by a name that does not depend on where
    # the package lies: "meshlap", "meshlap.assembly", ...
    return {".".join((package.name, *p.parent.relative_to(package).parts)): p.parent
            for p in sorted(package.rglob("__init__.py"))}


def warm_up() -> None:
    """Compile the kernels of the first builds a user is likely to make.

    A small mesh and a small point cloud with the defaults; a 1,500-vertex dome (a sphere cut
    flat: creases, and enough vertices for the iterative semidefiniteness check) and its
    eigenpairs; the paper's operator, stored and matrix-free (``meshlap demo``); a tetrahedral
    volume and its eigenpairs. :func:`build` runs it in a subprocess with an empty cache folder (about 20 s of
    CPU), and each of these first builds then compiles nothing. Other options (e.g.
    ``pointwise=True``) still compile on first use.

    Examples
    --------
    >>> warm_up()  # doctest: +SKIP
    """
    import meshlap

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # only compiling
        # fit_rows: the default's point-wise rows, which a build fits on first use
        V, F = meshlap.shapes.sphere(500, seed=0)
        meshlap.laplacian(V, F).fit_rows()
        meshlap.point_cloud_laplacian(meshlap.samples.sphere_points(500)).fit_rows()
        V, F = meshlap.shapes.sphere(1500, seed=0)
        V[:, 2] = np.maximum(V[:, 2], -0.3)
        meshlap.spectral.eigs(meshlap.laplacian(V, F).fit_rows(), 6)  # the FEM pencil's flips
        meshlap.laplacian(V, F, operator="kernel").assemble()  # the kernel's rows and checks
        meshlap.laplacian(V, F, correction="none")
        _ = meshlap.laplacian(V, F, h=0.01, correction="none", matrix_free=True) @ V
        volume = meshlap.laplacian(*meshlap.samples.cube_tetrahedra(6)).fit_rows()
        meshlap.spectral.eigs(volume, 4)  # a volume's factorization and its ordering's count


def build(package: Path) -> Path:
    """Compile the kernels of the package at ``package`` and ship them in ``package/_kernels``.

    The build step of a wheel (``setup.py``) calls it on the package copied to the build
    folder. It runs :func:`warm_up` in a fresh interpreter that imports that copy with an empty
    cache folder of its own, then moves the cache files into ``_kernels/<module folder>/`` and
    writes the manifest. Returns the ``_kernels`` folder.

    Examples
    --------
    >>> build(Path("meshlap"))  # doctest: +SKIP
    PosixPath('meshlap/_kernels')
    """
    package = Path(package).resolve()
    dest = package / SHIPPED.name
    shutil.rmtree(dest, ignore_errors=True)  # compile from the sources, not from an older build
    folders = {_subpath(folder): name for name, folder in _module_folders(package).items()}
    with tempfile.TemporaryDirectory() as cache:
        env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
        env.update(XDG_CACHE_HOME=cache, PYTHONPATH=os.pathsep.join(
            [str(package.parent), *filter(None, [env.get("PYTHONPATH")])]))
        print("meshlap: compiling the kernels of the first builds, to ship them (about 15-30 s)",
              file=sys.stderr, flush=True)
        subprocess.run([sys.executable, "-c", "from meshlap._prebuilt import warm_up; warm_up()"],
                       env=env, check=True, cwd=cache)
        made = Path(cache) / "meshlap" / "numba"
        for sub in sorted(made.iterdir()):
            if sub.name not in folders:
                raise RuntimeError(f"compiled kernels of an unknown folder: {sub.name}")
            shutil.copytree(sub, dest / folders[sub.name],
                            ignore=shutil.ignore_patterns("*.tmp.*"))
    # the sources' digest: a new release installed at the same place seeds the cache again
    sources = hashlib.sha256(b"".join(p.read_bytes() for p in sorted(package.rglob("*.py")))).hexdigest()
    (dest / MANIFEST).write_text(json.dumps(dict(_versions(), sources=sources), indent=1))
    return dest


def _stamp(index: Path) -> object:
    # numba's version and the source's stamp at the head of a cache index (.nbi)
    with open(index, "rb") as f:
        version = pickle.load(f)
        return version, pickle.loads(f.read())[0]


def _copy(src: Path, dst: Path) -> None:
    # another process may read or seed the same cache at the same time: write aside, rename
    tmp = dst.with_name(f"{dst.name}.tmp.{os.getpid()}")
    shutil.copyfile(src, tmp)
    os.replace(tmp, dst)


def seed(cache: Path, shipped: Path = SHIPPED) -> bool:
    """Copy the shipped kernels into the cache folder ``cache``, where numba looks for them.

    Once per installed copy: a marker in each sub-folder names the manifest it was seeded
    from. An index the user's cache already holds for the same sources is kept (it may hold
    more than the shipped one); one for other sources (an older install at the same place) is
    replaced. Returns whether the shipped kernels apply here (see the module's notes).

    Examples
    --------
    >>> seed(Path(tempfile.mkdtemp()), shipped=Path("no-such-folder"))
    False
    """
    try:
        manifest = (shipped / MANIFEST).read_text()
    except OSError:
        return False
    made_with, versions = json.loads(manifest), _versions()
    if {k: made_with.get(k) for k in versions} != versions:
        return False
    marker = ".seeded-" + hashlib.sha1(manifest.encode()).hexdigest()[:16]
    package = shipped.parent
    try:
        for name, folder in _module_folders(package).items():
            source, target = shipped / name, cache / _subpath(folder)
            if not source.is_dir() or (target / marker).exists():
                continue
            target.mkdir(parents=True, exist_ok=True)
            for index in source.glob("*.nbi"):
                mine = target / index.name
                try:
                    if mine.exists() and _stamp(mine) == _stamp(index):
                        continue
                except Exception:  # an unreadable index: numba would ignore it; replace it
                    pass
                for data in source.glob(index.name[:-len(".nbi")] + ".*.nbc"):
                    _copy(data, target / data.name)
                _copy(index, mine)  # last: the index names the data files
            (target / marker).touch()
    except OSError:  # a read-only or full cache: numba compiles as without the shipped kernels
        return False
    return True
