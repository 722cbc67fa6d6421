"""A report as a reader's browser shows it: headless chromium, screenshot and layout.

Two uses: the test that opens a report in a real browser and checks its
first screen (tests/test_report_browser.py), and the script that writes
the first-screen screenshot of any report (benchmarks/report_screenshot.py).
Both run Debian's ``chromium`` (installed by scripts/setup.sh) headless,
with a fresh profile and no network, sync or component updates.

:func:`first_screen` loads a page and returns what the report's own
script recorded once the page had loaded (render/report.py): the window
size, the number of images and of images that failed to decode, and the
rectangle of every element marked ``data-first-screen`` (the answer, its
table, the headline chart).
"""

from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import InputError

FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
)
WINDOW = (1280, 900)  # a laptop's browser window, px


def chromium() -> str:
    """The chromium executable (an InputError naming scripts/setup.sh when missing)."""
    for name in ("chromium", "chromium-browser"):
        exe = shutil.which(name)
        if exe:
            return exe
    raise InputError("chromium", "not found", "Debian's chromium (scripts/setup.sh installs it)")


def _run(args: list[str], url: str, timeout: float) -> subprocess.CompletedProcess:
    with tempfile.TemporaryDirectory(prefix="upd-chromium-") as profile:
        return subprocess.run(
            [chromium(), *FLAGS, f"--user-data-dir={profile}", *args, url],
            capture_output=True,
            text=True,
            timeout=timeout,
        )


def _url(html: str | Path) -> str:
    p = Path(html)
    if not p.is_file():
        raise InputError("report", str(p), "an existing report.html")
    return p.resolve().as_uri()


def screenshot(
    html: str | Path,
    png: str | Path,
    *,
    window: tuple[int, int] = WINDOW,
    budget_ms: int = 10000,
    timeout: float = 180.0,
) -> Path:
    """Write the first screen of ``html`` (what a ``window`` shows on opening) to ``png``."""
    png = Path(png).resolve()
    png.parent.mkdir(parents=True, exist_ok=True)
    if png.exists():
        png.unlink()
    r = _run(
        [
            f"--window-size={window[0]},{window[1]}",
            f"--virtual-time-budget={budget_ms}",
            f"--screenshot={png}",
        ],
        _url(html),
        timeout,
    )
    if not png.is_file():
        raise InputError("screenshot", str(png), "a PNG written by chromium", r.stderr[-400:])
    return png


@dataclass
class FirstScreen:
    """What the report's script recorded in a browser (see the module docstring)."""

    loaded: bool
    viewport: tuple[int, int]
    images: int
    broken_images: int
    rects: dict[str, tuple[int, int, int, int]] = field(default_factory=dict)
    dom: str = ""

    def on_screen(self, name: str) -> bool:
        """True when element ``name`` lies wholly inside the first screen."""
        r = self.rects.get(name)
        if r is None:
            return False
        left, top, right, bottom = r
        w, h = self.viewport
        return left >= 0 and top >= 0 and right <= w and bottom <= h and bottom > top


def first_screen(
    html: str | Path,
    *,
    window: tuple[int, int] = WINDOW,
    budget_ms: int = 10000,
    timeout: float = 180.0,
    tries: int = 3,
) -> FirstScreen:
    """Open ``html`` in headless chromium and read what its script recorded.

    A saturated machine can make chromium dump the page before the load
    event; the page is then loaded again (at most ``tries`` times), and the
    last attempt is returned as not ``loaded``.
    """
    url = _url(html)
    out = FirstScreen(False, (0, 0), 0, 0)
    for _ in range(tries):
        r = _run(
            [
                f"--window-size={window[0]},{window[1]}",
                f"--virtual-time-budget={budget_ms}",
                "--dump-dom",
            ],
            url,
            timeout,
        )
        out = parse_dom(r.stdout)
        if out.loaded:
            return out
    return out


def parse_dom(dom: str) -> FirstScreen:
    """The :class:`FirstScreen` record from a dumped DOM."""
    body = re.search(r"<body([^>]*)>", dom)
    attrs = dict(re.findall(r'([\w-]+)="([^"]*)"', body.group(1))) if body else {}
    vp = attrs.get("data-viewport", "0x0").split("x")
    rects = {}
    for m in re.finditer(r"<[^>]*data-first-screen=\"([^\"]+)\"[^>]*>", dom):
        rect = re.search(r'data-rect="([-\d,]+)"', m.group(0))
        if rect:
            rects[m.group(1)] = tuple(int(v) for v in rect.group(1).split(","))
    return FirstScreen(
        loaded=attrs.get("data-laid-out") == "yes",
        viewport=(int(vp[0] or 0), int(vp[1] or 0)),
        images=int(attrs.get("data-images", 0)),
        broken_images=int(attrs.get("data-broken-images", 0)),
        rects=rects,
        dom=dom,
    )
