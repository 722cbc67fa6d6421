"""``upd analytic`` as a user runs it: JSON summary, figures and CSVs, one-line errors."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from conftest import assert_nonblank, run_upd

from workbench.analytic import ConeDesign, paper_kinematics, rigid_body_kinematics

EXPECTED_FIGURES = (
    "inclination_vs_cone_angle",
    "slip_along_damper",
    "max_slip_vs_cone_angle",
    "paper_vs_3d",
    "contact_line_slip_3d",
)


def test_json_summary_has_the_paper_and_3d_values():
    r = run_upd(
        "analytic", "--beta", "45", "--cone-angle", "10", "--r1", "10", "--length", "40", "--json"
    )
    assert r.code == 0, r
    s = r.json  # stdout is pure JSON (logs go to stderr)
    for key in (
        "gamma_deg",
        "alpha1_deg",
        "max_slip_ratio",
        "max_slip_ratio_3d",
        "max_transverse_slip_ratio_3d",
        "max_longitudinal_slip_ratio_3d",
    ):
        assert isinstance(s[key], float), key
    d = ConeDesign(45, 10, 10, 40)
    # the CLI reports exactly what the library computes (JSON keeps full precision)
    assert s["gamma_deg"] == paper_kinematics(d).gamma_deg
    assert s["max_slip_ratio"] == paper_kinematics(d).max_slip_ratio
    assert s["max_slip_ratio_3d"] == pytest.approx(
        rigid_body_kinematics(d).max_slip_ratio, rel=1e-12
    )
    assert s["gamma_deg"] == pytest.approx(14.2159, abs=1e-4)
    assert s["max_slip_ratio"] == pytest.approx(0.352, abs=5e-4)
    assert s["inputs"] == {
        "beta_deg": 45.0,
        "cone_angle_deg": 10.0,
        "r1_mm": 10.0,
        "length_mm": 40.0,
    }
    assert "files" not in s  # no --out: summary only


def test_human_summary_without_json():
    r = run_upd("analytic", "--cone-angle", "15")
    assert r.code == 0, r
    assert "max_slip_ratio:" in r.out and "gamma_deg:" in r.out
    with pytest.raises(json.JSONDecodeError):
        json.loads(r.out)


def test_help_lists_the_options():
    r = run_upd("analytic", "--help")
    assert r.code == 0
    for opt in ("--beta", "--cone-angle", "--r1", "--length", "--json", "--out"):
        assert opt in r.out


def test_out_writes_nonblank_figures_and_csvs(tmp_path):
    out = tmp_path / "analytic"
    r = run_upd("analytic", "--out", str(out), "--json", "--step", "0.5")
    assert r.code == 0, r
    s = r.json
    files = {p for p in s["files"]}
    for stem in EXPECTED_FIGURES:
        png, csv_path = out / f"{stem}.png", out / f"{stem}.csv"
        assert str(png) in files and str(csv_path) in files
        assert_nonblank(png)
        with open(csv_path, newline="") as fh:
            rows = list(csv.reader(fh))
        assert len(rows) > 10 and len(set(map(len, rows))) == 1
        assert all(
            any(u in h for u in ("_deg", "_mm", "ratio", "side", "family", "over", "difference"))
            for h in rows[0]
        ), rows[0]
    assert json.loads((out / "summary.json").read_text())["max_slip_ratio"] == s["max_slip_ratio"]
    # the Fig. 6 CSV holds the paper's R1 = 5 mm maximum (about 0.7 at beta 45)
    data = np.genfromtxt(
        out / "max_slip_vs_cone_angle.csv", delimiter=",", names=True, dtype=None, encoding="utf-8"
    )
    r1_5 = data[(data["family"] == "r1") & np.isclose(data["r1_mm"], 5.0)]
    assert r1_5["max_slip_ratio_paper"].max() == pytest.approx(0.69, abs=0.01)


@pytest.mark.parametrize(
    "args, param, fragment",
    [
        (("--cone-angle", "45"), "cone_angle_deg = 45.0", "vertical"),
        (("--cone-angle", "60"), "cone_angle_deg = 60.0", "cone_angle_deg < beta_deg = 45 deg"),
        (("--r1", "-5"), "r1_mm = -5.0", "0.001 mm <= r1_mm"),
        (("--beta", "90"), "beta_deg = 90.0", "beta_deg <= 89 deg"),
        (("--beta", "abc"), "beta_deg = 'abc'", "not a number"),
        (("--length", "forty"), "length_mm = 'forty'", "not a number"),
        (("--points", "2"), "points = 2", "3 <= points"),
    ],
)
def test_bad_input_one_line_exit_2(args, param, fragment):
    r = run_upd("analytic", *args, "--json")
    assert r.code == 2, r
    assert r.out == ""  # nothing on stdout
    lines = r.err.strip().splitlines()
    assert len(lines) == 1, r.err
    assert lines[0].startswith("upd analytic: error: ")
    assert param in lines[0] and fragment in lines[0]
    assert "Traceback" not in r.err
