"""The Python API: examples/notebook_api.py runs as written, and ``import workbench`` stays light.

The example builds a coarse rig (14 mm, 4 modes, rigid damper: about 30 s
on one core the first time) and solves two forces; the test checks what a
notebook user relies on: Figure objects with labelled axes, files only
where asked, the process's matplotlib backend and style untouched, every
input shown with its value and source, and the physics of the two curves
(friction lowers the receptance and dissipates more at the higher force).
"""

from __future__ import annotations

import runpy
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import ROOT, assert_nonblank
from workbench.errors import InputError

EXAMPLE = ROOT / "examples" / "notebook_api.py"


@pytest.fixture(scope="module")
def example(tmp_path_factory):
    import matplotlib

    out = tmp_path_factory.mktemp("nb")
    backend, rc = matplotlib.get_backend(), dict(matplotlib.rcParams)
    argv = sys.argv
    sys.argv = [str(EXAMPLE), str(out)]
    try:
        g = runpy.run_path(str(EXAMPLE), run_name="__main__")
    finally:
        sys.argv = argv
    return out, g, backend, rc


def test_example_runs_and_leaves_matplotlib_alone(example, capsys):
    import matplotlib
    from matplotlib.figure import Figure

    out, g, backend, rc = example
    assert matplotlib.get_backend() == backend
    assert dict(matplotlib.rcParams) == rc  # the workbench style is applied per figure only
    fig = g["fig"]
    assert isinstance(fig, Figure)
    ax = fig.axes[0]
    assert "mm/N" in ax.get_ylabel() and "Hz" in ax.get_xlabel()
    for name in ("receptance.png", "status.png", "sdof_frf.png"):
        assert_nonblank(out / name)
    assert sorted(p.name for p in out.glob("*.png")) == [
        "receptance.png",
        "sdof_frf.png",
        "status.png",
    ]


def test_example_curves_and_inputs(example):
    out, g, *_ = example
    m, curves = g["m"], g["curves"]
    rows = {r["option"]: r for r in m.inputs()}
    assert all(r["value"] is not None for r in rows.values())
    assert rows["mesh-size"]["value"] == 14.0 and rows["mesh-size"]["source"] == "python API"
    assert rows["mu"]["value"] == 0.5 and "contact.toml" in rows["mu"]["source"]
    assert rows["cf"]["unit"] == "N" and "kt-face" not in rows  # the cone has lines, no faces
    low, high = curves
    assert low.branch.completed and high.branch.completed
    r_low = low.receptance_mm_per_n[low.peak_index]
    r_high = high.receptance_mm_per_n[high.peak_index]
    assert r_high < 0.5 * r_low  # friction damping: the receptance peak drops with the force
    assert high.energy_mj[high.peak_index].sum() > 100 * low.energy_mj[low.peak_index].sum()
    assert np.all(np.diff(high.freq_hz[:5]) > 0)


def test_frf_refuses_model_options_and_unknown_names(example):
    import workbench as wb

    _, g, *_ = example
    with pytest.raises(InputError, match="wb.model"):
        wb.frf(g["m"], force_n=1.0, mu=0.3)
    with pytest.raises(InputError, match="harmonic"):
        wb.frf(g["m"], force_n=1.0, harmonic=[0, 1])
    with pytest.raises(InputError, match="force_n"):
        wb.frf(g["m"], force_n=-1.0)


def test_import_workbench_is_light():
    code = (
        "import sys, workbench as wb; assert callable(wb.model); "
        "print(sorted(m for m in ('dolfinx', 'matplotlib', 'pyvista', 'gmsh') "
        "if m in sys.modules))"
    )
    r = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=Path(__file__).parent
    )
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "[]"
