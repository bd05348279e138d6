"""The Python examples of the README and of the guides in docs/ run as written (from the
repository root, as a user would)."""

import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
BLOCKS = [(page.relative_to(ROOT), code) for page in PAGES
          for code in re.findall(r"```python\n(.*?)```", page.read_text(), re.S)]


def _params():
    for i, (page, code) in enumerate(BLOCKS):
        first = code.strip().splitlines()[0]
        marks = []
        if "trimesh_mesh" in code:
            marks.append(pytest.mark.skip(reason="needs the user's own trimesh object"))
        if "sphere(16000" in code:
            marks.append(pytest.mark.slow)
        uses_mpi = "meshlap.distributed" in code or "from meshlap import distributed" in code
        if uses_mpi and importlib.util.find_spec("petsc4py") is None:
            marks.append(pytest.mark.skip(reason="petsc4py absent: install it with .ci/install-mpi"))
        yield pytest.param(code, id=f"{page.stem}-block{i}-{first[:30]}", marks=marks)


def test_readme_has_examples():
    assert len(BLOCKS) >= 5


@pytest.mark.parametrize("code", list(_params()))
def test_readme_block_runs(code, monkeypatch, tmp_path):
    monkeypatch.chdir(ROOT)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    # the full tables take minutes (benchmarks/ makes them): the same code on the quick sizes,
    # writing into a scratch folder rather than the repository
    code = code.replace('reproduce.run(ns=(500, 2000, 8000, 16000), out_dir="tables")',
                        f"reproduce.run(quick=True, out_dir={str(tmp_path)!r})")
    exec(compile(code, "README.md", "exec"), {"__name__": "readme"})
