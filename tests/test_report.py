"""The quality report (issue 41 items 2 and 3): the HTML checked without a browser, the page
loaded in headless Chromium, the worst normalized residual named, and the figures' legends
and axis units."""

from __future__ import annotations

import base64
import io
import os
import re
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402

from bvpnav import NavigationProblem, plot, report  # noqa: E402
from bvpnav.cli import main  # noqa: E402
from bvpnav.constraints import Position  # noqa: E402
from bvpnav.errors import InputError  # noqa: E402
from bvpnav.imu import ImuData  # noqa: E402
from bvpnav.io import write_table  # noqa: E402
from bvpnav.samples import _strapdown_frame, write_sample  # noqa: E402
from bvpnav.scenarios import car_drive  # noqa: E402
from bvpnav.sensors import grade  # noqa: E402
from bvpnav.spec import Spec, dumps_spec  # noqa: E402

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
#: The fix moved 30 m east (index into the drive's fixes: t = 30 s).
MOVED = 30
CHROMIUM = "/usr/bin/chromium"


# ------------------------------------------------------------------ fixtures
@pytest.fixture(scope="module")
def walking(tmp_path_factory):
    """`bvpnav simulate walking` solved with --report: (folder, report path)."""
    d = tmp_path_factory.mktemp("walking")
    write_sample("walking", d / "rec")
    out = d / "report.html"
    assert main(["solve", str(d / "rec" / "recording.csv"), "--spec", str(d / "rec" / "spec.toml"), "--out",
                 str(d / "traj.csv"), "--report", str(out), "-q"]) == 0
    return d, out


def _car_files(folder: Path, moved: bool) -> tuple[Path, Path, np.ndarray]:
    """A one-minute car drive at 10 Hz with 1 Hz GNSS fixes as a recording and spec (the
    tactical grade's error model and noise), fix MOVED shifted 30 m in x when ``moved``."""
    drive = car_drive(60.0, 10.0, seed=1)
    g = grade("tactical")
    fixes = drive.fix_position.copy()
    if moved:
        fixes[MOVED, 0] += 30.0
    fix_items = [Position(t=drive.fix_t, value=fixes, sigma=np.tile(drive.fix_sigma, (drive.fix_t.size, 1)),
                          name="gnss")]
    q0 = drive.initial_attitude_guess.as_quat()
    inp = {"time": "t", "time_unit": "s", "specific_force": ["f_x", "f_y", "f_z"],
           "gyro": ["w_x", "w_y", "w_z"], "gyro_unit": "rad/s", "unit": "m/s^2", "frame": "enu",
           "initial_attitude": {"quaternion": [float(v) for v in q0], "scalar": "last"}}
    folder.mkdir(parents=True, exist_ok=True)
    rec, spec = folder / "recording.csv", folder / "spec.toml"
    write_table(_strapdown_frame(drive.t, drive.specific_force, w=drive.gyro), rec)
    sa = g.sigma_a(drive.rate, 30.0)
    spec.write_text(dumps_spec(Spec(inp, {"residual": "acceleration", "sigma_a": float(np.ravel(sa)[0])},
                                    {"solver": "direct", "lam": 1.0, "uncertainty": True}, fix_items,
                                    list(g.error_model(30.0).components))))
    write_table(pd.DataFrame({"t": drive.t, **{a: drive.position[:, k] for k, a in enumerate("xyz")}}),
                folder / "truth.csv")
    return rec, spec, drive.fix_t


@pytest.fixture(scope="module")
def car(tmp_path_factory):
    """The drive with one fix moved 30 m, solved by `bvpnav solve --report`: (folder, report)."""
    d = tmp_path_factory.mktemp("car")
    rec, spec, _ = _car_files(d / "rec", moved=True)
    out = d / "report.html"
    assert main(["solve", str(rec), "--spec", str(spec), "--out", str(d / "traj.csv"), "--report", str(out),
                 "-q"]) == 0
    return d, out


