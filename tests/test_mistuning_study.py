"""The mistuning study kind (issue 32, item 3) on a tiny disk: 6 blades, the coarse
paper-like mesh, the cylinder, EO 1, 4 Sobol patterns of 2 % frequency scatter, harmonics
[0, 1], one force (10 N, at which the cylinder barely slips on this disk).

The study is killed (SIGKILL) after its first tasks and run again through the CLI: it
resumes from its cache. The tuned disk's blades all peak alike; in the linear
configurations no pattern's amplification factor exceeds Whitehead's bound; at 10 N the
friction peaks are the stuck ones (the damper barely slips); a study whose patterns are all
zero (standard deviation 0) is the tuned disk: it computes nothing and every amplification
factor is exactly 1. Bad input is refused in one line naming the option."""

from __future__ import annotations

import csv
import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from workbench.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
STUDY = """
name = "mist_tiny"
kind = "mistuning"
dampers = ["cylinder"]
forces = [10.0]
geometry = "{geometry}"
mesh-size = 25.0
contact-mesh-size = 8.0
damper-mesh-size = 10.0
contact-points = 3
harmonics = [0, 1]
damping = 0.005
n-blades = 6
eos = [1]
sector-modes = 4
damper-modes = 3
mistuning-std = 2.0
mistuning-patterns = 4
mistuning-sampling = "sobol"
mistuning-seed = 2026
"""
N_TASKS = 3 * 5  # (no damper, stuck, 10 N) x (4 patterns and the tuned disk)


def _write(tmp: Path, **change: str) -> Path:
    text = STUDY.format(geometry=ROOT / "geometry" / "paper_rig.toml")
    for k, v in change.items():
        text = "\n".join(
            f"{k} = {v}" if line.startswith(f"{k} =") else line for line in text.splitlines()
        )
    path = tmp / "study.toml"
    path.write_text(text)
    return path


def _spec(tmp: Path, **change: str):
    from workbench.studies.engine.spec import load_study

    return load_study(_write(tmp, **change))


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """Killed after its first two tasks, resumed through the CLI, then run once more."""
    from conftest import run_upd

    from workbench.studies.kinds import get

    tmp = tmp_path_factory.mktemp("mist")
    path = _write(tmp)
    out = tmp / "out"
    cache = out / "cache" / "mistuning"
    cmd = [sys.executable, "-m", "workbench.cli.main", "study", str(path), "--out", str(out)]
    with (tmp / "killed.err").open("w") as fh:
        p = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=fh)
    t0 = time.time()
    while not (cache.is_dir() and len(list(cache.glob("*.json"))) >= 2):
        assert p.poll() is None and time.time() - t0 < 300, (tmp / "killed.err").read_text()
        time.sleep(0.05)
    p.send_signal(signal.SIGKILL)  # no chance to clean up: each task file is whole or absent
    p.wait()
    done = len(list(cache.glob("*.json")))
    r = run_upd("study", path, "--out", out, "--json")
    assert r.code == 0, r.err
    again = get("mistuning").run(_spec(tmp), out, False)
    return tmp, out, done, r.json, again


def test_a_killed_study_resumes_and_a_second_run_reuses_every_task(study):
    _, _, done, first, again = study
    assert 2 <= done < N_TASKS
    assert first["n_tasks"] == N_TASKS and first["n_reused"] == done
    assert first["n_computed"] == N_TASKS - done
    assert again["n_computed"] == 0 and again["n_reused"] == N_TASKS
    assert again["stats"] == first["stats"]


def test_tables_results_and_figures_are_written_with_units(study):
    import h5py

    _, out, _, first, _ = study
    rows = list(csv.DictReader(open(out / "tables" / "mistuning_peaks.csv")))
    assert len(rows) == N_TASKS * 6  # every blade of every pattern and configuration
    afs = list(csv.DictReader(open(out / "tables" / "mistuning_af.csv")))
    assert len(afs) == 3 * 4
    with h5py.File(out / "mistuning.h5") as h:
        assert h["peak_m_per_n"].shape == (1, 1, 3, 4, 6)
        assert h["peak_m_per_n"].attrs["unit"] == "m/N"
        assert h["peak_hz"].attrs["unit"] == "Hz"
        assert h["forces_n"].attrs["unit"] == "N"
        assert json.loads(h.attrs["configs"]) == ["none", "stuck", "friction_10N"]
        # the AF is the worst blade's peak over the tuned disk's worst blade's
        worst = h["peak_m_per_n"][0, 0].max(axis=2)  # [config, pattern]
        tuned = h["tuned_peak_m_per_n"][0, 0].max(axis=1)  # [config]
        np.testing.assert_array_equal(h["af"][0, 0], worst / tuned[:, None])
    for name in ("af_hist", "af_compare", "worst_response"):
        assert (out / "figures" / f"mistuning_{name}.png").stat().st_size > 10_000
    html = (out / "report.html").read_text()
    for name in ("n-blades", "eos", "sector-modes", "mistuning-std", "mistuning-patterns"):
        assert name in html  # the Inputs table: the bladed-disk options the study reads too
    (a,) = first["answer"]
    assert a["best_damper"] == "cylinder" and a["force_n"] == 10.0


