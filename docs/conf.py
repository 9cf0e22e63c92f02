"""Sphinx configuration of petthm's manual (``make docs``): Markdown pages
(MyST), the theme of PETSc's own manual, warnings as errors."""
import os
import sys

sys.path.insert(0, os.path.abspath("_ext"))
sys.path.insert(0, os.path.abspath(".."))

project = "petthm"
author = "the petthm developers"
copyright = "2026, the petthm developers"

extensions = ["myst_parser", "petthm_options"]
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "_ext"]

html_theme = "pydata_sphinx_theme"
html_title = "petthm"
html_theme_options = {"navigation_depth": 3, "show_toc_level": 2}
html_static_path = []
