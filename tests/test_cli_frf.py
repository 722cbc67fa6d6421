"""``upd frf`` on the documented examples, as a user runs it, and its one-line errors."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from conftest import assert_nonblank

EXAMPLES = Path(__file__).resolve().parents[1] / "studies" / "examples"


@pytest.mark.parametrize("name, n_levels", [("sdof_jenkins", 4), ("two_dof_contact", 4)])
def test_examples_run_and_report(upd, tmp_path, name, n_levels):
    r = upd("frf", EXAMPLES / f"{name}.toml", "--json", "--out", tmp_path)
    assert r.code == 0, r
    s = r.json
    assert s["length_unit"] == "m" and len(s["curves"]) == n_levels
    for c in s["curves"]:
        for key in (
            "peak_frequency_hz",
            "peak_amplitude",
            "h1_amplitude",
            "n_points",
            "wall_s",
            "energy_residual_max",
        ):
            assert c[key] is not None, key
        assert c["completed"] and not c["failed"]
        assert c["energy_residual_max"] < 1e-6
        assert s["band_hz"][0] <= c["peak_frequency_hz"] <= s["band_hz"][1]
        assert c["peak_amplitude_mm"] == pytest.approx(1e3 * c["peak_amplitude"])
        for f in c["files"].values():
            assert Path(f).is_file()
        if "png" in c["files"]:
            assert_nonblank(c["files"]["png"])
    # friction damping sets in: the peak response per newton drops from the first level
    # (stuck) to the second (stick-slip); in gross slip it rises again towards the free peak
    per_n = [c["peak_amplitude"] / c["level"] for c in s["curves"]]
    assert per_n[1] < 0.8 * per_n[0]
    assert_nonblank(s["figure"])
    assert (tmp_path / "summary.json").is_file()


def test_sdof_levels_show_the_friction_physics(upd, tmp_path):
    """Below slip the peak is the stuck one (141 Hz); far above slip it is the free one (100 Hz)."""
    r = upd(
        "frf",
        EXAMPLES / "sdof_jenkins.toml",
        "--json",
        "--out",
        tmp_path,
        "--levels",
        "0.05,4",
        "--harmonics",
        "0,1,2,3",
        "--no-stability",
    )
    assert r.code == 0, r
    low, high = r.json["curves"]
    assert abs(low["peak_frequency_hz"] - 141.42) < 0.5
    assert abs(high["peak_frequency_hz"] - 100.0) < 0.5


@pytest.mark.parametrize(
    "edit, words",
    [
        (('stiffness = "K"', 'stifness = "K"'), ["model.stifness", "did you mean 'stiffness'"]),
        (
            ("dofs = [0]\namplitudes_n", "dofs = [5]\namplitudes_n"),
            ["excitation.dofs[0] = 5", "0 <= i < 1"],
        ),
        (
            ("start_hz = 80.0", "start_hz = -80.0"),
            ["band.start_hz = -80.0", "0 Hz < band.start_hz"],
        ),
    ],
)
def test_bad_model_files_give_one_line(upd, tmp_path, edit, words):
    for p in EXAMPLES.glob("sdof_jenkins.*"):
        shutil.copy(p, tmp_path / p.name)
    toml = tmp_path / "sdof_jenkins.toml"
    toml.write_text(toml.read_text().replace(*edit, 1))
    r = upd("frf", toml, "--out", tmp_path / "out")
    assert r.code == 2, r
    lines = [ln for ln in r.err.strip().splitlines() if ln.startswith("upd frf: error")]
    assert len(lines) == 1 and "Traceback" not in r.err
    for w in words:
        assert w in lines[0]


def test_bad_command_line_values(upd, tmp_path):
    r = upd("frf", EXAMPLES / "sdof_jenkins.toml", "--band", "100,90", "--out", tmp_path)
    assert r.code == 2 and "band.end_hz = 90.0" in r.err
    r = upd("frf", EXAMPLES / "sdof_jenkins.toml", "--levels", "a,b", "--out", tmp_path)
    assert r.code == 2 and "--levels" in r.err
    for flag, val in (("--nt", "0"), ("--nt", "64,128"), ("--levels", ","), ("--harmonics", "")):
        r = upd("frf", EXAMPLES / "sdof_jenkins.toml", flag, val, "--out", tmp_path)
        assert r.code == 2 and flag in r.err, (flag, val, r)


def test_dimensionless_model_reports_rad_s_and_no_mm(upd, tmp_path):
    """length_unit = "1": frequencies also in rad/s, no *_mm keys; the three peaks
    (max |x|, harmonic 1, RMS) each have their own frequency; --nt is used."""
    for p in EXAMPLES.glob("sdof_jenkins.*"):
        shutil.copy(p, tmp_path / p.name)
    toml = tmp_path / "sdof_jenkins.toml"
    toml.write_text(toml.read_text().replace('length_unit = "m"', 'length_unit = "1"', 1))
    r = upd(
        "frf", toml, "--json", "--out", tmp_path / "o", "--levels", "1", "--nt", "64",
        "--harmonics", "0,1,2,3", "--no-stability",
    )  # fmt: skip
    assert r.code == 0, r
    s = r.json
    assert s["nt"] == 64
    (c,) = s["curves"]
    assert not [k for k in c if k.endswith("_mm")]
    for key in ("peak_frequency", "h1_peak_frequency", "rms_peak_frequency"):
        assert c[f"{key}_rad_s"] == pytest.approx(2 * 3.141592653589793 * c[f"{key}_hz"])
    assert c["peak_reached"] and c["h1_peak_reached"]
    assert c["peak_stability"] == "unknown" and c["n_unstable"] == 0
    assert c["rms_amplitude"] < c["peak_amplitude"]
