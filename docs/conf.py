"""Sphinx configuration: the gausspp site (``make docs``), built offline with warnings as errors.

The API reference is written at build time from ``gausspp.__all__`` and ``gausspp.scenes.__all__`` (one
list of public names, the packages' own), and the gallery runs every script in ``examples/`` except
those named in ``SLOW_EXAMPLES`` (shown, not executed) when the environment variable ``GAUSSPP_DOCS_SKIP_SLOW`` is set.
"""

from __future__ import annotations

import inspect
import os
import re
import shutil
import sys
import tempfile
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))

import gausspp  # noqa: E402
import gausspp.scenes  # noqa: E402

project = "gausspp"
author = "the gausspp authors"
copyright = "the gausspp authors"
release = version = gausspp.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx_gallery.gen_gallery",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = [
    "_build", "Thumbs.db", ".DS_Store", "auto_examples/*.ipynb", "auto_examples/*.py", "browser_check"
]  # fmt: skip
templates_path = ["_templates"]
# the gallery passes a function (reset_argv) in its configuration: the environment cache skips it
suppress_warnings = ["config.cache"]

html_theme = "pydata_sphinx_theme"
html_title = "gausspp"
html_theme_options = {"navigation_with_keys": False, "show_prev_next": True}
# the theme's light/dark switch starts from a mode it knows (a first visit otherwise logs "invalid theme mode")
html_context = {"default_mode": "light"}

myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath", "amsmath"]

autosummary_generate = True
autosummary_imported_members = True
autosummary_ignore_module_all = False
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_typehints = "description"
napoleon_numpy_docstring = True
napoleon_google_docstring = False

# The examples the test build (tests/test_docs_site.py) shows without running; `make docs` runs them all.
# Measured in the full build on a shared 2-core machine (each example page's "Total running time"): this one
# takes 26 s, every other example 1.4-5 s.
SLOW_EXAMPLES = [
    "error_vs_runtime.py",  # a work-precision sweep: four integrators x two step solvers, repeated
]
SKIP_SLOW = bool(os.environ.get("GAUSSPP_DOCS_SKIP_SLOW"))
_slow = "|".join(re.escape(name) for name in SLOW_EXAMPLES)

# Each example takes its figure's file name in argv[1] and, if it animates, its GIF's in argv[2]; in the
# build both go to a scratch directory, not into examples/. The gallery shows the figures captured from
# matplotlib and the GIFs the examples wrote (GifScraper).
_FIGURES = Path(tempfile.mkdtemp(prefix="gausspp-docs-"))


def _example_argv(gallery_conf: dict, script_vars: dict) -> list[str]:
    """Pass the example its figure's and its animation's paths in a scratch directory."""
    src = Path(script_vars["src_file"])
    argv = [str(_FIGURES / f"{src.stem}.png")]
    if "plot.animate(" in src.read_text():
        argv.append(str(_FIGURES / f"{src.stem}.gif"))
    return argv


class GifScraper:
    """Show the GIF an example wrote (``gausspp.plot.animate(..., out=argv[2])``) after the code block that wrote
    it: moved into the gallery's images, one image per GIF (sphinx-gallery's custom image scraper protocol)."""

    def __repr__(self) -> str:  # a stable name: the gallery's cache compares configurations by repr
        return "GifScraper"

    def __call__(self, block: object, block_vars: dict, gallery_conf: dict) -> str:
        from sphinx_gallery.scrapers import figure_rst

        gif = _FIGURES / (Path(block_vars["src_file"]).stem + ".gif")
        if not gif.is_file():
            return ""
        target = Path(next(block_vars["image_path_iterator"])).with_suffix(".gif")
        shutil.move(gif, target)
        return figure_rst([target], gallery_conf["src_dir"])


sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    # executed: every script, or all but the slow ones (these still appear, code without output)
    "filename_pattern": rf"/(?!({_slow})$)[^/]+\.py$" if SKIP_SLOW else r"/[^/]+\.py$",
    "ignore_pattern": r"__init__\.py$",
    "image_scrapers": ("matplotlib", GifScraper()),
    "reset_argv": _example_argv,
    "download_all_examples": True,
    "remove_config_comments": True,
    "abort_on_example_error": False,
    "only_warn_on_example_error": False,
    "min_reported_time": 1,
    # no "Computation times" pages: they load jQuery and DataTables from CDNs, which an offline site cannot reach
    # (the browser check of `make docs` reports them); each example's page still says its running time
    "write_computation_times": False,
    "within_subsection_order": "FileNameSortKey",
}


def _kind(obj: object) -> str:
    if inspect.ismodule(obj):
        return "Modules"
    if inspect.isclass(obj) and issubclass(obj, (Exception, Warning)):
        return "Errors and warnings"
    if inspect.isclass(obj):
        return "Classes"
    if not callable(obj):
        return "Registries"
    return "Functions"


def _api_section(module: object, title: str) -> list[str]:
    groups: dict[str, list[str]] = {}
    for name in sorted(module.__all__, key=str.lower):
        groups.setdefault(_kind(getattr(module, name)), []).append(name)
    lines = [title, "-" * len(title), "", f".. currentmodule:: {module.__name__}", ""]
    for kind in ("Classes", "Functions", "Registries", "Modules", "Errors and warnings"):
        if kind in groups:
            lines += [f".. rubric:: {kind}", "", ".. autosummary::", "   :toctree: generated", ""]
            lines += [f"   {name}" for name in groups[kind]] + [""]
    return lines


def _write_api() -> None:
    """Write api/index.rst from the packages' ``__all__`` (every public name, one place)."""
    lines = ["API reference", "=============", "", "Every public name of ``gausspp`` and ``gausspp.scenes``.", ""]
    lines += _api_section(gausspp, "gausspp") + _api_section(gausspp.scenes, "gausspp.scenes")
    target = DOCS / "api" / "index.rst"
    target.parent.mkdir(exist_ok=True)
    text = "\n".join(lines)
    if not target.exists() or target.read_text() != text:
        target.write_text(text)
    public = {f"{m.__name__}.{n}" for m in (gausspp, gausspp.scenes) for n in m.__all__}
    for page in (DOCS / "api" / "generated").glob("*.rst"):  # a name no longer public: its page goes too
        if page.stem not in public:
            page.unlink()


_write_api()
