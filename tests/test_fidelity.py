"""The fidelity study: Pareto front, tolerance pick, option parsing, a tiny end-to-end run."""

from __future__ import annotations

import csv
import itertools
import json
import math
import random

import numpy as np
import pytest

from tests.conftest import ROOT, assert_nonblank, run_upd
from workbench.errors import InputError
from workbench.hbm.core.fourier import default_nt
from workbench.post.fidelity import Setting
from workbench.post.pareto import pareto_front, pick_cheapest
from workbench.studies.engine.spec import resolve
from workbench.studies.kinds.fidelity.ladders import propose_combination
from workbench.studies.kinds.fidelity.options import parse_harmonics

# ---- Pareto front ---------------------------------------------------------------------------

# one worker computes the module's tiny fidelity study (its fixture) once for every test
pytestmark = pytest.mark.xdist_group("fidelity")


def test_pareto_front_known_points():
    pts = [
        (1.0, 10.0),
        (2.0, 5.0),
        (3.0, 7.0),
        (4.0, 1.0),
        (4.0, 0.5),
        (5.0, None),
        (0.5, 20.0),
        (6.0, 0.5),
        (7.0, float("nan")),
        (8.0, 0.1),
    ]
    # (3, 7) is beaten by (2, 5); (4, 1) by (4, 0.5); (6, 0.5) ties in error but is slower;
    # None / NaN errors (failed settings) are never on the front
    assert pareto_front(pts) == [6, 0, 1, 4, 9]


def _dominated(i, pts):
    ti, ei = pts[i]
    return any(
        (tj <= ti and ej <= ei) and (tj < ti or ej < ei) for j, (tj, ej) in enumerate(pts) if j != i
    )


def test_pareto_front_matches_brute_force():
    rng = random.Random(8)
    for _ in range(50):
        pts = [
            (rng.choice([1, 2, 3, 4, 5, 6]) * 1.0, rng.choice([0.1, 0.5, 1.0, 2.0, 4.0]))
            for _ in range(rng.randint(1, 12))
        ]
        front = pareto_front(pts)
        expect = {i for i in range(len(pts)) if not _dominated(i, pts)}
        # exact duplicates are not dominated by each other: the front keeps one of them
        got = {pts[i] for i in front}
        assert got == {pts[i] for i in expect}
        assert len(front) == len(got)
        assert [pts[i][0] for i in front] == sorted(pts[i][0] for i in front)


# ---- tolerance pick -------------------------------------------------------------------------


def _row(label, t, e):
    return {"label": label, "time_s": t, "max_error_pct": e, "role": "knob"}


def test_pick_cheapest_meeting_the_tolerance():
    rows = [
        _row("coarse", 1.0, 5.0),
        _row("a", 3.0, 0.9),
        _row("b", 2.0, 0.99),
        _row("fine", 10.0, 0.01),
        _row("failed", 0.5, None),
    ]
    p = pick_cheapest(rows, 1.0)
    assert p["met"] and p["picked"]["label"] == "b"
    assert "cheapest" in p["reason"] and "'b'" in p["reason"]
    p = pick_cheapest(rows, 0.5)
    assert p["picked"]["label"] == "fine"
    p = pick_cheapest(rows, 5.0)  # the boundary counts as meeting it
    assert p["picked"]["label"] == "coarse"


def test_pick_when_nothing_meets_names_the_closest():
    rows = [_row("coarse", 1.0, 5.0), _row("mid", 3.0, 2.0), _row("x", 4.0, None)]
    p = pick_cheapest(rows, 1.0)
    assert not p["met"] and p["picked"] is None
    assert p["closest"]["label"] == "mid"
    assert p["reason"].startswith("NO setting meets 1 %") and "'mid'" in p["reason"]
    p = pick_cheapest([_row("x", 4.0, None)], 1.0)
    assert p["closest"] is None and "failed" in p["reason"]


def _ladder(knob, values, errors):
    out = []
    for v, e in zip(values, errors, strict=True):
        st = Setting(str(v), {knob: v}, "knob")
        st.errors = (
            {}
            if e is None
            else {
                "c": {"peak_amplitude_mm": e, "peak_frequency_hz": 0.0, "friction_energy_mj": 0.0}
            }
        )
        out.append(st)
    return out


