# Sphinx configuration of the defocus manual (docs/build.sh builds it).
import defocus

project = "defocus"
author = "the defocus developers"
copyright = "the defocus developers"
release = version = defocus.__version__

extensions = ["myst_parser", "sphinx.ext.autodoc"]
source_suffix = {".md": "markdown"}
exclude_patterns = ["build.sh", "CMakeLists.txt", "*.cpp"]
myst_heading_anchors = 3
myst_enable_extensions = ["deflist"]
autodoc_member_order = "bysource"
html_theme = "furo"
html_title = "defocus manual"
