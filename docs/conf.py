"""Sphinx configuration of the bvpnav documentation.

Build (offline; warnings are errors, as in ``tests/test_docs.py``)::

    pip install -e ".[docs]"
    sphinx-build -W --keep-going -j 2 -b html docs docs/_build/html
    python -m http.server --directory docs/_build/html 8000     # http://localhost:8000

Nothing is fetched at build or view time: no intersphinx, and MathJax is served from
``_static`` (sphinx-mathjax-offline).

The tutorial series in ``examples/tutorial`` (jupytext percent scripts, linked into
``docs/tutorials``) is executed by myst-nb at small size (``BVPNAV_SMALL=1``) unless the
environment says otherwise: ``BVPNAV_SMALL=0`` runs the full-size tutorials and
``BVPNAV_DOCS_EXECUTE=off`` builds the pages without running them (no figures).
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

from sphinx.ext import napoleon

import bvpnav

sys.path.insert(0, str(Path(__file__).parent / "_ext"))
import bvpnav_docs  # noqa: E402  (docs/_ext, just put on the path)

# -- Project ------------------------------------------------------------------------
project = "bvpnav"
author = "bvpnav developers"
copyright = "bvpnav developers"  # noqa: A001  (Sphinx's name)
release = bvpnav.__version__
version = release

# -- General ------------------------------------------------------------------------
extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "bvpnav_docs",  # docs/_ext: MathJax copied into _static (equations render without a network)
    "titles_only_toc",  # docs/_ext: the sidebar's tree made without copying each page's whole ToC
    "sphinx.ext.viewcode",
    "myst_nb",
]
# No intersphinx: the build must work without network access.
exclude_patterns = [
    "_build", "_ext", "conf.py", "**/.ipynb_checkpoints", "jupyter_execute",
]
templates_path = ["_templates"]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".py": "myst-nb"}
root_doc = "index"
default_role = "code"

# -- MyST / myst-nb -----------------------------------------------------------------
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
# The tutorials are jupytext "percent" scripts; myst-nb reads them as notebooks.
nb_custom_formats = {".py": "bvpnav_docs.read_percent_script"}
_EXECUTE_MODES = ("cache", "force", "auto", "inline", "off")
nb_execution_mode = os.environ.get("BVPNAV_DOCS_EXECUTE", "cache")
if nb_execution_mode not in _EXECUTE_MODES:
    raise ValueError(f"BVPNAV_DOCS_EXECUTE={nb_execution_mode!r}: choose one of {list(_EXECUTE_MODES)} "
                     "('off' builds the tutorial pages without running them)")
nb_execution_timeout = 600
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_execution_in_temp = True  # nothing a tutorial writes lands in the source tree
nb_merge_streams = True

# What the executed tutorials see (the kernel inherits this process's environment).
os.environ.setdefault("BVPNAV_SMALL", "1")
# The figure files the pages save go to a temporary folder, or to BVPNAV_DOCS_FIGURES when set
# (the test suite checks the tutorials' files there); the pages show the figures inline either way.
os.environ["BVPNAV_FIGURES"] = os.environ.get("BVPNAV_DOCS_FIGURES") or tempfile.mkdtemp(
    prefix="bvpnav-docs-figures-")
os.environ["MPLBACKEND"] = "module://matplotlib_inline.backend_inline"  # figures shown inline
# tqdm.auto sees a Jupyter kernel and warns that ipywidgets is missing; the pages need no widget.
os.environ["PYTHONWARNINGS"] = ",".join(
    filter(None, [os.environ.get("PYTHONWARNINGS"), "ignore:IProgress not found"]))

# -- API reference --------------------------------------------------------------------
autosummary_generate = True
# Submodules are found by walking each package (not from __all__), so every module gets a
# page; autodoc documents what each module's __all__ exports.
autosummary_ignore_module_all = True
# Each object is described once, under its shortest public name (the module template
# passes these to :exclude-members:; see bvpnav_docs.documented_elsewhere).
autosummary_context = {"documented_elsewhere": bvpnav_docs.documented_elsewhere(),
                       # each module page's Summary links every class and function it defines to its description
                       "module_objects": bvpnav_docs.module_objects()}
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "signature"
autodoc_typehints_format = "short"
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_param = False  # types as written (no guessed cross-references such as "n" in "shape (n,)")
napoleon_use_rtype = False
# "Attributes" sections are rendered like "Parameters": no attribute directives that would
# describe dataclass fields a second time, and types stay plain text.
napoleon_custom_sections = [("Attributes", "params_style")]

# -- HTML -----------------------------------------------------------------------------
html_theme = "furo"
html_title = f"bvpnav {release}"
html_static_path = []


def _napoleon_except_data(app, what, name, obj, options, lines):
    """Napoleon for everything but module data and attributes.

    Napoleon reads the first line of a data or attribute docstring as ``type: text``, so
    the project's ``#: Rate-table radius (m): ...`` comments would lose their first
    clause to a bogus type. Those comments are prose; leave them as written.
    """
    if what in ("data", "attribute"):
        return
    napoleon._process_docstring(app, what, name, obj, options, lines)


def setup(app):
    for listener in list(app.events.listeners.get("autodoc-process-docstring", [])):
        if listener.handler is napoleon._process_docstring:
            app.disconnect(listener.id)
    app.connect("autodoc-process-docstring", _napoleon_except_data)