def test_propose_combination_takes_the_coarsest_level_meeting_alone():
    ladders = {
        "modes": _ladder("modes", [4, 8, 12, 24], [3.0, 0.8, 0.2, 0.0]),
        "nt": _ladder("nt", [16, 32, 64], [None, 0.5, 0.0]),
    }
    vals, why = propose_combination(ladders, 1.0)
    assert vals == {"modes": 8, "nt": 32}
    assert "0.8" in why["modes"]
    vals, _ = propose_combination(ladders, 1.0, shift=1)  # the fallback: one level finer
    assert vals == {"modes": 12, "nt": 64}
    vals, _ = propose_combination(ladders, 1.0, shift=5)  # never beyond the finest
    assert vals == {"modes": 24, "nt": 64}
    # explicit per-level errors (e.g. against each knob's own finest level) take precedence
    vals, why = propose_combination(
        ladders, 1.0, errors={"modes": [0.5, 0.1, 0.0, 0.0], "nt": [2.0, 0.9, 0.0]}
    )
    assert vals == {"modes": 4, "nt": 32} and "0.9" in why["nt"]
    ladders["nt"] = _ladder("nt", [16, 32], [4.0, 2.0])
    assert propose_combination(ladders, 1.0) is None


# ---- options --------------------------------------------------------------------------------


@pytest.mark.parametrize("text, value", [("1%", 1.0), (" 0.5 %", 0.5), ("2", 2.0), (3, 3.0)])
def test_tolerance_accepts_percent(text, value):
    assert resolve({"tolerance": text}, "f.toml").fidelity.tolerance == value
    assert resolve(cli_values={"tolerance": text}).fidelity.tolerance == value


@pytest.mark.parametrize("text", ["abc%", "%", "0%", "-1", "150%"])
def test_tolerance_bad_values_name_the_parameter(text):
    with pytest.raises(InputError) as e:
        resolve(cli_values={"tolerance": text})
    assert e.value.param == "tolerance" and e.value.value == text


def test_parse_harmonics():
    assert parse_harmonics("1") == [1]
    assert parse_harmonics("0-3") == [0, 1, 2, 3]
    assert parse_harmonics("1+3+5") == [1, 3, 5]
    for bad in ("2-3", "0", "a", "1+1", "3-1"):
        with pytest.raises(InputError):
            parse_harmonics(bad)


def test_cli_bad_tolerance_is_one_line_exit_2():
    r = run_upd("study", "studies/fidelity.toml", "--tolerance", "1x%", "--out", "/nonexistent")
    assert r.code == 2
    lines = [x for x in r.err.strip().splitlines() if x.strip()]
    assert len(lines) == 1 and "tolerance" in lines[0] and "1x%" in lines[0], r.err
    r = run_upd("study", "studies/fidelity.toml", "--levels-harmonics", "2-3")
    assert r.code == 2 and "levels-harmonics" in r.err and "Traceback" not in r.err


def test_study_help_mentions_the_fidelity_options():
    r = run_upd("study", "--help")
    assert r.code == 0
    for opt in (
        "--tolerance",
        "--knobs",
        "--levels-mesh-size",
        "--levels-contact-mesh-size",
        "--contact-mesh-size",
        "--damper-phases",
        "--levels-modes",
        "--levels-harmonics",
        "--levels-nt",
        "--levels-points-per-line",
        "--levels-rigid-damper",
    ):
        assert opt in r.out, opt


def test_the_study_file_resolves():
    from workbench.studies.engine.spec import load_study
    from workbench.studies.kinds.fidelity.ladders import plan_settings

    spec = load_study(ROOT / "studies" / "fidelity.toml", {"tolerance": "1%"})
    assert spec.kind == "fidelity" and spec.fidelity.tolerance == 1.0
    settings, ladders = plan_settings(spec, ["cone"])
    ref = next(s for s in settings if s.role == "reference")
    assert ref.values == {
        "mesh-size": min(spec.fidelity.levels_mesh_size),
        "contact-mesh-size": 1.5,  # geometry/rig.toml's: not a knob of this study
        "modes": max(spec.fidelity.levels_modes),
        "harmonics": list(range(8)),
        "nt": max(spec.fidelity.levels_nt),
        "points-per-line": max(spec.fidelity.levels_points_per_line),
        "rigid-damper": False,
    }
    assert len(spec.fidelity.levels_mesh_size) >= 4
    # every setting is distinct; one knob differs from the base in each ladder setting
    assert len({s.key for s in settings}) == len(settings)
    base = settings[0].values
    for knob, lad in ladders.items():
        for st in lad:
            # harmonics beyond the base's come with the solver's default sampling for them
            extra = (
                {"nt"} if knob == "harmonics" and max(st.values[knob]) > max(base[knob]) else set()
            )
            assert {k for k in base if st.values[k] != base[k]} <= {knob} | extra
            if extra:
                assert st.values["nt"] == max(base["nt"], default_nt(tuple(st.values[knob])))
                if st.values["nt"] != base["nt"]:  # the chart's label says so
                    assert st.label.endswith(f", nt {st.values['nt']}"), st.label


