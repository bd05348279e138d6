"""The API reference has one page per public module, and the guides' toctree lists every guide.

CI builds the site itself with warnings as errors (.ci/run: sphinx-build -W).
"""

import pkgutil
import re
from pathlib import Path

import meshlap

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def public_modules():
    return {m.name[len("meshlap."):]: m.ispkg for m in pkgutil.walk_packages(meshlap.__path__, "meshlap.")
            if not any(part.startswith("_") for part in m.name.split("."))}


def test_one_api_page_per_public_module():
    modules = public_modules()
    assert {"geometry.core", "io", "store", "viewer"} <= set(modules)
    pages = {p.stem for p in (DOCS / "api").glob("*.rst")} - {"index"}
    assert pages == set(modules)
    index = (DOCS / "api" / "index.rst").read_text()
    assert set(re.findall(r"^   ([\w.]+)$", index, re.M)) == set(modules)
    for name, package in modules.items():
        page = (DOCS / "api" / f"{name}.rst").read_text()
        assert f".. automodule:: meshlap.{name}\n" in page
        assert (":no-members:" in page) == package  # a package's names are on its modules' pages


def test_every_guide_and_notebook_is_in_the_toctree():
    index = (DOCS / "index.md").read_text()
    guides = {p.stem for p in DOCS.glob("*.md")} - {"index"}
    notebooks = {f"notebooks/{p.stem}" for p in (ROOT / "notebooks").glob("*.ipynb")}
    listed = set(re.findall(r"^([\w/-]+)$", index, re.M))
    assert guides | notebooks <= listed