# ------------------------------------------------------------------ the HTML, without a browser
class _Page(HTMLParser):
    """Images, tables (class -> rows of cell texts), links and scripts of a page."""

    def __init__(self):
        super().__init__()
        self.imgs, self.tables, self.urls, self.tags, self.figures = [], {}, [], [], []
        self._table = None
        self._row = None
        self._cell = None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.tags.append(tag)
        for key in ("src", "href", "data", "poster", "action"):
            if a.get(key):
                self.urls.append(a[key])
        if tag == "img":
            self.imgs.append(a)
        elif tag == "figure":
            self.figures.append(a.get("id", ""))
        elif tag == "table":
            self._table = a.get("class", "")
            self.tables[self._table] = []
        elif tag == "tr" and self._table is not None:
            self._row = []
        elif tag in ("td", "th") and self._row is not None:
            self._cell = []

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self._row.append("".join(self._cell).strip())
            self._cell = None
        elif tag == "tr" and self._row is not None:
            self.tables[self._table].append(self._row)
            self._row = None
        elif tag == "table":
            self._table = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def _parse(path: Path) -> _Page:
    page = _Page()
    page.feed(path.read_text(encoding="utf-8"))
    return page


def _check_self_contained(path: Path, figures: set) -> _Page:
    text = path.read_text(encoding="utf-8")
    page = _parse(path)
    assert {"script", "link", "iframe", "object", "embed"}.isdisjoint(page.tags)
    # nothing fetched from elsewhere: every URL is a data: URI, no http(s) or protocol-relative
    assert all(u.startswith("data:") for u in page.urls), [u[:40] for u in page.urls]
    assert not re.search(r"(https?:)?//[a-z0-9.-]+\.[a-z]{2,}", re.sub(r"data:[^\"']+", "", text), re.I)
    assert "@import" not in text and "url(" not in text
    assert page.figures == [f"fig-{k}" for k in report.FIGURES if k in figures]
    assert len(page.imgs) == len(figures)
    for img in page.imgs:
        src = img["src"]
        assert src.startswith("data:image/png;base64,")
        raw = base64.b64decode(src.split(",", 1)[1], validate=True)
        assert raw.startswith(PNG_MAGIC)
        pix = mpimg.imread(io.BytesIO(raw), format="png")
        assert pix.ndim == 3 and pix.shape[0] > 100 and pix.shape[1] > 100
        assert img.get("alt")
    assert {"summary", "worst", "items"} <= set(page.tables)
    return page


def test_walking_report_is_one_self_contained_file(walking):
    d, out = walking
    page = _check_self_contained(out, {"map", "solution", "residuals"})
    summary = dict(r for r in page.tables["summary"][1:])
    assert summary["samples"] == "1266" and summary["verified"] == "yes" and summary["solver"] == "direct"
    assert summary["axes"] == "x, y, z"
    # every item is hard: the worst normalized residuals are the acceleration residuals w / sigma_a
    # (sigma_a the default 1 m/s^2, said so), largest first
    worst = page.tables["worst"]
    assert worst[0][:3] == ["rank", "t (s)", "item"] and len(worst) == 1 + report.WORST_ROWS
    norm = [abs(float(r[7])) for r in worst[1:]]
    assert norm == sorted(norm, reverse=True) and norm[0] > 1.0
    assert {r[2] for r in worst[1:]} == {"acceleration w"}
    assert "default, not stated" in summary["sigma_a (m/s^2)"]
    items = page.tables["items"]
    assert [r[0] for r in items[1:]] == ["start"] + [f"stance {k}" for k in range(11)]


@pytest.mark.slow
def test_car_report_names_the_moved_fix_first(car):
    d, out = car
    page = _check_self_contained(out, {"map", "solution", "residuals", "sensor_errors", "attitude", "loop"})
    header, first, second = page.tables["worst"][:3]
    row = dict(zip(header, first, strict=True))
    assert (row["item"], row["row"], float(row["t (s)"])) == ("gnss", "x(t=30)", 30.0)
    # moved 30 m with sigma 1 m: the estimate follows the other fixes, the residual is most of -30 m
    assert float(row["normalized"]) < -20.0 and row["residual"].endswith(" m") and row["sigma"] == "1 m"
    assert abs(float(dict(zip(header, second, strict=True))["normalized"])) < 5.0
    # the sensor errors: biases at their knots (0, 30, 60 s) with standard deviations
    ep = page.tables["error-params"]
    params = {r[0]: r for r in ep[1:]}
    assert [params[f"gyro_bias_z[{k}]"][1] for k in range(3)] == ["0", "30", "60"]
    assert all(float(params[n][3]) > 0 for n in params)
    text = out.read_text(encoding="utf-8")
    assert "Attitude loop:" in text and "Attitude corrections" in text


