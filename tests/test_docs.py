"""The documentation site builds offline with warnings as errors and has its key pages.

The build (conftest's session fixture ``docs_build``, shared with test_tutorial) runs
``sphinx-build -W --keep-going -b html`` (as a reader would) on a copy of ``docs/`` in a
temporary folder, so the generated API stubs never land in the work tree; every proxy points
at a closed loopback port, so any attempt to fetch something during the build (intersphinx
inventories, remote images) fails it. The tutorials, the gallery and the executed guides are
executed at small size (``BVPNAV_SMALL=1``).
"""

from __future__ import annotations

import json
import os
import pkgutil
import re
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from _docs_only import environment as docs_only_environment
from _hostile import assert_unchanged, snapshot

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

#: the site build (a sphinx run that executes the tutorials) and the wheel builds
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
TUTORIAL = ROOT / "examples" / "tutorial"
SCRIPTS = sorted(TUTORIAL.glob("[0-9][0-9]_*.py"))
GALLERY = sorted((ROOT / "examples" / "gallery").glob("[a-z]*.py"))
#: Hand-written pages that myst-nb executes (their code cells show output and a figure).
EXECUTED_GUIDES = ["getting_started", "guide/strapdown", "guide/readers"]
GUIDES = ["items", "error_models", "solvers", "lambda", "uncertainty", "files_cli", "batch", "strapdown",
          "readers",
          "safety"]


def _sources(*roots: Path) -> dict:
    """:func:`snapshot` of the files under ``roots`` but bytecode caches, which tests running
    beside the build (pytest -n) write when they import an example."""
    return {p: v for p, v in snapshot(*roots).items() if "__pycache__" not in p.parts}


@pytest.fixture
def site(docs_build):
    """The HTML folder of the site, built once per session (conftest's ``docs_build``)."""
    return docs_build.html


def test_every_tutorial_script_is_linked_into_the_gallery():
    """A new tutorial in examples/tutorial needs its link in docs/tutorials (or the site misses it)."""
    assert SCRIPTS, "no tutorial scripts found"
    for script in SCRIPTS:
        link = DOCS / "tutorials" / script.name
        assert link.exists(), (
            f"docs/tutorials/{script.name} is missing: add it with "
            f"`ln -s ../../examples/tutorial/{script.name} docs/tutorials/`")
        assert link.resolve() == script.resolve(), f"docs/tutorials/{script.name} does not point at {script}"
    linked = sorted(p.name for p in (DOCS / "tutorials").glob("[0-9][0-9]_*.py"))
    assert linked == [p.name for p in SCRIPTS], "docs/tutorials links a script that examples/tutorial lacks"


def test_docs_only_environment_blocks_exactly_what_the_extra_does_not_install():
    """The site fixture's guard: with [docs] the readers' packages and Sphinx are importable and the
    test-only ones are not; an extra without them (parquet) would block rosbags, as a fresh venv
    with the old [docs] lacked it (tutorial 08 then fails with a ModuleNotFoundError naming it)."""
    from _docs_only import blocked_modules, docs_closure

    closure = docs_closure("docs")
    assert {"sphinx", "myst-nb", "rosbags", "pynmea2", "pymap3d", "cvxpy"} <= closure
    assert not {"pytest", "pyarrow", "evo", "hypothesis"} & closure
    blocked = set(blocked_modules("docs"))
    assert {"pytest", "pyarrow", "evo"} <= blocked
    assert not {"rosbags", "pynmea2", "pymap3d", "sphinx", "myst_nb", "numpy"} & blocked
    assert {"rosbags", "sphinx", "pynmea2"} <= set(blocked_modules("parquet"))


def test_every_gallery_script_is_linked_into_the_gallery():
    """A gallery page per use; each script in examples/gallery has its link in docs/gallery."""
    assert [p.stem for p in GALLERY] == sorted(
        ["vehicle_with_fixes", "walker_with_stances", "lambda_study", "solver_comparison"])
    linked = sorted((DOCS / "gallery").glob("[a-z]*.py"))
    assert [p.name for p in linked] == [p.name for p in GALLERY]
    for link in linked:
        assert link.is_symlink() and link.resolve() == (ROOT / "examples" / "gallery" / link.name).resolve()


def _figures(site: Path, page: str) -> list[Path]:
    html = (site / f"{page}.html").read_text()
    folder = (site / page).parent
    return [(folder / src).resolve() for src in re.findall(r'<img[^>]+src="([^"]+\.png)"', html)]


@pytest.mark.parametrize("page", EXECUTED_GUIDES + [f"gallery/{p.stem}" for p in GALLERY])
def test_guides_and_gallery_show_output_and_figures(site, page):
    """The guides and the gallery pages were executed: printed output, figures, no traceback."""
    html = (site / f"{page}.html").read_text()
    assert "cell_output" in html and "Traceback" not in html
    figures = _figures(site, page)
    assert figures, f"{page}: no figure on the page"
    for png in figures:
        assert png.is_file() and png.stat().st_size > 5000, png
    if page.startswith("gallery/"):  # the use's own figure and its report's main figures
        assert len(figures) >= 3, f"{page}: its main figures ({len(figures)} shown)"
        assert "report figures: " in html and "solution" in html


