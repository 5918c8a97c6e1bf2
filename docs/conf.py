"""Sphinx configuration of the feeddrive documentation site.

Build (the README's test command runs this, warnings as errors)::

    .venv/bin/sphinx-build -W --keep-going -b html docs docs/_build/html

Why Sphinx + PyData theme + numpydoc + sphinx-gallery: it is the toolchain of the libraries
feeddrive stands on and that its users know (numpy, scipy, xarray, pandas, matplotlib,
python-control); numpydoc reads the docstrings' own style; sphinx-gallery runs every example at
each build and shows its figures and output; all four are released every few months (MkDocs
itself has had no release since 1.6.1 in 2024).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import feeddrive

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))  # feeddrive_docs: the CLI reference, docstring fixes

project = "feeddrive"
author = "the feeddrive maintainers"
copyright = "2026, the feeddrive maintainers"  # noqa: A001 (Sphinx's name)
version = release = feeddrive.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = [
    "_build", "_generated",  # _generated/cli_commands.rst is included by cli.rst
    "examples/GALLERY_HEADER.rst", "sg_execution_times.rst",
    "auto_examples/*.py", "auto_examples/*.ipynb", "auto_examples/*.zip",
    "auto_examples/*.json", "auto_examples/*.md5",
]

# --- strict: every reference must resolve -------------------------------------------------
# nitpicky reports every unresolved cross-reference.  The package's own names must resolve;
# the libraries' names cannot without intersphinx, which would download their inventories at
# each build (the build runs offline), so they are listed here and nothing else is.
nitpicky = True
_EXTERNAL = (r"(np|numpy|xr|xarray|pd|pandas|scipy|plt|matplotlib|mpl|typer|click|rich|"
             r"control|ct|numba|pa|pyarrow|dask|distributed|concurrent|collections|typing|"
             r"pathlib|os|io|json|sqlite3|threading|http|socketserver|subprocess|enum|"
             r"datetime|types|abc|contextlib|dataclasses|argparse|signal|queue|"
             r"multiprocessing|tomllib)(\..*)?")
nitpick_ignore_regex = [
    ("py:.*", _EXTERNAL),
    # builtins and typing words as numpydoc writes them in "Parameters" types
    ("py:.*", r"(optional|default.*|array_like|array-like|callable|iterable|sequence|"
              r"mapping|file-like|path-like|scalar|None|Any|Self|T|F)"),
    # a generic type in a field's annotation, split at its comma by the docstring parser
    ("py:class", r"'?(tuple|dict|list|set)\[.*"),
    ("py:class", r"(ndarray|Dataset|DataArray|DataFrame|Series|Figure|Axes|Path|PathLike|"
                 r"StateSpace|TransferFunction|Console|Typer|Future|Executor|Client)"),
    # private names are not in the reference by design
    ("py:.*", r"(.*\.)?_\w+(\..*)?"),
    # the internals the docstrings name but the reference does not document (the generated
    # model's machinery, the solvers, the file plumbing): they show as code, not as links
    ("py:.*", r"feeddrive\.(solvers|protocol|registry|presets|fmu\.(solver|build|model)|"
              r"analysis\.critical|model\.(codegen|loops|"
              r"disturbances|compensation|friction\.\w+|mechanisms\.\w+)|"
              r"parameters\.(components|toml_io|validation))(\..*)?"),
    ("py:.*", r"(DENSE_CHUNK|KEEP_STREAMED|CHUNK_WALL_TIME|SimulationInterrupted|MARGINAL|"
              r"MAX_RESAMPLE_FACTOR|feeddrive\.analysis\.trace_input\.MAX_RESAMPLE_FACTOR|"
              r"steady_window|identifiable|from_run|settings|server|jobs|compute|"
              r"store\.point_key)"),
]

# --- API reference --------------------------------------------------------------------------
# undoc-members: the constants of an __all__ have no docstring but belong in the reference
autodoc_default_options = {"members": True, "undoc-members": True, "show-inheritance": False}
autodoc_member_order = "bysource"
autodoc_typehints = "none"  # the signatures carry the types; numpydoc renders the docstrings
autosummary_generate = False
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks: set[str] = set()
add_module_names = True

# --- Markdown pages (the user guide is docs/*.md) -----------------------------------------
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
suppress_warnings = ["myst.header"]  # pages start at "#" and may skip a level below

# --- gallery: every example runs at every build --------------------------------------------
sphinx_gallery_conf = {
    "examples_dirs": ["examples"],
    "gallery_dirs": ["auto_examples"],
    "filename_pattern": r".*\.py$",  # run every example, not only plot_*.py
    "abort_on_example_error": True,
    "only_warn_on_example_error": False,
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "reset_modules": ("matplotlib",),
    "min_reported_time": 0,  # every example page states its run time
    "show_memory": False,
    "write_computation_times": True,
}

# --- HTML ----------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"feeddrive {release}"
html_theme_options = {
    "navigation_with_keys": False,
    # the top navigation: User guide, API, CLI, Examples, Project (issue 41 item 12: 19 flat
    # entries, the API under "More")
    "header_links_before_dropdown": 5,
    "show_toc_level": 2,
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
    "secondary_sidebar_items": ["page-toc"],
}
html_static_path = ["_static"]
html_css_files = ["feeddrive.css"]
html_show_sourcelink = False
html_copy_source = False

# matplotlib without a display
os.environ.setdefault("MPLBACKEND", "Agg")


def setup(app):  # type: ignore[no-untyped-def]
    import feeddrive_docs

    feeddrive_docs.write_cli_reference(HERE / "_generated" / "cli_commands.rst")
    # before numpydoc (priority 500): |v| in a docstring is an absolute value, not an RST
    # substitution
    app.connect("autodoc-process-docstring", feeddrive_docs.escape_bars, priority=400)
    # a name re-exported by a package (feeddrive.ParameterError) is documented once, where
    # the everyday API names it; a docstring naming it by its module resolves to that entry
    app.connect("missing-reference", feeddrive_docs.resolve_reexported)