# ---- a tiny end-to-end study ----------------------------------------------------------------

TINY = """
name = "tiny"
kind = "fidelity"
dampers = ["cone"]
phases = [0.0]
forces = [15.0]
mesh-size = 14.0
stability = false
harmonics = [0, 1, 2, 3, 4, 5]
nt = 64
knobs = ["harmonics", "nt"]
levels-harmonics = ["1", "0-3", "0-5"]
levels-nt = [16, 32, 64, 128]
"""
TOL = "3%"


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    from workbench.studies.engine.spec import load_study
    from workbench.studies.kinds.fidelity.compute import run_fidelity

    d = tmp_path_factory.mktemp("fid")
    (d / "tiny.toml").write_text(TINY)
    spec = load_study(d / "tiny.toml", {"tolerance": TOL})
    first = run_fidelity(spec, d / "out")
    return d, first


def _by_label(summary):
    return {r["label"]: r for r in summary["settings"]}


def test_tiny_reference_error_is_zero_and_errors_converge(tiny):
    d, s = tiny
    rows = _by_label(s)
    # H 0-5 and nt 64 are the base; nt 128 (with H 0-5) is the reference
    assert {"base", "H 1", "H 0-3", "nt 16", "nt 32", "reference"} <= set(rows)
    assert s["failures"] == []
    ref = rows["reference"]
    for q in ("peak_amplitude_mm", "peak_frequency_hz", "friction_energy_mj"):
        assert ref[f"err_{q}_pct"] == 0.0
    # AFT samples: 16 -> 32 -> 64 -> 128 (the reference) converges; harmonics 1 -> 0-5 too
    assert (
        rows["nt 16"]["max_error_pct"]
        > rows["nt 32"]["max_error_pct"]
        > rows["base"]["max_error_pct"]
        > 0.0
    )
    assert rows["H 1"]["max_error_pct"] > rows["base"]["max_error_pct"]
    # every setting pays geometry and reduction, even those that found them cached
    for r in rows.values():
        assert r["geometry_s"] > 0 and r["reduction_s"] > 0 and r["hbm_s"] > 0
        assert math.isclose(
            r["time_s"],
            r["geometry_s"] + r["reduction_s"] + r["assembly_s"] + r["hbm_s"],
            rel_tol=1e-6,
            abs_tol=2e-3,
        )
    # same model for every setting: the same recorded geometry and reduction times
    assert len({(r["geometry_s"], r["reduction_s"]) for r in rows.values()}) == 1
    # the Pareto front is non-dominated among the candidates (the reference is not one)
    cand = [r for r in rows.values() if r["role"] != "reference"]
    front = [r for r in cand if r["on_front"]]
    assert sorted(r["label"] for r in front) == sorted(s["pareto_front"]) and front
    for f, r in itertools.product(front, cand):
        assert not (r["time_s"] < f["time_s"] and r["max_error_pct"] < f["max_error_pct"])