def test_index_routes_a_recording_to_the_readers_and_strapdown_guides(site):
    html = (site / "index.html").read_text()
    line = re.search(r"Have a recording.*?</li>", html, re.DOTALL).group(0)
    assert 'href="guide/readers.html"' in line and 'href="guide/strapdown.html"' in line, line
    assert 'href="gallery/index.html"' in html


def test_key_pages_exist(site):
    pages = ["index", "getting_started", "formulation", "guide/index", "tutorials/index",
             "api/index", "changelog", "genindex", "py-modindex", "search"]
    pages += [f"guide/{g}" for g in GUIDES]
    pages += [f"tutorials/{p.stem}" for p in SCRIPTS]
    missing = [p for p in pages if not (site / f"{p}.html").is_file()]
    assert not missing, missing


def test_api_reference_lists_the_public_api(site):
    top = (site / "api" / "generated" / "bvpnav.html").read_text()
    for name in ("NavigationProblem", "ImuData", "Solution", "InputError", "compare_solvers"):
        assert f'id="bvpnav.{name}"' in top, name
    assert 'id="bvpnav.NavigationProblem.solve"' in top
    cons = (site / "api" / "generated" / "bvpnav.constraints.html").read_text()
    for name in ("Position", "Velocity", "AverageVelocity", "TrackLine", "SpeedLimit"):
        assert f'id="bvpnav.constraints.{name}"' in cons, name


def test_api_reference_is_recursive_over_every_public_module(site):
    """Every public module of the installed package has its page, wherever it lives."""
    import bvpnav
    import bvpnav.constraints

    names = {"bvpnav", "bvpnav.constraints"}
    for pkg in (bvpnav, bvpnav.constraints):
        for info in pkgutil.walk_packages(pkg.__path__, prefix=pkg.__name__ + "."):
            if not any(part.startswith("_") for part in info.name.split(".")):
                names.add(info.name)
    assert {"bvpnav.problem", "bvpnav.error_models.bias", "bvpnav.constraints.position"} <= names
    missing = sorted(n for n in names if not (site / "api" / "generated" / f"{n}.html").is_file())
    assert not missing, missing


def _public_modules() -> list[str]:
    import bvpnav
    import bvpnav.constraints

    names = {"bvpnav", "bvpnav.constraints"}
    for pkg in (bvpnav, bvpnav.constraints):
        for info in pkgutil.walk_packages(pkg.__path__, prefix=pkg.__name__ + "."):
            if not any(part.startswith("_") for part in info.name.split(".")):
                names.add(info.name)
    return sorted(names)


def test_api_index_lists_every_module(site):
    """The API index links every public module's page (not only the two top packages)."""
    html = (site / "api" / "index.html").read_text()
    linked = set(re.findall(r'href="generated/([\w.]+)\.html(?:#[\w.-]*)?"', html))
    names = _public_modules()
    assert {"bvpnav.evaluate", "bvpnav.linalg", "bvpnav.solve", "bvpnav.readers", "bvpnav.lam",
            "bvpnav.backends", "bvpnav.error_models.bias", "bvpnav.constraints.position"} <= set(names)
    missing = sorted(set(names) - linked)
    assert not missing, f"modules without a row on the API index: {missing}"


def _resolve(dotted: str):
    import importlib

    parts = dotted.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        for part in parts[k:]:
            obj = getattr(obj, part)
        return obj
    raise ImportError(dotted)


@pytest.mark.parametrize("module", _public_modules())
def test_every_module_page_links_to_the_objects_it_defines(site, module):
    """Each class and function a module defines (and exports) is a link on the module's page to
    the one place it is described: an anchor with that object's id, on a page that has it."""
    import importlib
    import inspect

    mod = importlib.import_module(module)
    names = getattr(mod, "__all__", None) or [k for k in vars(mod) if not k.startswith("_")]
    defined = {k: getattr(mod, k) for k in names if hasattr(mod, k)}
    defined = {k: v for k, v in defined.items()
               if (inspect.isclass(v) or inspect.isfunction(v)) and getattr(v, "__module__", "") == module
               and v.__doc__}  # autodoc describes documented objects only (bvpnav.cli.build_parser has none)
    html = (site / "api" / "generated" / f"{module}.html").read_text()
    links = re.findall(r'<a class="reference internal" href="([\w.]*)#([\w.]+)"', html)
    unlinked = []
    for k, obj in defined.items():
        targets = [(page or f"{module}.html", anchor) for page, anchor in links if anchor.endswith("." + k)]
        good = [t for t in targets if _resolve(t[1]) is obj
                and f'id="{t[1]}"' in (site / "api" / "generated" / t[0]).read_text()]
        if not good:
            unlinked.append(k)
    assert not unlinked, f"{module}: no link to the description of {unlinked}"


