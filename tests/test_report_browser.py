"""A comparison report in a real browser (headless chromium): the first screen is the answer.

The report's own script records, once the page has loaded, where the
answer table and the headline chart lie and how many images failed to
decode (workbench/render/report.py); workbench/render/browser.py opens the
page in Debian's chromium (scripts/setup.sh installs it) and reads that
record back from the DOM. The window is a laptop's, 1280 x 900: its page
area is what the test calls the first screen.
"""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from tests.synthetic import synthetic_study
from workbench.render import sections
from workbench.render.browser import first_screen, screenshot
from workbench.render.report import write_report
from workbench.render.section_builder import _Builder


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    """The first sections of a comparison report (the answer, then the cases) of a
    synthetic three-damper study, written as a study writes them."""
    root = tmp_path_factory.mktemp("report")
    r = synthetic_study()
    for c in r.cases:  # a few points Hill could not decide, as real curves have
        c.branch.stability[5:8] = -1
    b = _Builder(r, root)
    b.fig_dir.mkdir(parents=True)
    b.tab_dir.mkdir(parents=True)
    sections._answer(b, "")
    sections._cases(b)
    b.run()
    manifest = {
        "title": "Study 'synthetic'",
        "subtitle": "comparison study,",
        "created": "2026-01-01 00:00:00",
        "sections": [s.as_dict() for s in b.sections],
    }
    (root / "manifest.json").write_text(json.dumps(manifest))
    return write_report(root)


def test_the_first_screen_holds_the_answer_and_the_headline_chart(report, tmp_path):
    # scripts/setup.sh installs Debian's chromium: its absence is a broken setup, not a skip
    assert shutil.which("chromium"), "chromium missing: run scripts/setup.sh"
    fs = first_screen(report)
    assert fs.loaded, "chromium never ran the report's load handler"
    w, h = fs.viewport
    assert w == 1280 and 600 <= h <= 900, fs.viewport  # a laptop window's page area
    assert fs.images == 1 and fs.broken_images == 0
    assert fs.on_screen("answer-table"), (fs.rects, fs.viewport)
    assert fs.on_screen("headline-chart"), (fs.rects, fs.viewport)
    # the chart beside the table, not below it
    table, chart = fs.rects["answer-table"], fs.rects["headline-chart"]
    assert chart[0] >= table[2] - 1
    # what the reader reads there: the ranking, the ratio, the unknown verdicts
    dom = fs.dom
    assert "vibrates least" in dom and "times as much" in dom
    assert "unknown" in dom[: dom.index('data-first-screen="headline-chart"')]

    # and the pixels: the chart is painted where the page says (the cone's blue is there)
    import matplotlib.image as mpimg

    png = screenshot(report, tmp_path / "first_screen.png")
    img = np.asarray(mpimg.imread(str(png)))[..., :3]
    left, top, right, bottom = chart
    area = img[top:bottom, left:right]
    blue = np.abs(area - np.array([0x00, 0x72, 0xB2]) / 255.0).max(axis=-1) < 0.08
    assert int(blue.sum()) > 200, int(blue.sum())


def test_an_image_that_does_not_decode_is_counted(report, tmp_path):
    """A check of the check: a figure whose bytes are not a PNG is reported broken."""
    root = report.parent
    bad = tmp_path / "bad"
    shutil.copytree(root, bad)
    fig = json.loads((bad / "manifest.json").read_text())["sections"][0]["figures"][0]
    (bad / fig["path"]).write_bytes(b"\x89PNG\r\n\x1a\n not an image")
    fs = first_screen(write_report(bad))
    assert fs.loaded and fs.images == 1 and fs.broken_images == 1
