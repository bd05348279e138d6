"""What needs an optional extra is skipped, with the reason, where the extra is absent.

The README's test command (``pip install -e ".[test]" && pytest``) must pass on a machine
without MPI: the doctests of :mod:`meshlap.distributed` need mpi4py, petsc4py and slepc4py
(``.ci/install-mpi``), and a doctest that imports another optional package (k3d, meshio, ...)
needs that package. Such doctests are collected and reported as skipped, naming what is
missing; tests/ states its own skips (``pytest.importorskip``, ``skipif``).
"""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent
MPI_MODULES = ("mpi4py", "petsc4py", "slepc4py")
# packages of the extras (pyproject.toml) and of the inputs a doctest may import; not the core ones
OPTIONAL = frozenset({"matplotlib", "k3d", "meshio", "robust_laplacian", "trimesh", "pyvista", "open3d",
                      "lapy", "pycompadre", *MPI_MODULES})
_IMPORT = re.compile(r"^\s*(?:import|from)\s+([A-Za-z_]\w*)", re.M)


def _absent(names: set[str]) -> list[str]:
    return sorted(n for n in names if importlib.util.find_spec(n) is None)


def _needs(item: pytest.Item) -> set[str]:
    """The optional packages a doctest item needs: MPI's for meshlap/distributed, else what it imports."""
    path = Path(str(item.path)).resolve()
    needs = set(MPI_MODULES) if (ROOT / "meshlap" / "distributed") in path.parents else set()
    for example in getattr(getattr(item, "dtest", None), "examples", ()):
        needs |= {m for m in _IMPORT.findall(example.source) if m in OPTIONAL}
    return needs


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    for item in items:
        if not isinstance(item, pytest.DoctestItem):
            continue
        missing = _absent(_needs(item))
        if missing:
            how = ".ci/install-mpi" if set(missing) & set(MPI_MODULES) else "pip install it"
            item.add_marker(pytest.mark.skip(reason=f"needs {', '.join(missing)} (absent; {how})"))
