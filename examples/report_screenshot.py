"""The screenshot of a quality report shown in the docs (``docs/_static/figures/report.png``).

A one-minute simulated car drive (:func:`bvpnav.scenarios.car_drive`, 10 Hz, tactical
grade, 1 Hz GNSS fixes, the fix at t = 30 s moved 30 m east) solved with the grade's
error model and standard deviations; its report (:meth:`bvpnav.Solution.report`) opened in
headless Chromium (Debian's ``/usr/bin/chromium``) and the top of the page (summary, map
view with the moved fix marked, position and velocity) captured, then scaled to 760
pixels wide so the PNG stays under 300 kB.

Run: ``python examples/report_screenshot.py [--out docs/_static/figures/report.png]
[--html report.html]``.
"""

from __future__ import annotations

import argparse
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from bvpnav import NavigationProblem
from bvpnav.constraints import Position
from bvpnav.io import atomic_write_bytes
from bvpnav.scenarios import car_drive
from bvpnav.sensors import grade

ROOT = Path(__file__).resolve().parents[1]
#: Width of the browser window and of the saved PNG, pixels.
WINDOW, WIDTH = (1100, 1900), 760
#: Largest PNG kept in the docs, bytes.
MAX_BYTES = 300_000


def solve_drive():
    """The drive with its moved fix, solved with standard deviations: (solution, truth)."""
    drive = car_drive(60.0, 10.0, seed=1)
    g = grade("tactical")
    fixes = drive.fix_position.copy()
    fixes[30, 0] += 30.0
    prob = NavigationProblem(drive.data(), error_model=g.error_model(30.0),
                             sigma_a=g.sigma_a(drive.rate, 30.0))
    prob.add(Position(t=drive.fix_t, value=fixes, sigma=np.tile(drive.fix_sigma, (drive.fix_t.size, 1)),
                      name="gnss"))
    sol = prob.solve(solver="direct", lam=1.0, uncertainty=True, attitude={"progress": False})
    return sol, prob, drive.position


def screenshot(html: Path, png: Path) -> None:
    """Chromium's headless screenshot of ``html`` at :data:`WINDOW`."""
    with tempfile.TemporaryDirectory() as profile:
        subprocess.run(["/usr/bin/chromium", "--headless", "--no-sandbox", "--disable-gpu",
                        "--disable-background-networking", "--disable-component-update", "--disable-sync",
                        "--no-first-run", f"--user-data-dir={profile}", f"--screenshot={png}",
                        f"--window-size={WINDOW[0]},{WINDOW[1]}", html.resolve().as_uri()],
                       check=True, capture_output=True, timeout=180)


def main(argv: list[str] | None = None) -> Path:
    from PIL import Image

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(ROOT / "docs" / "_static" / "figures" / "report.png"))
    ap.add_argument("--html", help="also keep the report there")
    args = ap.parse_args(argv)
    sol, prob, truth = solve_drive()
    with tempfile.TemporaryDirectory() as tmp:
        html = Path(args.html) if args.html else Path(tmp) / "report.html"
        sol.report(html, items=prob.items, truth=truth, title="bvpnav report: a one-minute car drive")
        raw = Path(tmp) / "shot.png"
        screenshot(html, raw)
        img = Image.open(raw).convert("RGB")
        img = img.resize((WIDTH, round(img.height * WIDTH / img.width)), Image.LANCZOS)
        img = img.quantize(colors=128, method=Image.Quantize.MEDIANCUT)
        buf = Path(tmp) / "small.png"
        img.save(buf, format="PNG", optimize=True)
        data = buf.read_bytes()
    if len(data) > MAX_BYTES:
        raise SystemExit(f"{len(data)} bytes: over the {MAX_BYTES} kept in the docs")
    atomic_write_bytes(args.out, data)
    print(f"wrote {args.out}: {img.width} x {img.height} pixels, {len(data) / 1000:.0f} kB")
    return Path(args.out)


if __name__ == "__main__":
    main()