@pytest.mark.slow
def test_car_report_without_the_moved_fix_has_no_outlier(tmp_path):
    rec, spec, _ = _car_files(tmp_path / "rec", moved=False)
    out = tmp_path / "r.html"
    assert main(["solve", str(rec), "--spec", str(spec), "--out", str(tmp_path / "t.csv"), "--report",
                 str(out), "-q"]) == 0
    header, first = _parse(out).tables["worst"][:2]
    assert abs(float(dict(zip(header, first, strict=True))["normalized"])) < 5.0


def test_report_refuses_an_input_and_other_suffixes(walking, tmp_path):
    d, _ = walking
    spec = d / "rec" / "spec.toml"
    before = spec.read_bytes()
    args = ["solve", str(d / "rec" / "recording.csv"), "--spec", str(spec), "--out", str(tmp_path / "t.csv"),
            "-q", "--report"]
    assert main([*args, str(spec)]) == 2
    assert spec.read_bytes() == before
    assert main([*args, str(tmp_path / "r.pdf")]) == 2
    assert not (tmp_path / "t.csv").exists() and not (tmp_path / "r.pdf").exists()


# ------------------------------------------------------------------ normalized residuals: known answers
def _clash(mode: str, **kw):
    """0 m held hard at t = 1 s and 0.3 m given at the same time (sigma 0.1 m): the residual
    of the second is exactly -0.3 m, normalized -3."""
    t = np.linspace(0.0, 2.0, 21)
    prob = NavigationProblem(ImuData(t=t, acc=np.zeros(21)), sigma_a=0.5)
    prob.add(Position(t=[0.0, 1.0], value=[0.0, 0.0], name="held"),
             Position(t=1.0, value=0.3, sigma=0.1, mode=mode, name="clash", **kw))
    return prob.solve(solver="clarabel" if mode == "robust" else "direct")


def test_normalized_residuals_known_answer():
    sol = _clash("soft")
    tab = report.normalized_residuals(sol)
    first = tab.iloc[0]
    assert (first["item"], first["row"], first["t"], first["units"]) == ("clash", "x(t=1)", 1.0, "m")
    np.testing.assert_allclose([first["residual"], first["sigma"], first["normalized"]], [-0.3, 0.1, -3.0],
                               rtol=0, atol=1e-9)
    assert not first["down_weighted"]
    # the hard item has no sigma: not listed; the acceleration residuals are, against sigma_a = 0.5
    assert "held" not in set(tab["item"])
    w = tab[tab["item"] == "acceleration w"]
    assert len(w) == 21 and np.allclose(w["sigma"], 0.5)
    np.testing.assert_allclose(np.sort(w["normalized"].abs().to_numpy()),
                               np.sort(np.abs(sol.residuals["w_x"].to_numpy()) / 0.5), rtol=0, atol=1e-15)


@pytest.mark.parametrize("huber, down", [(0.05, True), (1.0, False)])
def test_robust_rows_beyond_the_threshold_are_down_weighted(huber, down):
    sol = _clash("robust", huber=huber)
    first = report.normalized_residuals(sol).iloc[0]
    assert first["item"] == "clash" and abs(first["residual"] + 0.3) < 1e-6
    assert bool(first["down_weighted"]) is down


def test_solution_report_checks_the_suffix(tmp_path):
    sol = _clash("soft")
    with pytest.raises(InputError, match="end its name with .html"):
        sol.report(tmp_path / "r.txt")
    sol.report(tmp_path / "r.html")
    page = _check_self_contained(tmp_path / "r.html", {"solution", "residuals"})
    assert page.tables["worst"][1][2:4] == ["clash", "x(t=1)"]


# ------------------------------------------------------------------ a real browser
def _chromium_or_skip() -> str:
    if Path(CHROMIUM).is_file() or shutil.which("chromium"):
        return CHROMIUM if Path(CHROMIUM).is_file() else shutil.which("chromium")
    if os.environ.get("CI"):
        pytest.fail(f"CI: no headless browser at {CHROMIUM}; .ci/run installs Debian's chromium with apt-get")
    pytest.skip(f"no headless browser at {CHROMIUM} (install Debian's chromium: apt-get install chromium); "
                "the browser test runs under CI")


