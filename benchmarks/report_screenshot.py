"""The first screen of a study report, as a reader's browser shows it on opening.

Writes a PNG of what a 1280 x 900 browser window shows of ``report.html``
(headless chromium, workbench/render/browser.py) and prints what the
report's own script recorded: whether the answer table and the headline
chart lie wholly on that first screen and how many images failed to load.
Exit code 1 when one of those checks fails (the PNG is written anyway).

    .venv/bin/python benchmarks/report_screenshot.py results/paper_rig/report.html \\
        docs/figures/report33_first_screen_after_paper_rig.png
    .venv/bin/python benchmarks/report_screenshot.py REPORT.html OUT.png --window 1440x900
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from workbench.render.browser import WINDOW, first_screen, screenshot  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("report", type=Path, help="a report.html written by upd study / upd report")
    ap.add_argument("png", type=Path, help="the screenshot to write")
    ap.add_argument(
        "--window", default=f"{WINDOW[0]}x{WINDOW[1]}", help="browser window, px (WIDTHxHEIGHT)"
    )
    args = ap.parse_args(argv)
    w, h = (int(v) for v in args.window.lower().split("x"))
    png = screenshot(args.report, args.png, window=(w, h))
    fs = first_screen(args.report, window=(w, h))
    checks = {
        "page loaded": fs.loaded,
        "answer table on the first screen": fs.on_screen("answer-table"),
        "headline chart on the first screen": fs.on_screen("headline-chart"),
        f"every image decoded ({fs.images} images)": fs.loaded and fs.broken_images == 0,
    }
    print(f"wrote {png} ({w} x {h} window)")
    for what, ok in checks.items():
        print(f"  {'ok  ' if ok else 'FAIL'} {what}")
    return 0 if all(checks.values()) else 1


if __name__ == "__main__":
    raise SystemExit(main())
