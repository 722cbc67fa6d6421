"""Shared test set-up: off-screen rendering, one thread per process, CLI runner."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

# Hypothesis' too_slow health check times the drawing of examples: on 2 shared cores under
# pytest-xdist a draw was once held 1.7 s by the machine (not by the strategy) and failed a
# property test that had nothing wrong. Timing is for the benchmarks; the properties and
# their random examples stay as they are.
settings.register_profile("shared-cores", suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("shared-cores")

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("UPD_NO_PROGRESS", "1")
# studies and screens in tests run their FE stage in the test's own process (pytest-xdist
# already fills the cores); the worker pool has its own tests (test_prefetch.py)
os.environ.setdefault("UPD_WORKERS", "1")
os.environ.setdefault("MPLBACKEND", "Agg")

ROOT = Path(__file__).resolve().parents[1]


class CliResult:
    def __init__(self, code: int, out: str, err: str):
        self.code, self.out, self.err = code, out, err

    @property
    def json(self):
        return json.loads(self.out)

    def __repr__(self) -> str:
        return f"CliResult(code={self.code}, err={self.err[-2000:]!r})"


def run_upd(*args: str, timeout: float = 900, cwd: Path | None = None) -> CliResult:
    """Run ``upd`` as a separate process (as a user would) and capture it."""
    cmd = [sys.executable, "-m", "workbench.cli.main", *map(str, args)]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=cwd or ROOT)
    return CliResult(p.returncode, p.stdout, p.stderr)


@pytest.fixture
def upd():
    return run_upd


TINY = ROOT / "tests" / "studies" / "tiny.toml"


@pytest.fixture(scope="session")
def tiny_resumed(tmp_path_factory):
    """The tiny study, SIGKILLed during its FE stage, run again and SIGKILLed after its
    first case, then resumed: (folder, JSON summary of the last run).

    Shared by the resume test and the study-state tests (xdist group "resume"), which
    work on copies of the folder so that they reuse its meshes and reduced models.
    """
    import signal
    import time

    out = tmp_path_factory.mktemp("tiny") / "tiny"
    cmd = [sys.executable, "-m", "workbench.cli.main", "study", str(TINY), "--out", str(out)]
    log = out.parent / "killed.err"

    def kill_when(ready) -> None:
        with log.open("w") as fh:
            p = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=fh)
        t0 = time.time()
        while not ready():
            assert p.poll() is None and time.time() - t0 < 600, log.read_text()[-2000:]
            time.sleep(0.05)
        p.send_signal(signal.SIGKILL)  # no chance to clean up: atomic writes must do
        p.wait()

    # 1. during the FE stage (the reduction of the rig has started)
    kill_when(lambda: "building the craig-bampton model" in log.read_text())
    # 2. during the curves (the first case is finished)
    cases = out / "cache" / "cases"
    kill_when(lambda: cases.is_dir() and any(cases.glob("*.h5")))
    r = run_upd("study", TINY, "--out", out, "--json")
    assert r.code == 0, r
    assert "removing the stale lock" in r.err  # the killed runs' lock does not block
    return out, r.json


def image_std(png: str | Path) -> float:
    """Pixel standard deviation of an image (0 for a blank one)."""
    import matplotlib.image as mpimg
    import numpy as np

    img = mpimg.imread(str(png))
    return float(np.asarray(img, dtype=float)[..., :3].std())


def assert_nonblank(png: str | Path, floor: float = 0.02) -> None:
    """The image exists and its pixels vary (values in 0..1) by more than ``floor``."""
    p = Path(png)
    assert p.is_file(), f"missing figure {p}"
    s = image_std(p)
    assert s > floor, f"{p.name} looks blank (pixel std {s:.4f} <= {floor})"
