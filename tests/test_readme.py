"""The Python examples of the README and of the guides in docs/ run as written (from the
repository root, as a user would). Fences marked ``py`` instead of ``python`` are sketches
with the user's own objects (a pyvista grid, an open3d cloud): shown, not run."""

import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
BLOCKS = {page.relative_to(ROOT): re.findall(r"```python\n(.*?)```", page.read_text(), re.S)
          for page in PAGES}


def _marks(code: str) -> list:
    marks = []
    if "sphere(16000" in code:
        marks.append(pytest.mark.slow)
    uses_mpi = "meshlap.distributed" in code or "from meshlap import distributed" in code
    if uses_mpi and importlib.util.find_spec("petsc4py") is None:
        marks.append(pytest.mark.skip(reason="petsc4py absent: install it with .ci/install-mpi"))
    # the "Coming from" pages import their peer: skipped, naming it, where it is not installed
    missing = sorted({m for m in re.findall(r"^(?:import|from) (\w+)", code, re.M)
                      if importlib.util.find_spec(m) is None})
    if missing:
        marks.append(pytest.mark.skip(reason=f"{', '.join(missing)} absent (pip install it)"))
    return marks


def _params():
    # the README's blocks stand alone; a guide's blocks build on each other, in order
    for page, blocks in BLOCKS.items():
        runnable = [b for b in blocks if "trimesh_mesh" not in b]  # needs the user's own object
        if not runnable:
            continue
        if page.name == "README.md":
            for i, code in enumerate(runnable):
                first = code.strip().splitlines()[0]
                yield pytest.param([code], id=f"README-block{i}-{first[:30]}", marks=_marks(code))
        else:
            yield pytest.param(runnable, id=f"{page.stem}", marks=_marks("".join(runnable)))


def test_readme_has_examples():
    assert len(BLOCKS[Path("README.md")]) >= 1 and sum(map(len, BLOCKS.values())) >= 5


@pytest.mark.parametrize("blocks", list(_params()))
def test_readme_block_runs(blocks, monkeypatch, tmp_path):
    monkeypatch.chdir(ROOT)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    # the full tables take minutes (benchmarks/ makes them): the same code on the quick sizes,
    # writing into a scratch folder rather than the repository
    namespace = {"__name__": "readme"}
    for code in blocks:
        code = code.replace('reproduce.run(ns=(500, 2000, 8000, 16000), out_dir="tables")',
                            f"reproduce.run(quick=True, out_dir={str(tmp_path)!r})")
        exec(compile(code, "README.md", "exec"), namespace)