def test_tiny_tolerance_pick_is_the_cheapest_meeting(tiny):
    d, s = tiny
    p = s["picked"]
    tol = float(TOL.rstrip("%"))
    rows = [r for r in s["settings"] if r["role"] != "reference"]
    meeting = [r for r in rows if r["max_error_pct"] is not None and r["max_error_pct"] <= tol]
    if meeting:
        assert p["met"] and p["picked"]["time_s"] == min(r["time_s"] for r in meeting)
        assert p["picked"]["max_error_pct"] <= tol
        assert p["picked"]["label"] in s["pareto_front"]  # the cheapest meeting is on the front
    else:
        assert not p["met"] and "NO setting meets" in p["reason"]
    # the first combination: per knob, the coarsest level within tol of the knob's finest
    own = s["knob_self_errors_pct"]
    assert own["nt"]["nt 128"] == 0.0 and own["harmonics"]["H 0-5"] == 0.0
    want = {
        k: next(lv for lv, e in errs.items() if e is not None and e <= tol)
        for k, errs in own.items()
    }
    c = s["combinations"][0]
    assert [lv.split(" (")[0] for lv in c["levels"].values()] == list(want.values())
    match = [
        r
        for r in s["settings"]
        if r["role"] != "combined" and all(r[k] == lv for k, lv in want.items())
    ]
    if match and match[0]["role"] == "reference":
        assert c["label"] == "reference" and not c["meets"]
    elif match:  # an already measured setting: not computed again
        assert c["label"] == match[0]["label"] and "already measured" in c["note"]
    else:  # a new setting: computed, its error against the reference measured
        comb = next(r for r in s["settings"] if r["label"] == c["label"])
        assert comb["role"] == "combined" and comb["max_error_pct"] is not None
        assert c["meets"] == (comb["max_error_pct"] <= tol)
        assert c["note"] == "computed to verify it"
        assert comb["time_s"] > 0 and comb["hbm_s"] > 0


def test_tiny_errors_against_the_limit(tiny):
    """Each knob's limit is extrapolated or flagged; every setting has errors against it."""
    d, s = tiny
    qs = ("peak_amplitude_mm", "peak_frequency_hz", "friction_energy_mj")
    assert set(s["knob_limits"]) == {"harmonics", "nt"}
    for lim in s["knob_limits"].values():
        for byq in lim.values():
            for q in qs:
                e = byq[q]
                if e["asymptotic"]:  # an extrapolation: with its order and uncertainty
                    assert e["method"] == "richardson" and 0.5 <= e["order"] <= 8
                    assert e["uncertainty"] >= 0 and e["reason"] == "" and e["trusted"]
                elif e["trusted"]:  # bounded: the finest level +- the finest levels' spread
                    assert e["method"] == "bounded" and e["value"] == e["finest"]
                    assert e["uncertainty"] >= 0 and "bounded" in e["reason"]
                else:  # no made-up number: the finest level, with the reason
                    assert e["method"] == "finest level" and e["value"] == e["finest"]
                    assert e["reason"]
    rows = _by_label(s)
    for c, byq in s["limit"].items():
        for q in qs:
            e = byq[q]
            flags = [s["knob_limits"][k][c][q]["asymptotic"] for k in s["knob_limits"]]
            trusted = [s["knob_limits"][k][c][q]["trusted"] for k in s["knob_limits"]]
            assert e["asymptotic"] == all(flags) and e["trusted"] == all(trusted)
            assert (e["uncertainty"] is None) == (not all(trusted))
    ref = rows["reference"]
    for q in qs:  # the reference itself is measured against the limit
        assert ref[f"err_lim_{q}_pct"] is not None and ref[f"err_lim_{q}_pct"] >= 0
    assert rows["nt 16"]["max_error_vs_limit_pct"] > 0
    # the pick says what it measured against: the limit where trusted, else the reference
    trusted = any(e["asymptotic"] for byq in s["limit"].values() for e in byq.values())
    assert s["picked"]["basis"] in s["picked"]["reason"]
    assert ("extrapolated limit" in s["picked"]["basis"]) == trusted
    assert (d / "out" / "tables" / "fidelity_limits.csv").is_file()
    man = json.loads((d / "out" / "manifest.json").read_text())
    assert "limits" in [x["id"] for x in man["sections"]]


def test_tiny_outputs_and_report(tiny):
    d, s = tiny
    out = d / "out"
    man = json.loads((out / "manifest.json").read_text())
    ids = [x["id"] for x in man["sections"]]
    assert ids[:3] == ["setup", "knob-harmonics", "knob-nt"] and "pareto" in ids
    assert "pick" in ids
    pick_text = " ".join(next(x for x in man["sections"] if x["id"] == "pick")["text"])
    assert s["picked"]["reason"] in pick_text
    for f in ("fidelity_harmonics.png", "fidelity_nt.png", "fidelity_pareto.png"):
        assert_nonblank(out / "figures" / f)
    for t in (
        "fidelity_settings.csv",
        "fidelity_pareto.csv",
        "fidelity_cases.csv",
        "fidelity_nt.csv",
    ):
        assert (out / "tables" / t).is_file()
    assert (out / "report.html").stat().st_size > 10_000


