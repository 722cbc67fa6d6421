"""Robustness study: methods x cases on small models, the failure map, resume, bad input.

The rig cases of studies/robustness.toml need meshes and reductions, so the
default tests use the small documented models of workbench.hbm.io.examples; the
end-to-end run on a rig case is marked slow.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from conftest import assert_nonblank, run_upd

from workbench.errors import InputError, SolveError
from workbench.hard_cases import CASES, METHODS
from workbench.hbm.io.examples import sdof_jenkins, sdof_unilateral
from workbench.studies.engine.spec import BY_NAME, resolve
from workbench.studies.kinds.robustness import compute as rb
from workbench.studies.kinds.robustness.cells import ENERGY_TOL, Problem, classify, method_options
from workbench.studies.kinds.robustness.time_check import (
    TIME_MODELS,
    branch_amplitudes_at,
    compare_with_branch,
    time_check,
    turning_points,
)

ROOT = Path(__file__).resolve().parents[1]


def _problem(name, ex, level, band=None, harmonics=(0, 1, 2, 3)):
    band = band or ex.band_hz
    return Problem(
        name,
        f"test-{name}-{level}-{band}",
        level,
        tuple(harmonics),
        None,
        lambda: (ex.system, ex.f1, band, ex.outputs, ex.output_names),
    )


@pytest.fixture(scope="module")
def jenkins_cells():
    # the friction oscillator at the slip force: stick-slip over the peak, no fold
    p = _problem("jenkins", sdof_jenkins(), 1.0)
    return rb.method_map(
        [p],
        ["default", "fd-jacobian", "ls-basic", "tangent-predictor", "frequency-stepping"],
        tol_pct=1.0,
    )


def test_methods_agree_on_the_friction_oscillator(jenkins_cells):
    by = {c["method"]: c for c in jenkins_cells}
    assert by["default"]["status"] == "ok" and by["default"]["succeeded"]
    ref = by["default"]["peak_amplitude"]
    ok = [c for c in jenkins_cells if c["succeeded"]]
    assert len(ok) >= 4  # the branch has no turning point: every method should pass
    for c in ok:
        # 0.5 %: the top of a Jenkins peak is kinked and flat; where each method's points and
        # its peak search land on it moves the largest amplitude by ~0.1 %
        assert abs(c["peak_amplitude"] - ref) / ref < 5e-3, c["method"]
        assert c["status"] == "ok"
        assert c["newton_its"] > 0 and c["n_points"] > 5 and c["wall_s"] > 0
    # the analytic and the finite-difference Jacobians converge to the same points
    assert by["fd-jacobian"]["amp_dev_pct"] == pytest.approx(0.0, abs=1e-3)


def test_frequency_stepping_fails_at_a_turning_point_and_keeps_its_branch():
    # a mass pressed on a stiff unilateral spring (kn = 3 k): the opening contact folds the
    # curve near 71 Hz (a superharmonic resonance); arc length passes, stepping cannot
    ex = sdof_unilateral(kn_ratio=3.0, zeta=0.01)
    p = _problem("unilateral", ex, 3.0, band=(60.0, 250.0), harmonics=(0, 1, 2, 3, 4, 5))
    cells = rb.method_map([p], ["default", "frequency-stepping"])
    ref, step = cells
    assert ref["status"] == "ok" and ref["n_turning_points"] >= 1
    fold = min(ref["turning_points_hz"])
    assert step["status"] == "failed" and not step["succeeded"]
    assert "turning point" in step["message"]
    assert step["n_points"] > 1  # the points before the fold are kept
    # it stopped at the fold, not before and not beyond the frequency where the branch turns
    assert step["freq_reached_hz"] == pytest.approx(max(ref["turning_points_hz"]), rel=0.02)
    assert fold < 75.0
    assert step["band_fraction"] < 0.1


def test_a_converged_but_different_peak_is_a_wrong_answer():
    cells = [
        dict(
            case="c",
            method="a",
            succeeded=True,
            peak_amplitude=1.0,
            peak_frequency_hz=10.0,
            band_hz=[0.0, 20.0],
        ),
        dict(
            case="c",
            method="b",
            succeeded=True,
            peak_amplitude=0.97,
            peak_frequency_hz=10.0,
            band_hz=[0.0, 20.0],
        ),
        dict(
            case="c",
            method="d",
            succeeded=True,
            peak_amplitude=1.004,
            peak_frequency_hz=11.0,
            band_hz=[0.0, 20.0],
        ),
        dict(
            case="c",
            method="e",
            succeeded=False,
            peak_amplitude=0.5,
            peak_frequency_hz=5.0,
            band_hz=[0.0, 20.0],
        ),
    ]
    classify(cells, "a", 1.0)
    assert [c["status"] for c in cells] == ["ok", "wrong", "ok", "failed"]
    assert cells[1]["amp_dev_pct"] == pytest.approx(-3.0)
    assert cells[2]["freq_dev_pct"] == pytest.approx(5.0)


def test_turning_points_are_sign_changes_of_the_frequency_increment():
    f = np.array([1.0, 2.0, 3.0, 2.5, 2.0, 2.6, 4.0])
    assert turning_points(f).tolist() == [2, 4]  # the vertices, f = 3 and f = 2
    assert turning_points(np.linspace(1, 2, 9)).size == 0


def test_time_integration_is_compared_with_the_nearest_coexisting_solution():
    # a folded branch: three solutions at f = 2 (amplitudes 1, 2 and 3)
    check = {
        "freq_hz": [1.0, 3.0, 1.5, 3.0],
        "amp": [0.0, 2.0, 3.0, 4.0],
        "points": [{"freq_hz": 2.0, "hbm_amplitude": 1.0, "ti_amplitude": 3.03}],
    }
    assert sorted(branch_amplitudes_at(check["freq_hz"], check["amp"], 2.0)) == pytest.approx(
        [1.0, 2.0 + 2.0 / 3.0, 3.0 + 1.0 / 3.0]
    )
    compare_with_branch(check)
    r = check["points"][0]
    assert r["nearest_hbm_amplitude"] == pytest.approx(3.0 + 1.0 / 3.0)
    assert r["diff_nearest_pct"] == pytest.approx(100 * (3.03 / (10 / 3) - 1))
    assert r["n_hbm_solutions"] == 3


def test_resume_recomputes_nothing(tmp_path, monkeypatch):
    p = _problem("jenkins-low", sdof_jenkins(), 0.5)
    first = rb.method_map([p], ["default", "ls-basic"], tmp_path)
    assert len(list(tmp_path.glob("*.json"))) == 2 and not any(c["cached"] for c in first)

    def boom(*a, **k):
        raise AssertionError("a cached cell was recomputed")

    monkeypatch.setattr(rb, "run_cell", boom)
    again = rb.method_map([p], ["default", "ls-basic"], tmp_path)
    assert all(c["cached"] for c in again)
    assert [c["newton_its"] for c in again] == [c["newton_its"] for c in first]
    with pytest.raises(AssertionError, match="recomputed"):
        rb.method_map([p], ["default"], tmp_path, force=True)


def test_map_figure_is_not_blank(jenkins_cells, tmp_path):
    from workbench.studies.kinds.robustness.figures import plot_branches, plot_failure_map

    cells = [dict(c) for c in jenkins_cells]
    cells[-1]["status"] = "failed"  # all three colours
    cells[-2]["status"] = "wrong"
    methods = [c["method"] for c in cells]
    png = plot_failure_map(cells, methods, ["jenkins"], tmp_path / "map.png")
    assert_nonblank(png)
    assert_nonblank(plot_branches(cells, ["jenkins"], tmp_path / "curves.png"))


def test_registry_matches_the_study_options():
    assert tuple(METHODS) == BY_NAME["methods"].choices
    assert tuple(CASES) == BY_NAME["hard-cases"].choices
    assert method_options("default") == method_options("default", {})
    assert method_options("fixed-step").ds_min == method_options("fixed-step").ds_max


@pytest.mark.parametrize(
    "key,value,param",
    [
        ("methods", ["default", "newton-raphson"], "methods[1]"),
        ("hard-cases", "near-separation,moon-landing", "hard-cases[1]"),
    ],
)
def test_unknown_names_are_input_errors(key, value, param):
    with pytest.raises(InputError) as e:
        resolve({"kind": "robustness", key: value})
    assert e.value.param == param


def test_cli_unknown_method_is_one_line_exit_2(tmp_path):
    r = run_upd(
        "study", "--kind", "robustness", "--methods", "default,nope", "--out", tmp_path, timeout=120
    )
    assert r.code == 2, r.err
    lines = [ln for ln in r.err.strip().splitlines() if ln.strip()]
    assert len(lines) == 1 and "methods[1]" in lines[0] and "nope" in lines[0]


def test_study_help_lists_the_robustness_options():
    r = run_upd("study", "--help", timeout=120)
    assert r.code == 0
    text = re.sub(r"-\s+", "-", r.out)  # argparse wraps lines after hyphens
    assert "robustness options" in text
    for word in (
        "--methods",
        "--hard-cases",
        "--peak-tolerance",
        "--time-check",
        *METHODS,
        *CASES,
    ):
        assert word in text, word


def test_time_integration_confirms_the_light_damping_peak():
    # the Jenkins oscillator with 0.01 % damping: time integration started on the HBM orbit
    # at the peak stays on it (7 harmonics: the HBM truncation error is well below 1 %)
    rec = time_check("sdof-light-damping", TIME_MODELS["sdof-light-damping"])
    peak = next(r for r in rec["points"] if "peak" in r["why"])
    assert peak["hill_stable"]
    assert abs(peak["diff_pct"]) < 1.0


@pytest.mark.slow
def test_study_end_to_end_on_one_rig_case(tmp_path):
    from workbench.studies.kinds.robustness.compute import run_robustness

    spec = resolve(
        {
            "kind": "robustness",
            "name": "rob",
            "methods": ["default", "ls-basic"],
            "hard-cases": ["high-force"],
            "time-check": False,
            "mesh-size": 14.0,
            "geometry": str(ROOT / "studies" / "robustness_geometry.toml"),
        }
    )
    s = run_robustness(spec, tmp_path)
    assert s["reference_failed"] == []
    assert {c["method"] for c in s["cells"]} == {"default", "ls-basic"}
    man = json.loads((tmp_path / "manifest.json").read_text())
    assert any(sec["id"] == "map" for sec in man["sections"])
    assert (tmp_path / "report.html").is_file()
    assert_nonblank(tmp_path / "figures" / "robustness_map.png")
    again = run_robustness(spec, tmp_path)
    assert [c["newton_its"] for c in again["cells"]] == [c["newton_its"] for c in s["cells"]]
    # a reference that fails (a fixed step cannot follow the near-separation case) is an
    # error (exit 3) raised after the outputs are written, with the summary as partial
    bad = spec.replace(methods=["fixed-step", "default"], hard_cases=["near-separation"])
    with pytest.raises(SolveError, match="reference method 'fixed-step' failed") as e:
        run_robustness(bad, tmp_path / "bad")
    assert e.value.partial["reference_failed"] == ["near-separation"]
    assert (tmp_path / "bad" / "report.html").is_file()


@pytest.mark.parametrize("model", ["jenkins", "two-dof"])
@pytest.mark.parametrize("method", ["ls-cp", "default"])
def test_every_accepted_point_is_a_solution(method, model):
    # SNES itself says "converged" (snorm) when a failed line search leaves a tiny step; the
    # corrector must not accept such a point (with the cp line search it did: residuals up to
    # 4e-8 relative on the Jenkins oscillator, 0.19 on the light-damping rig case). Each
    # point's residual is computed here, independently of the corrector.
    from workbench.hbm.core.balance import HarmonicBalance
    from workbench.hbm.core.fourier import Fourier
    from workbench.hbm.forced.response import frequency_response
    from workbench.hbm.io.examples import two_dof_contact

    ex, level, harm = (
        (sdof_jenkins(), 1.0, (0, 1, 2, 3))
        if model == "jenkins"
        else (two_dof_contact(zeta=0.005), 3.0, tuple(range(6)))
    )
    opts = method_options(method)
    b = frequency_response(
        ex.system, ex.f1, level, ex.band_hz, outputs=ex.outputs, harmonics=harm, options=opts
    )
    hb = HarmonicBalance(
        ex.system,
        ex.f1,
        Fourier(b.harmonics, b.nt),
        ex.outputs,
        level,
        opts.space,
        opts.backend,
        opts.dc_anchor,
    )
    if method == "default":
        assert b.n_points > 10 and not b.failed, b.message
    else:
        # cp on the two-DOF model sits on the edge: on one machine it completes, on a fresh
        # Debian root it stops at 88.2 Hz where the corrector (rightly) refuses SNES's claim
        # of convergence. What this test asserts is that every point it did accept solves
        # the balance, so it only needs some points to check.
        assert b.n_points >= 5, b.message
    worst = max(
        np.abs(hb.residual(x, 2 * np.pi * f)).max() / max(np.abs(x).max(), b.stats["u_ref_m"])
        for x, f in zip(b.x, b.freq_hz, strict=True)
    )
    # the corrector's tolerance (relative); points accepted on a stall at a kink are counted
    # and may reach tol_stall
    limit = opts.tol if b.stats["n_stalled"] == 0 else opts.tol_stall
    assert worst <= 1.01 * limit
    assert np.max(b.energy_residual) < ENERGY_TOL


def test_report_text_names_each_failure_and_how_far_it_got():
    spec = resolve(
        {
            "kind": "robustness",
            "methods": ["default", "fixed-step"],
            "hard-cases": ["high-force"],
            "time-check": False,
        }
    )
    base = dict(
        case="high-force",
        band_hz=[300.0, 400.0],
        n_points=12,
        newton_its=40,
        wall_s=0.1,
        stable=[True] * 12,
    )
    cells = [
        dict(
            base,
            method="default",
            succeeded=True,
            peak_amplitude=1.0,
            peak_frequency_hz=350.0,
            energy_residual_max=1e-9,
        ),
        dict(
            base,
            method="fixed-step",
            succeeded=False,
            failed=True,
            message="the corrector failed at f = 340 Hz",
            freq_reached_hz=340.0,
            band_fraction=0.4,
            peak_amplitude=0.5,
            peak_frequency_hz=340.0,
        ),
    ]
    classify(cells, "default", 1.0)
    secs = rb._sections(spec, cells, [], {})
    text = " ".join(secs[1]["text"])
    assert "fixed-step on high-force: the corrector failed at f = 340 Hz" in text
    assert "reached 340 Hz, 40 % of the band, 12 points kept" in text
    # a converged branch that is not a solution (energy balance off) is a wrong answer
    cells[1].update(succeeded=True, energy_residual_max=0.4, peak_amplitude=1.0)
    classify(cells, "default", 1.0)
    assert cells[1]["status"] == "wrong"
    assert "energy balance is off by 0.4" in " ".join(rb._sections(spec, cells, [], {})[1]["text"])