def _chromium(exe: str, tmp: Path, url: str, *extra) -> subprocess.CompletedProcess:
    return subprocess.run([exe, "--headless", "--no-sandbox", "--disable-gpu",
                           "--disable-background-networking", "--disable-component-update", "--disable-sync",
                           "--no-first-run", f"--user-data-dir={tmp / 'profile'}", "--enable-logging=stderr",
                           "--v=0", *extra, url], capture_output=True, text=True, timeout=180, check=False)


def test_walking_report_loads_in_headless_chromium(walking, tmp_path):
    _check_in_chromium(walking[1], tmp_path)


@pytest.mark.slow
def test_car_report_loads_in_headless_chromium(car, tmp_path):
    _check_in_chromium(car[1], tmp_path)


def _check_in_chromium(out: Path, tmp_path: Path) -> None:
    exe = _chromium_or_skip()
    url = out.resolve().as_uri()
    dom = _chromium(exe, tmp_path, url, "--dump-dom")
    assert dom.returncode == 0, dom.stderr[-2000:]
    shot = tmp_path / "shot.png"
    run = _chromium(exe, tmp_path, url, f"--screenshot={shot}", "--window-size=1200,3000")
    assert run.returncode == 0, run.stderr[-2000:]
    for log in (dom.stderr, run.stderr):
        # the page has no script: any console message (an uncaught error logs as INFO:CONSOLE) is a fault
        assert "Uncaught" not in log and ":CONSOLE" not in log and "CONSOLE(" not in log, log[-2000:]
    # the rendered page holds every figure, as data: images, and its tables
    n_img = len(_parse(out).imgs)
    assert dom.stdout.count("<img") == n_img >= 3
    assert dom.stdout.count('src="data:image/png;base64,') == n_img
    assert 'class="worst"' in dom.stdout and "Worst normalized residuals" in dom.stdout
    # the screenshot shows the figures: a substantial non-white area, and coloured lines (the
    # figures' curves; the tables and text are black and grey) on many rows of pixels. Measured:
    # 590 (walking) and 825 (car) coloured rows, 63 with the images' data removed, 0 blank
    pix = mpimg.imread(shot)[..., :3]
    assert pix.shape[:2] == (3000, 1200)
    ink = np.any(pix < 0.9, axis=2)
    assert ink.mean() > 0.02
    rows = np.flatnonzero(ink.any(axis=1))
    assert rows[-1] - rows[0] > 2000  # drawn down the whole page, not one line at the top
    coloured = (pix.max(axis=2) - pix.min(axis=2)) > 0.15
    assert coloured.any(axis=1).sum() > 300


# ------------------------------------------------------------------ figures: legends and units
_UNIT = re.compile(r"\(.+\)\s*$")


def _check_units(fig) -> None:
    """Every axis label has a unit; an axes without an x (y) label shares that axis with
    one whose label has it."""
    axes = [a for a in fig.axes if a.get_visible() and a.axison]
    for ax in axes:
        for xy in ("x", "y"):
            label = getattr(ax, f"get_{xy}label")()
            if label:
                assert _UNIT.search(label), (ax.get_title(), label)
                continue
            siblings = getattr(ax, f"get_shared_{xy}_axes")().get_siblings(ax)
            assert any(_UNIT.search(getattr(s, f"get_{xy}label")()) for s in siblings), (ax.get_title(), xy)


def test_walking_plot_has_one_legend_entry_for_the_stances(walking):
    d, _ = walking
    from bvpnav.readers import read
    from bvpnav.spec import load_spec

    spec = load_spec(d / "rec" / "spec.toml")
    prob = spec.build(read(d / "rec" / "recording.csv", spec.input).imu_data(spec.input))
    assert sum(type(it).__name__ == "ZeroVelocity" for it in prob.items) == 11
    sol = prob.solve()
    fig = plot.solution(sol, items=prob.items)
    for a in "xyz":
        (ax,) = [x for x in fig.axes if x.get_title() == f"velocity {a}"]
        texts = [t.get_text() for t in ax.get_legend().get_texts()]
        stance = [t for t in texts if "stance" in t]
        assert stance == ["stance (hard, 11 items)"], texts
        # the eleven intervals are still all shaded, under one label
        assert sum(p.get_label() == stance[0] for p in ax.patches) == 11
    _check_units(fig)
    plt.close(fig)


