"""The API reference has one page per public module, and the guides' toctree lists every guide.

CI builds the site itself with warnings as errors (.ci/run: sphinx-build -W).
"""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def test_one_api_page_per_public_module():
    # every module and subpackage, by its dotted name below meshlap (e.g. assembly.grid)
    modules = set()
    for p in (ROOT / "meshlap").rglob("*.py"):
        parts = list(p.relative_to(ROOT / "meshlap").with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        if parts and not any(x.startswith("_") for x in parts):
            modules.add(".".join(parts))
    pages = {p.stem for p in (DOCS / "api").glob("*.rst")} - {"index"}
    assert pages == modules
    index = (DOCS / "api" / "index.rst").read_text()
    assert {m for m in modules if re.search(rf"^   {re.escape(m)}$", index, re.M)} == modules
    for m in modules:
        assert f".. automodule:: meshlap.{m}" in (DOCS / "api" / f"{m}.rst").read_text()


def test_every_guide_and_notebook_is_in_the_toctree():
    index = (DOCS / "index.md").read_text()
    guides = {p.stem for p in DOCS.glob("*.md")} - {"index"}
    notebooks = {f"notebooks/{p.stem}" for p in (ROOT / "notebooks").glob("*.ipynb")}
    listed = set(re.findall(r"^([\w/-]+)$", index, re.M))
    assert guides | notebooks <= listed


def test_every_module_the_guides_name_is_there_after_import_meshlap():
    """``meshlap.inputs.read_input(path)`` in a guide works after ``import meshlap`` alone (it
    raised AttributeError for inputs and plot), and that import loads no optional package."""
    import subprocess
    import sys

    texts = [(ROOT / "README.md").read_text()] + [p.read_text() for p in DOCS.glob("*.md")] + \
        [p.read_text() for p in (ROOT / "notebooks").glob("*.ipynb")]
    named = {m for t in texts for m in re.findall(r"\bmeshlap\.([a-z_]+)\.[A-Za-z_]", t)}
    named -= {"distributed"}  # MPI: imported on its own (docs/distributed.md)
    named = {m for m in named if (ROOT / "meshlap" / f"{m}.py").exists() or (ROOT / "meshlap" / m).is_dir()}
    code = (f"import sys, meshlap; missing = [m for m in {sorted(named)!r} if not hasattr(meshlap, m)]; "
            "optional = ('matplotlib', 'k3d', 'meshio', 'pyvista', 'trimesh', 'mpi4py'); "
            "extra = [m for m in optional if m in sys.modules]; "
            "assert not missing and not extra, (missing, extra)")
    assert {"inputs", "plot", "spectral"} <= named
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)


def test_the_operator_guide_quotes_laplacians_signature():
    import inspect

    import meshlap

    text = (DOCS / "operator.md").read_text()
    quoted = re.search(r"`meshlap\.laplacian\((.*?)\)` returns", text, re.S).group(1)
    names = [p.split("=")[0].strip(" *") for p in quoted.replace("\n", " ").split(",")]
    params = inspect.signature(meshlap.laplacian).parameters
    assert [n for n in names if n] == [n for n in params], quoted