def test_tuned_blades_peak_alike_and_friction_at_10_n_is_the_stuck_disk(study):
    """A tuned disk under an engine order is a travelling wave: every blade's peak is the
    same (the AFT samples a multiple of N). At 10 N the cylinder barely slips: the friction
    peaks are the stuck linear ones (tuned: 1e-5; each pattern's blades: 0.2 %, the
    continuation's sampling of a mistuned top)."""
    import h5py

    _, out, _, _, _ = study
    with h5py.File(out / "mistuning.h5") as h:
        tuned = h["tuned_peak_m_per_n"][0, 0]  # [config, blade]
        peaks = h["peak_m_per_n"][0, 0]  # [config, pattern, blade]
    assert np.all(np.abs(tuned / tuned[:, :1] - 1) < 1e-9)
    none, stuck, fric = tuned[:, 0]
    assert none > stuck  # the damper stiffens the platforms: a lower, higher-frequency peak
    assert abs(fric / stuck - 1) < 1e-5
    assert np.abs(peaks[2] / peaks[1] - 1).max() < 2e-3


def test_linear_amplification_stays_below_whiteheads_bound(study):
    from workbench.pipeline.mistuning import whitehead_bound

    _, _, _, first, _ = study
    bound = whitehead_bound(6)
    assert first["whitehead_bound"] == bound
    lin = [s for s in first["stats"] if s["config"] in ("none", "stuck")]
    assert len(lin) == 2
    for s in lin:
        assert 1.0 < s["af_max"] <= bound and s["n_above_whitehead"] == 0
        assert s["af_p95"] <= s["af_max"]


def test_patterns_of_zeros_are_the_tuned_disk_with_af_exactly_one(study):
    """Standard deviation 0: every pattern's key is the tuned disk's, already cached."""
    from workbench.studies.kinds import get

    tmp, out, _, _, _ = study
    z = tmp / "zero"
    z.mkdir()
    s = get("mistuning").run(_spec(z, **{"mistuning-std": "0.0"}), out, False)
    assert s["n_computed"] == 0
    for row in s["stats"]:
        assert row["af_max"] == 1.0 and row["af_mean"] == 1.0 and row["af_p95"] == 1.0


def test_patterns_map_normal_deviates_to_stiffness():
    from scipy.stats import norm

    from workbench.studies.kinds.mistuning.patterns import sample_patterns

    p = sample_patterns(16, 6, 2.0, "sobol", 7)
    np.testing.assert_array_equal(p.delta, (1 + p.df) ** 2 - 1)
    np.testing.assert_array_equal(p.df, 0.02 * p.z)
    # a larger Sobol design keeps the patterns of a smaller one
    np.testing.assert_array_equal(sample_patterns(40, 6, 2.0, "sobol", 7).z[:16], p.z)
    # a Latin hypercube puts one point in each of n strata per blade
    q = sample_patterns(20, 6, 3.0, "lhs", 7)
    strata = np.floor(norm.cdf(q.z) * 20).astype(int)
    for j in range(6):
        assert sorted(strata[:, j]) == list(range(20))


def test_a_curve_top_is_refined_by_the_parabola_through_one_over_a_squared():
    from workbench.studies.kinds.mistuning.compute import curve_peak

    f = np.linspace(400.0, 420.0, 11)
    a = 1.0 / np.sqrt(4.0 + 0.3 * (f - 411.3) ** 2)
    top, at = curve_peak(f, a)
    assert abs(top - 0.5) < 1e-12 and abs(at - 411.3) < 1e-9
    assert curve_peak(f, f) == (420.0, 420.0)  # a band end: the point itself


@pytest.mark.parametrize(
    "change, name",
    [
        ({"mistuning-std": "-1.0"}, "mistuning-std"),
        ({"mistuning-patterns": "1"}, "mistuning-patterns"),
        ({"mistuning-sampling": '"halton"'}, "mistuning-sampling"),
        # 64 patterns at 45 %: a draw below -2.2 sigma leaves a blade without stiffness
        ({"mistuning-std": "45.0", "mistuning-patterns": "64"}, "mistuning-std"),
    ],
)
def test_bad_input_names_the_option(tmp_path, change, name):
    with pytest.raises(InputError) as e:
        _spec(tmp_path, **change)
    assert e.value.param == name
    assert "\n" not in str(e.value)


def test_the_shipped_study_file_loads():
    from workbench.studies.engine.spec import load_study
    from workbench.studies.kinds.mistuning.patterns import study_patterns

    spec = load_study(ROOT / "studies" / "mistuning.toml")
    assert spec.kind == "mistuning" and spec.bladed_disk.n_blades == 8
    pats = study_patterns(spec)
    assert pats.df.shape == (50, 8) and np.all(1 + pats.df > 0)