@pytest.mark.slow
def test_report_figures_have_units_and_equal_map_axes(car):
    from bvpnav.readers import read
    from bvpnav.spec import load_spec

    d, _ = car
    spec = load_spec(d.parent / d.name / "rec" / "spec.toml")
    data = read(d / "rec" / "recording.csv", spec.input).imu_data(spec.input)
    prob = spec.build(data)
    sol = prob.solve(**{k: v for k, v in spec.solve.items() if k in ("solver", "lam")})
    truth = pd.read_csv(d / "rec" / "truth.csv")[["x", "y", "z"]].to_numpy()
    figs = report.figures(sol, items=prob.items, truth=truth)
    assert {"map", "solution", "residuals", "sensor_errors", "attitude", "loop"} <= set(figs)
    for fig in figs.values():
        _check_units(fig)
    ax = figs["map"].axes[0]
    assert ax.get_aspect() == 1.0
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert {"truth", "estimate", "position fixes"} <= set(labels)
    for fig in figs.values():
        plt.close(fig)


def test_ci_installs_the_browser_before_the_tests():
    run = Path(__file__).resolve().parents[1] / ".ci" / "run"
    lines = run.read_text(encoding="utf-8").strip().splitlines()
    install = [k for k, line in enumerate(lines) if "apt-get install" in line and "chromium" in line]
    assert install and install[0] < len(lines) - 1 and lines[install[0]].startswith("command -v chromium")
    assert any(line.startswith("export CI=") for line in lines[:install[0]])


def test_readme_report_line_runs_as_written(tmp_path, monkeypatch):
    import shlex

    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text(encoding="utf-8")
    (block,) = [b for b in re.findall(r"```bash\n(.*?)\n```", readme, re.S) if "--report" in b]
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "walking", "--out", "walk"]) == 0  # the line above it in README
    for line in block.splitlines():
        args = shlex.split(line.split("#")[0])
        assert args[0] == "bvpnav" and main([*args[1:], "-q"]) == 0
    out = tmp_path / "walk" / "report.html"
    assert _parse(out).tables["worst"][1][2] == "acceleration w"
    assert (tmp_path / "walk" / "traj.csv").is_file()


def test_compare_plot_has_units_on_its_axes():
    from bvpnav.compare import compare_solvers

    t = np.linspace(0.0, 2.0, 21)
    prob = NavigationProblem(ImuData(t=t, acc=np.ones(21)), sigma_a=0.5)
    prob.add(Position(t=[0.0, 2.0], value=[0.0, 2.0], name="ends"))
    fig = plot.comparison(compare_solvers(prob, solvers=["direct"], presets=["default"]))
    _check_units(fig)
    assert [a.get_xlabel() for a in fig.axes] == ["wall time (s)", "forward error (relative)"]
    plt.close(fig)


def test_one_axis_report_with_a_lambda_rule_and_the_load_form(tmp_path):
    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 4.0, 81)
    acc = np.cos(t) + 0.05 * rng.standard_normal(t.size)
    prob = NavigationProblem(ImuData(t=t, acc=acc), residual="load")
    prob.add(Position(t=[0.0, 4.0], value=[0.0, 1.0 - np.cos(4.0)], name="ends"),
             Position(t=np.arange(0.5, 4.0, 0.5), value=1.0 - np.cos(np.arange(0.5, 4.0, 0.5)), sigma=0.01,
                      name="fixes"))
    sol = prob.solve(lam="gcv")
    assert sol.sigma_a is None and sol.curve is not None
    sol.report(tmp_path / "r.html", truth=1.0 - np.cos(t))
    page = _check_self_contained(tmp_path / "r.html", {"solution", "residuals", "lcurve"})
    # the load form has no sigma_a: only the fixes are normalized, each at its time
    worst = page.tables["worst"]
    assert {r[2] for r in worst[1:]} == {"fixes"} and len(worst) == 1 + 7
    assert sorted(float(r[1]) for r in worst[1:]) == [0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5]
    assert "lambda chosen by <b>gcv</b>" in (tmp_path / "r.html").read_text(encoding="utf-8")
