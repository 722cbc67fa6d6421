"""Pinned results of both path-following problems, held bit for bit through refactors.

The forced responses and backbones below were computed once (tests/data/path_pinned.npz,
written by ``python tests/test_path_pinned.py --write`` at the commit before the path
engine's migration, issue 30 item 2) and must come out the same: every per-point array
exactly, ``completed``, ``failed``, ``message``, and the integer counters of the
corrector (Newton solves, factorisations, residual and Jacobian evaluations, Krylov
iterations). Timings are not compared. A change that is meant to change results
regenerates the file and says why in its commit.

The cases cover both correctors of the forced response (the PETSc SNES one and the
compiled one, on tests/test_small.py's examples), every solver variant of the
robustness study (finite-difference Jacobian, lagged GMRES, chord, line searches,
predictors, plain frequency stepping), and backbones with refinement at synthesised
peaks, a fold passed by arc length, the dense, chord and Newton-Krylov linear solvers
and the plateau stop.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import fields
from pathlib import Path

import numpy as np
import pytest

from workbench.contact import ContactElements
from workbench.hbm import SolverOptions, System, frequency_response
from workbench.hbm.io.examples import line_damper_rig, sdof_jenkins, two_dof_contact, unit_jenkins
from workbench.hbm.nlmodes.backbone import nonlinear_mode

DATA = Path(__file__).parent / "data" / "path_pinned.npz"

# the corrector counters pinned (forced response: Branch.stats; backbone: timings)
FRF_COUNTS = (
    "n_snes",
    "n_factor",
    "n_residual",
    "n_jacobian",
    "ksp_its",
    "n_stalled",
    "n_failed",
    "aft_periods_max",
    "stability_n_hill",
    "stability_n_linear",
    "stability_n_carried",
    "stability_n_bisect",
    "stability_n_unknown",
    "n_unknowns",
)
NLM_COUNTS = ("factorisations", "krylov_its")


def _small(make, level, harm, nt, compiled):
    ex = make()
    return frequency_response(
        ex.system,
        ex.f1,
        level,
        ex.band_hz,
        ex.outputs,
        harmonics=harm,
        nt=nt,
        options=SolverOptions(compiled=compiled),
    )


def _jenkins(**kw):
    ex = sdof_jenkins(zeta=0.02)
    return frequency_response(
        ex.system,
        ex.f1,
        1.0,
        (90, 160),
        [0],
        harmonics=(0, 1, 2, 3),
        options=SolverOptions(**kw),
    )


def _rig(lin, lag):
    ex = line_damper_rig(n_per_line=3, family="out-of-phase", k_line_n_per_m2=5e8, mu=0.5)
    return nonlinear_mode(
        ex.system,
        f1=ex.f1,
        band_hz=ex.band_hz,
        harmonics=(0, 1, 3),
        outputs=ex.outputs,
        max_fold_points=20,
        levels=(0.096, 3.84, 30.0),
        linear=lin,
        jacobian_lag=lag,
    )


def _folding_chain():
    el = ContactElements.from_dofs(2, [[1]], mu=0.5, kt=4e5, n0=2.0)
    K = np.array([[8e4, -4e4], [-4e4, 4e4]])
    sysm = System(M=np.eye(2) * 0.1, K=K, zeta=0.005, contacts=el)
    return nonlinear_mode(sysm, f1=np.array([1.0, 0.0j]), harmonics=(0, 1, 3), outputs=[0])


def _sdof_levels():
    ex = sdof_jenkins()
    return nonlinear_mode(
        ex.system, f1=ex.f1, harmonics=(0, 1, 3), outputs=ex.outputs, levels=ex.levels
    )


def _two_dof_levels():
    ex = two_dof_contact()
    return nonlinear_mode(
        ex.system,
        f1=ex.f1,
        band_hz=ex.band_hz,
        harmonics=(0, 1, 2, 3),
        outputs=ex.outputs,
        levels=ex.levels,
    )


SMALL = {
    "unit-jenkins-slip": (unit_jenkins, 1.0, tuple(range(8)), 128),
    "unit-jenkins-below": (unit_jenkins, 0.8, tuple(range(8)), 128),
    "sdof-jenkins": (sdof_jenkins, 1.0, tuple(range(8)), 128),
    "two-dof-separating": (two_dof_contact, 3.0, tuple(range(6)), 128),
    "two-dof-circular": (lambda: two_dof_contact(law="circular"), 2.0, (0, 1, 2, 3), 64),
    "two-dof-dahl": (lambda: two_dof_contact(law="dahl"), 2.0, (0, 1, 2, 3), 64),
}
VARIANTS = {
    "default": {},
    "fd": dict(jacobian="fd"),
    "lagged": dict(linear_solver="lagged"),
    "chord": dict(linear_solver="chord"),
    "ls-basic": dict(line_search="basic"),
    "ls-l2": dict(line_search="l2"),
    "pred-tangent": dict(predictor="tangent"),
    "pred-constant": dict(predictor="constant"),
    "frequency-stepping": dict(continuation="frequency", ds_max=0.02),
}

CASES: dict[str, Callable[[], object]] = {}
for _name, (_make, _level, _harm, _nt) in SMALL.items():
    for _c in ("off", "auto"):
        CASES[f"frf-{_name}-{_c}"] = lambda m=_make, lv=_level, h=_harm, n=_nt, c=_c: _small(
            m, lv, h, n, c
        )
for _name, _kw in VARIANTS.items():
    CASES[f"frf-jenkins-{_name}"] = lambda kw=_kw: _jenkins(**kw)
CASES["nlm-sdof-levels"] = _sdof_levels
CASES["nlm-two-dof-levels"] = _two_dof_levels
CASES["nlm-folding-chain"] = _folding_chain
CASES["nlm-rig-dense"] = lambda: _rig("dense", 1)
CASES["nlm-rig-chord"] = lambda: _rig("dense", 3)
CASES["nlm-rig-krylov"] = lambda: _rig("auto", 3)


def record_of(b) -> dict[str, np.ndarray]:
    """Every array, the end state and the counters of a Branch or NlModeBranch."""
    out: dict[str, np.ndarray] = {}
    for f in fields(b):
        v = getattr(b, f.name)
        if isinstance(v, np.ndarray):
            out[f.name] = v
    for k in ("completed", "failed", "message"):
        out[k] = np.asarray(getattr(b, k))
    counts = getattr(b, "stats", None)
    names = FRF_COUNTS if counts is not None else NLM_COUNTS
    counts = counts if counts is not None else b.timings
    for k in names:
        out[f"count:{k}"] = np.asarray(counts[k])
    if "mode" in (getattr(b, "stats", None) or {}):
        out["count:mode"] = np.asarray(b.stats["mode"])
    return out


def _stored() -> dict[str, dict[str, np.ndarray]]:
    out: dict[str, dict[str, np.ndarray]] = {}
    with np.load(DATA) as z:
        for key in z.files:
            case, name = key.split("|", 1)
            out.setdefault(case, {})[name] = z[key]
    return out


@pytest.fixture(scope="module")
def stored():
    return _stored()


def test_every_case_is_stored(stored):
    assert sorted(stored) == sorted(CASES)


@pytest.mark.parametrize("case", sorted(CASES))
def test_path_results_are_pinned(case, stored):
    """The branch equals the stored one bit for bit (arrays, end state, counters)."""
    want = stored[case]
    got = record_of(CASES[case]())
    assert sorted(got) == sorted(want)
    for k, v in want.items():
        assert got[k].dtype == v.dtype and got[k].shape == v.shape, k
        np.testing.assert_array_equal(got[k], v, err_msg=f"{case}: {k}")


def write() -> None:
    data = {}
    for case, run in CASES.items():
        for k, v in record_of(run()).items():
            data[f"{case}|{k}"] = v
    DATA.parent.mkdir(exist_ok=True)
    np.savez_compressed(DATA, **data)
    print(f"{DATA}: {len(CASES)} cases, {DATA.stat().st_size} bytes")


if __name__ == "__main__":
    if sys.argv[1:] != ["--write"]:
        sys.exit("usage: python tests/test_path_pinned.py --write")
    write()
