"""Sphinx configuration of meshlap's documentation: ``sphinx-build -W -b html docs docs/_build``.

The API pages come from the docstrings (numpydoc), the guides are the Markdown files beside
this one (MyST), and the notebooks of ../notebooks are rendered as committed, without being
run (myst-nb, execution off); they are copied here at build time, since Sphinx reads only
files under this folder.
"""

import shutil
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

import meshlap  # noqa: E402

project = "meshlap"
author = "meshlap developers"
copyright = "meshlap developers, BSD-3-Clause"
version = release = meshlap.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_nb",
]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "jupyter_execute", "**.ipynb_checkpoints"]
nb_execution_mode = "off"  # render the notebooks as committed (CI runs them with nbmake)
myst_enable_extensions = ["dollarmath"]
myst_heading_anchors = 3
# links to files of the repository; attribute names that several classes share (S, L, mass)
suppress_warnings = ["myst.xref_missing", "ref.python"]

autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "imported-members": False}
numpydoc_show_class_members = False
numpydoc_xref_param_type = False
html_theme = "alabaster"
html_title = f"meshlap {release}"



def _plain_text_bars(app, what, name, obj, options, lines):
    # meshlap's docstrings write math in plain text: |x| is an absolute value or a norm, not an
    # RST substitution; code lines (doctests) are left as they are
    for i, line in enumerate(lines):
        if not line.lstrip().startswith((">>>", "...")):
            lines[i] = line.replace("|", "\\|")


def setup(app):
    app.connect("autodoc-process-docstring", _plain_text_bars, priority=100)  # before numpydoc


# the notebooks, as committed
shutil.copytree(ROOT / "notebooks", HERE / "notebooks", dirs_exist_ok=True,
                ignore=shutil.ignore_patterns("*.html", ".ipynb_checkpoints"))
