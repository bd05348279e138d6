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