def test_tiny_second_run_reuses_everything(tiny):
    d, first = tiny
    r = run_upd("study", d / "tiny.toml", "--tolerance", TOL, "--out", d / "out", "--json", "-q")
    assert r.code == 0, r
    s = r.json
    assert s["n_computed"] == 0 and s["n_models_prepared"] == 0
    assert s["n_reused"] == first["n_computed"]
    a, b = _by_label(first), _by_label(s)
    for k in a:  # same errors and the same charged times: nothing was measured again
        assert a[k]["max_error_pct"] == b[k]["max_error_pct"]
        assert a[k]["time_s"] == b[k]["time_s"]
    assert s["picked"]["reason"] == first["picked"]["reason"]


def test_tiny_failed_case_has_no_error_and_is_never_picked(tiny):
    import dataclasses

    from workbench.post.fidelity import relative_errors
    from workbench.post.results import CaseResult

    d, _ = tiny
    files = sorted((d / "out" / "cache" / "cases").glob("*.h5"))
    good = CaseResult.load(files[0])
    ref = Setting("reference", {}, "reference", results={"c": good})
    bad = CaseResult.load(files[0])
    bad.branch = dataclasses.replace(bad.branch, failed=True, message="diverged")
    st = Setting("broken", {}, "knob", results={"c": bad})
    st.errors = relative_errors(st, ref)
    assert st.error() is None and st.failed == ["c: diverged"]
    same = Setting("same", {}, "knob", results={"c": good})
    same.errors = relative_errors(same, ref)
    assert same.error() == 0.0
    rows = [
        {"label": s.label, "time_s": t, "max_error_pct": s.error()}
        for s, t in ((st, 1.0), (same, 2.0))
    ]
    assert pick_cheapest(rows, 1.0)["picked"]["label"] == "same"


@pytest.mark.slow
def test_real_fidelity_study(tmp_path):
    """The shipped study (about 15-25 min on 2 busy cores): reference exact, a clear pick."""
    r = run_upd(
        "study",
        ROOT / "studies" / "fidelity.toml",
        "--tolerance",
        "1%",
        "--out",
        tmp_path / "fid",
        "--json",
        "-q",
        timeout=5400,
    )
    assert r.code == 0, r
    s = r.json
    rows = _by_label(s)
    assert rows["reference"]["max_error_pct"] == 0.0 and s["failures"] == []
    assert len(s["knobs"]["mesh-size"]) >= 4 and s["pareto_front"]
    p = s["picked"]
    assert p["met"] == (p["picked"] is not None)
    if p["met"]:
        assert p["picked"]["max_error_pct"] <= 1.0 and p["picked"]["label"] in s["pareto_front"]
    else:
        assert "NO setting meets" in p["reason"]
    for f in ("fidelity_pareto.png", "fidelity_mesh-size.png", "fidelity_nt.png"):
        assert_nonblank(tmp_path / "fid" / "figures" / f)


# ---- the nonlinear-mode synthesis entry -------------------------------------------------------

TINY_NLM = """
name = "tiny_nlm"
kind = "fidelity"
dampers = ["cone"]
phases = [0.0]
forces = [15.0]
mesh-size = 14.0
stability = false
harmonics = [0, 1, 2, 3]
nt = 32
knobs = ["nt"]
levels-nt = [32, 64]
nonlinear-modes = true
"""