@pytest.mark.parametrize("script", SCRIPTS, ids=[p.stem for p in SCRIPTS])
def test_tutorial_pages_were_executed(site, script):
    """Each tutorial page shows its code, the output it printed and its figure."""
    html = (site / "tutorials" / f"{script.stem}.html").read_text()
    assert "cell_output" in html, "no executed output on the page"
    images = re.findall(r'<img[^>]+src="([^"]+\.png)"', html)
    assert images, "no figure on the page"
    for src in images:
        png = (site / "tutorials" / src).resolve()
        assert png.is_file() and png.stat().st_size > 5000, src
    assert "Traceback" not in html


def test_formulation_page_has_equations_rendered_without_a_network(site):
    html = (site / "formulation.html").read_text()
    assert html.count('class="math') >= 10
    scripts = re.findall(r'<script[^>]*src="([^"]*mathjax[^"]*)"', html)
    assert scripts == ["_static/mathjax/tex-chtml.js"], scripts
    assert (site / "_static" / "mathjax" / "tex-chtml.js").stat().st_size > 100_000
    remote = sorted(str(p.relative_to(site)) for p in site.rglob("*.html")
                    if re.search(r'<(?:script|link|img)[^>]*(?:src|href)="(?:https?:)?//', p.read_text()))
    assert not remote, f"pages that load something from the network: {remote}"


def test_changelog_is_grouped_by_issue(site):
    """CHANGELOG.md at the top (where people look); the site's page is a link to it."""
    text = (ROOT / "CHANGELOG.md").read_text()
    for issue in (5, 7, 8, 17):
        assert re.search(rf"^## .*[Ii]ssue {issue}\b", text, re.MULTILINE), issue
    assert (DOCS / "changelog.md").resolve() == (ROOT / "CHANGELOG.md").resolve()
    page = (site / "changelog.html").read_text()
    assert "Issue 17: uncertainty" in page and "Issue 15: one solve pipeline" in page


# pip builds in the source tree (build/, *.egg-info): one worker for every wheel build (pytest -n)
@pytest.mark.xdist_group("wheel-build")
def test_license_and_typing_marker_ship_in_the_wheel(wheel_build):
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert meta["license"] == {"text": "MIT"}
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("MIT License") and "Copyright (c) bvpnav developers" in text
    proc, folder = wheel_build   # conftest: pip wheel --no-deps of the source tree
    assert proc.returncode == 0, proc.stdout + proc.stderr
    names = zipfile.ZipFile(next(folder.glob("bvpnav-*.whl"))).namelist()
    assert "bvpnav/py.typed" in names
    assert any(re.search(r"\.dist-info/(licenses/)?LICENSE$", n) for n in names), names


#: Runs the ``python`` code blocks of each page in order, one namespace per page.
_RUN_BLOCKS = r"""
import json, sys, traceback
pages = json.loads(sys.stdin.read())
failed = []
for page, blocks in pages.items():
    ns = {"__name__": "__docs__"}
    for k, code in enumerate(blocks, 1):
        try:
            exec(compile(code, f"{page} block {k}", "exec"), ns)
        except BaseException:
            failed.append(f"{page}, python block {k}:\n{traceback.format_exc()}")
            break
print("\n".join(failed), file=sys.stderr)
sys.exit(1 if failed else 0)
"""


def _python_blocks(page: Path, cells: bool = True) -> list[str]:
    """The ``python`` blocks of a page and (with ``cells``) the code cells of a page that
    myst-nb executes."""
    fence = r"(?:python|\{code-cell\} ipython3)" if cells else "python"
    return re.findall(rf"^```{fence}\n(.*?)^```", page.read_text(), re.MULTILINE | re.DOTALL)


def test_code_on_the_pages_runs(tmp_path):
    """Every ``python`` block of the hand-written pages runs as shown (a page's blocks in
    order, sharing one namespace), in an empty folder, at test size. The code cells of the
    pages myst-nb executes (:data:`EXECUTED_GUIDES`) are run by the site build, in the same
    docs-only environment, at the same size, in an empty folder, failing the build on an
    error (``nb_execution_raise_on_error``; :func:`test_guides_and_gallery_show_output_and_figures`):
    here their plain ``python`` blocks run, each page's on their own."""
    executed = {f"{g}.md" for g in EXECUTED_GUIDES}
    pages = {str(p.relative_to(DOCS)): _python_blocks(p, cells=str(p.relative_to(DOCS)) not in executed)
             for p in sorted(DOCS.glob("*.md")) + sorted((DOCS / "guide").glob("*.md"))
             if not p.name.startswith("_")}
    assert all(_python_blocks(DOCS / page) for page in executed), "an executed page without code cells"
    pages = {k: v for k, v in pages.items() if v}
    assert {"guide/items.md", "guide/strapdown.md"} <= set(pages)
    before = _sources(ROOT / "examples", DOCS)
    env = dict(os.environ, BVPNAV_SMALL="1", MPLBACKEND="Agg")
    env.update(docs_only_environment(tmp_path / "docs-only"))  # only what bvpnav[docs] installs
    run = tmp_path / "run"
    run.mkdir()
    proc = subprocess.run([sys.executable, "-c", _RUN_BLOCKS], input=json.dumps(pages), cwd=run,
                          env=env, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-6000:]
    assert_unchanged(before)
