"""Sphinx configuration of the ffrmbs documentation site.

Build (warnings are errors; about a minute plus the gallery's run time)::

    python3 -m pip install '.[docs]'
    python3 -m sphinx -j auto -W --keep-going -b html docs docs/_build/html

Generated at build time, never committed: the API stubs (``api/generated/``), the
gallery (``gallery/``, from ``../examples/gallery``), the scene-key reference (from
``ffrmbs_app.scene_file.schema``, extension ``_ext/scene_keys.py``) and the validation
report's tables (from the committed ``validation/_data/``, extension
``_ext/validation_report.py``).
"""
import os
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))              # this checkout's packages win over an installed copy
sys.path.insert(0, str(DOCS / "_ext"))
os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
os.environ.setdefault("MPLBACKEND", "Agg")

import ffrmbs  # noqa: E402

project = "ffrmbs"
author = "the ffrmbs authors"
copyright = "the ffrmbs authors, MIT licence"
release = version = ffrmbs.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "api_links",
    "scene_keys",
    "validation_report",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "validation/_data", "gallery/*.ipynb"]
root_doc = "index"
smartquotes = False               # "moreau" in the text is what a scene file takes, straight quotes

# --- API reference: autosummary stubs generated per public module --------------------------------
autosummary_generate = True
autosummary_imported_members = False
# A package's page shows its docstring and its modules; each name it re-exports is documented
# once, in the module that defines it (references to ``package.Name`` resolve there:
# ``_ext/api_links.py``).
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": True,
                           "ignore-module-all": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_typehints_format = "short"
autodoc_preserve_defaults = True
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_rtype = False
napoleon_use_ivar = True          # "Attributes" as fields, not a second description of dataclass fields
# ``python -m`` entry points run when imported: never import them while listing modules.
autosummary_mock_imports = ["validation.bench.__main__"]
# The docstrings name types in prose ("ndarray (N, 3)", "float [m]"), not as cross-references.
nitpicky = False

# --- MyST (the guide's .md pages) ------------------------------------------------------------------
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# --- gallery: every script of examples/gallery runs at build time ---------------------------------
sphinx_gallery_conf = {
    "examples_dirs": "../examples/gallery",
    "gallery_dirs": "gallery",
    "filename_pattern": r".*\.py$",
    "ignore_pattern": r"__init__\.py",
    "download_all_examples": False,
    "remove_config_comments": True,
    "abort_on_example_error": True,
    "image_scrapers": ("matplotlib",),
    "within_subsection_order": "FileNameSortKey",
}

# --- HTML ---------------------------------------------------------------------------------------
html_theme = "furo"
html_title = f"ffrmbs {release}"
html_static_path = []