@pytest.mark.slow
def test_fidelity_nonlinear_mode_entry(tmp_path):
    """With nonlinear-modes on, the ladder gets the synthesis as one more setting: its
    error is the synthesised peak against the reference setting's HBM peak (recomputed
    here from the cached backbone), within 2 % where the synthesis calls itself valid,
    and its time is the base model's plus the backbone's."""
    from workbench.hbm.nlmodes.record import NlModeBranch
    from workbench.hbm.nlmodes.synthesis import synthesize
    from workbench.studies.engine.spec import load_study
    from workbench.studies.kinds.fidelity.compute import run_fidelity

    (tmp_path / "tiny_nlm.toml").write_text(TINY_NLM)
    spec = load_study(tmp_path / "tiny_nlm.toml", {"tolerance": "3%"})
    out = tmp_path / "out"
    s = run_fidelity(spec, out)
    rows = _by_label(s)
    nlm = rows["nonlinear-mode synthesis"]
    assert nlm["role"] == "nlmode" and nlm["failed"] == ""
    base, ref = rows["base"], rows["reference"]
    # the model is the base setting's: same geometry and reduction charged
    assert (nlm["geometry_s"], nlm["reduction_s"]) == (base["geometry_s"], base["reduction_s"])
    assert nlm["hbm_s"] > 0
    # the error, recomputed from the cached backbone and the reference's peak
    (h5,) = (out / "cache" / "nlmodes").glob("*.h5")
    nm = NlModeBranch.load(h5)
    with np.load(h5.with_suffix(".npz")) as z:
        f1, band = z["f1"], tuple(float(v) for v in z["band"])
    syn = synthesize(nm, f1, 15.0, 0, band)
    assert ref["err_peak_amplitude_mm_pct"] == 0.0
    with open(out / "tables" / "fidelity_cases.csv", newline="") as fh:
        (ref_row,) = [r for r in csv.DictReader(fh) if r["role"] == "reference"]
    ref_peak = float(ref_row["peak_amplitude_mm"])
    err = nlm["err_peak_amplitude_mm_pct"]
    # the table keeps 4 significant digits: the recomputed error within 0.02 points
    assert err == pytest.approx(abs(syn.peak_amplitude * 1e3 / ref_peak - 1) * 100, abs=0.02)
    if syn.valid:
        assert err < 2.0
    else:
        assert "not valid" in nlm["knobs"]


def test_a_stuck_dampers_round_off_energy_is_zero_not_a_1000_percent_error():
    """A damper stuck at the peak dissipates nothing; its loop integral comes out as
    round-off (6.3e-18 mJ on the pad rig's stuck cylinder) and must not be read as a
    relative error of hundreds of percent against another round-off value, or against
    a limit: both are 0, the error 0 %. A level that slips where the reference sticks
    counts by its energy against the largest the study measures (100 % without one), and
    the other way round as 100 %: never a silent pass. A real dissipation (1e-9 mJ and
    up) is kept."""
    from workbench.post.fidelity import ROUND_OFF_ZERO, _relative, zeroed

    q = "friction_energy_mj"
    assert zeroed(q, 6.301e-18) == 0.0 and zeroed(q, -3e-17) == 0.0
    assert zeroed(q, 1e-9) == 1e-9 and zeroed(q, None) is None
    assert zeroed("peak_frequency_hz", 1e-15) == 1e-15  # only the energy has a zero floor
    out: dict = {}
    _relative(6.301e-18, 2.6e-18, out, q)
    assert out == {q: 0.0}  # 0 against 0, not 142 %
    out = {}
    _relative(0.5, 4e-17, out, q)
    assert out == {q: 100.0}  # one slips, the other sticks: no scale, a full miss
    out = {}
    _relative(0.5, 4e-17, out, q, scale=25.0)
    assert out[q] == pytest.approx(2.0)  # 0.5 mJ against the study's 25 mJ energies
    out = {}
    _relative(4e-17, 0.5, out, q)
    assert out == {q: 100.0}
    out = {}
    _relative(2e-9, 1e-9, out, q)
    assert out[q] == pytest.approx(100.0)  # small but real: measured
    assert ROUND_OFF_ZERO[q] < 1e-9


def test_an_nt_ladder_below_the_references_sampling_is_refused_when_planned():
    """Harmonics 0-5 beyond a base of 0-3 are sampled at nt 128 (the solver's default), so
    the reference is too; an nt ladder that stops at 64 could not correct it: the study
    says so when it is planned, naming levels-nt and the nt it needs."""
    from workbench.studies.engine.spec import load_study
    from workbench.studies.kinds.fidelity.ladders import plan_settings

    over = {"knobs": "harmonics,nt", "levels-harmonics": "0-1,0-3,0-5", "levels-nt": "16,32,64",
            "harmonics": "0,1,2,3", "nt": 64}  # fmt: skip
    spec = load_study(ROOT / "studies" / "fidelity.toml", over)
    with pytest.raises(InputError) as e:
        plan_settings(spec, ["cone"])
    assert e.value.param == "levels-nt" and "128" in str(e.value)
    spec = load_study(
        ROOT / "studies" / "fidelity.toml", dict(over, **{"levels-nt": "16,32,64,128"})
    )
    settings, _ = plan_settings(spec, ["cone"])
    ref = next(s for s in settings if s.role == "reference")
    assert ref.values["nt"] == 128 and ref.values["harmonics"] == list(range(6))
