"""The fidelity study of the main job on the paper rig (issue 31, item 3): its study file
plans the main job's setting and the intended cases and levels, the contact-mesh-size knob
reaches the mesh, a diverging ladder is flagged, not extrapolated into a limit."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import pytest

from tests.conftest import ROOT
from workbench.errors import InputError
from workbench.post.extrapolation import richardson
from workbench.post.fidelity import (
    NOT_APPLICABLE,
    Setting,
    combined_limits,
    ladder_limits,
)
from workbench.studies.engine.plan import make_case
from workbench.studies.engine.spec import load_study, resolve

STUDY = ROOT / "studies" / "fidelity_paper_rig.toml"
CASES = [
    "cone 0 deg 9.6 N",
    "cone 0 deg 30 N",
    "wedge 0 deg 9.6 N",
    "wedge 0 deg 30 N",
    "cone 180 deg 9.6 N",
    "cone 180 deg 30 N",
]


def test_the_study_plans_the_main_job_and_the_three_cases(tmp_path):
    from workbench.studies.kinds.fidelity.compute import _Computer
    from workbench.studies.kinds.fidelity.ladders import base_values, plan_settings

    spec = load_study(STUDY, {})
    comp = _Computer(spec, tmp_path, False)
    assert comp.names == CASES and comp.dampers == ["cone", "wedge"]
    # the base is the main job's setting (studies/paper_rig.toml, its geometry's defaults)
    main = load_study(ROOT / "studies" / "paper_rig.toml", {})
    assert Path(main.geometry).resolve() == Path(spec.geometry).resolve()
    assert (
        comp.base_values
        == base_values(main, ["cone"])
        == {
            "mesh-size": 9.0,
            "contact-mesh-size": 1.5,
            "modes": 12,
            "harmonics": [0, 1, 2, 3],
            "nt": 64,
            "points-per-line": 23,
            "rigid-damper": False,
        }
    )
    settings, ladders = plan_settings(spec, comp.dampers)
    base = settings[0]
    assert base.role == "base" and base.values == comp.base_values
    # at least three levels per knob (a Richardson estimate), the base one of them
    assert set(ladders) == {"mesh-size", "contact-mesh-size", "modes", "harmonics", "nt",
                            "points-per-line"}  # fmt: skip
    for knob, lad in ladders.items():
        assert len(lad) >= 3 and base in lad, knob
    ref = next(s for s in settings if s.role == "reference")
    assert ref.values == dict(
        comp.base_values,
        **{"contact-mesh-size": 1.0, "modes": 24, "harmonics": list(range(6)),
           "points-per-line": 33, "nt": 128},  # nt: the solver's default for harmonics 0-5
    )  # fmt: skip
    # the costly levels stay out: no 7 mm mesh, no harmonics above 5
    assert min(s.values["mesh-size"] for s in settings) == 9.0
    assert max(max(s.values["harmonics"]) for s in settings) == 5
    # the wedge does not take points per line: its cases on that ladder are the base's
    base_cases = [c.digest for c in comp.cases(base)]
    for st in ladders["points-per-line"]:
        for c, b in zip(comp.cases(st), base_cases, strict=True):
            assert (c.digest == b) == (c.damper == "wedge" or st is base)
    # every planned geometry passes the layout's fit checks (no gmsh)
    from workbench.geometry.layout import make_layout
    from workbench.geometry.params import load_geometry_params
    from workbench.pipeline import geometry_request

    reqs = {repr(r): r for st in settings for r in map(geometry_request, comp.cases(st))}
    # base, mesh, contact, points (cone), reference (cone: the wedge's is its contact 1 mm)
    assert len(reqs) == 2 + 2 * 2 + 2 * 2 + 3 + 1
    for r in reqs.values():
        gp = load_geometry_params(r["damper"], r["geometry_file"], r["overrides"], r["size_mm"])
        make_layout(gp)
    assert comp.not_applicable(ladders) == {
        ("points-per-line", "wedge 0 deg 9.6 N"),
        ("points-per-line", "wedge 0 deg 30 N"),
    }


@pytest.mark.parametrize(
    "pairs", [["cone 90"], ["blade 0"], ["cone"], ["cone x"], ["cone 0", "cone 0.0"]]
)
def test_bad_damper_phases_name_the_parameter(pairs):
    with pytest.raises(InputError, match=r"^damper-phases\[\d\] = \S"):
        resolve(
            {"kind": "fidelity", "dampers": ["cone", "wedge"], "phases": [0.0, 180.0],
             "damper-phases": pairs},
            "f.toml",
        )  # fmt: skip


def test_contact_mesh_size_reaches_the_mesh(tmp_path):
    """Two contact sizes: two geometry folders, two model keys, more nodes at the finer."""
    from workbench.pipeline.model import geometry_request, load_geometry

    s = load_study(STUDY, {}).as_dict()
    s.update({"mesh-size": 14.0, "points-per-line": 5})
    nodes, keys = {}, set()
    for size in (5.0, 2.5):
        case = make_case("cylinder", 0.0, 30.0, dict(s, **{"contact-mesh-size": size}))
        assert geometry_request(case)["overrides"]["rig"] == {"mesh": {"contact_size_mm": size}}
        geo = load_geometry(case, tmp_path)
        nodes[size] = (geo.stats["rig_n_nodes"], geo.stats["damper_n_nodes"])
        keys.add(case.model_digest)
    assert len(keys) == 2
    assert nodes[2.5][0] > nodes[5.0][0] and nodes[2.5][1] > nodes[5.0][1]
    # unset: the geometry file's size, no override (the cache keys of other studies stay)
    case = make_case("cylinder", 0.0, 30.0, dict(s, **{"contact-mesh-size": None}))
    assert "rig" not in (geometry_request(case)["overrides"] or {})


# ---- limits of a diverging ladder (synthetic values) ----------------------------------------

# the cone's friction energy at 30 N in phase on the paper rig against the contact mesh
# size, mm -> mJ (docs/notes/energy_convergence.md): the differences grow as it is refined
DIVERGING = {3.0: 22.29, 1.5: 24.30, 1.0: 25.88, 0.75: 29.03}


def test_a_diverging_ladder_is_not_extrapolated():
    h, q = list(DIVERGING), list(DIVERGING.values())
    est = richardson(h, q)
    assert not est.asymptotic and est.method == "finest level"
    assert est.value == est.finest == 29.03 and est.uncertainty is None
    # any three of its levels: never a limit
    for drop in range(4):
        e = richardson(h[:drop] + h[drop + 1 :], q[:drop] + q[drop + 1 :])
        assert not e.asymptotic and e.value == e.finest


@dataclass
class _Branch:
    failed: bool = False


@dataclass
class _Result:
    """The two things the limits read of a case: its branch's failure and its summary."""

    values: dict
    branch: _Branch = field(default_factory=_Branch)

    def summary(self):
        return self.values

    def peak_resolution(self):
        return {}  # no resolution known: the ladders are judged on their differences alone

    def refined_peak(self):
        return self.values


def _setting(knob: str, value, energy: dict[str, float]) -> Setting:
    st = Setting(f"{knob} {value}", {knob: value})
    st.results = {
        c: _Result({"peak_amplitude_mm": 0.1, "peak_frequency_hz": 400.0, "friction_energy_mj": e})
        for c, e in energy.items()
    }
    return st


def test_the_limit_of_every_knob_is_flagged_where_the_contact_ladder_diverges():
    """cone: the contact ladder diverges, so its limit is not trusted and not moved;
    wedge: the contact ladder converges (q = 64 + 0.2 h^2), and points per line does not
    reach it: its limit is the extrapolated one, trusted."""
    sizes = [3.0, 1.5, 1.0]
    lad = [
        _setting("contact-mesh-size", h, {"cone": DIVERGING[h], "wedge": 64.0 + 0.2 * h**2})
        for h in sizes
    ]
    pts = [_setting("points-per-line", n, {"cone": 20.0 + 40.0 / n, "wedge": 64.2})
           for n in (11, 17, 23)]  # fmt: skip
    ladders = {"contact-mesh-size": lad, "points-per-line": pts}
    skip = {("points-per-line", "wedge")}
    limits = ladder_limits(ladders, skip)
    cone = limits["contact-mesh-size"]["cone"]["friction_energy_mj"]
    assert not cone.asymptotic and cone.value == DIVERGING[1.0]
    wedge = limits["contact-mesh-size"]["wedge"]["friction_energy_mj"]
    assert wedge.asymptotic and wedge.value == pytest.approx(64.0, rel=1e-9)
    assert limits["points-per-line"]["wedge"]["friction_energy_mj"].reason == NOT_APPLICABLE
    ref = Setting("reference", {"contact-mesh-size": 1.0, "points-per-line": 23})
    ref.results = {c: lad[-1].results[c] for c in ("cone", "wedge")}
    comb = combined_limits(ref, ladders, limits)
    c, w = comb["cone"]["friction_energy_mj"], comb["wedge"]["friction_energy_mj"]
    assert not c["asymptotic"] and c["uncertainty"] is None and "contact-mesh-size" in c["reason"]
    # the points ladder (q = 20 + 40 h, h = 1/n) still corrects it: limit 20, finest 20 + 40/23
    assert c["value"] == pytest.approx(DIVERGING[1.0] - 40.0 / 23.0, rel=1e-9)
    assert w["asymptotic"] and w["value"] == pytest.approx(64.0, rel=1e-9)
    assert w["uncertainty"] == pytest.approx(1.25 * 0.2, rel=1e-6)


def test_no_error_is_relative_to_a_stuck_dampers_zero_energy():
    """The wedge at 9.6 N is stuck at the peak on the paper rig (0 mJ at the reference): an
    energy against 0 has no relative error; a level that slips there counts by its energy
    against the largest energy the reference has (64 mJ here), so a tiny slip (0.002 mJ)
    is a tiny error and a large one would not pass."""
    from workbench.post.fidelity import relative_errors, worst

    ref = _setting("nt", 64, {"stuck": 0.0, "slips": 64.0})
    same = _setting("nt", 32, {"stuck": 0.0, "slips": 64.0})
    other = _setting("nt", 16, {"stuck": 0.002, "slips": 60.8})
    e_same, e_other = relative_errors(same, ref), relative_errors(other, ref)
    assert e_same["stuck"]["friction_energy_mj"] == 0.0
    assert e_other["stuck"]["friction_energy_mj"] == pytest.approx(0.002 / 64.0 * 100.0)
    assert e_other["stuck"]["peak_amplitude_mm"] == 0.0  # the other quantities stay
    assert worst(e_other) == pytest.approx(5.0) == worst(e_other, "friction_energy_mj")
    other.results["slips"].branch.failed = True  # a failed case: no worst error at all
    assert worst(relative_errors(other, ref)) is None


# ---- the production model against the pad study's limit -------------------------------------

PADS = ROOT / "studies" / "fidelity_paper_rig_pads.toml"


def test_the_pad_study_is_the_point_study_on_the_pad_rig_with_the_main_job_as_production(
    tmp_path,
):
    """Same cases, base and knobs as the point-contact study, each ladder the point study's
    levels and one finer; its model is the pad rig; the production model (the main job's
    rig file) is solved at the base setting: the same solve, another model."""
    from workbench.studies.kinds.fidelity.compute import _Computer
    from workbench.studies.kinds.fidelity.ladders import plan_settings

    point, pads = load_study(STUDY, {}), load_study(PADS, {})
    assert Path(pads.geometry).name == "paper_rig_pads.toml"
    main = load_study(ROOT / "studies" / "paper_rig.toml", {})
    assert Path(pads.fidelity.production_geometry).resolve() == Path(main.geometry).resolve()
    cp, cq = _Computer(point, tmp_path / "p", False), _Computer(pads, tmp_path / "q", False)
    assert cp.names == CASES and cq.names[:6] == CASES and cq.base_values == cp.base_values
    assert cq.names[6:] == [  # the rest of the main job's table
        f"{d} {p} deg {f} N" for d, p in (("cylinder", 0), ("cylinder", 180), ("wedge", 180))
        for f in ("9.6", "30")
    ]  # fmt: skip
    sp_, lp = plan_settings(point, cp.dampers)
    sq, lq = plan_settings(pads, cq.dampers)
    assert sq[0].values == sp_[0].values and set(lq) == set(lp)
    for knob in lp:
        n = len(lp[knob])  # finer levels on the pad rig (the mesh three; nt the same)
        assert len(lq[knob]) == n + {"mesh-size": 3, "nt": 0}.get(knob, 1), knob
        # the pad study holds its points ladder at the contact ladder's finest size
        held = {"contact-mesh-size": 0.75} if knob == "points-per-line" else {}
        assert [s.values for s in lq[knob][:n]] == [dict(s.values, **held) for s in lp[knob]]
    prod = Setting("production", dict(sq[0].values), "production")
    on_pads, on_main = cq.cases(sq[0]), cq.cases(prod)
    for a, b, c in zip(on_pads, on_main, cp.cases(sp_[0]), strict=False):  # the point's six
        assert a.solve_params() == b.solve_params()
        assert a.model_digest != b.model_digest
        assert b.model_digest == c.model_digest  # the production model is the main job's


def test_the_production_model_is_judged_against_the_same_limit():
    """A converging contact ladder (q = 64 + 0.2 h^2, limit 64 +- 0.25): the base (1.5 mm,
    64.45) and a production model (63.2) get their errors against the same limit, the
    production's signed (below the limit: negative)."""
    from workbench.post.fidelity import limit_errors, relative_errors
    from workbench.studies.kinds.fidelity.report_base import base_vs_limit, rows

    lad = [_setting("contact-mesh-size", h, {"wedge": 64.0 + 0.2 * h**2}) for h in (3.0, 1.5, 1.0)]
    ladders = {"contact-mesh-size": lad}
    limits = ladder_limits(ladders)
    ref = lad[-1]
    comb = combined_limits(ref, ladders, limits)
    base = lad[1]
    base.role = "base"
    prod = _setting("contact-mesh-size", 1.5, {"wedge": 63.2})
    prod.role = "production"
    for st in (base, prod):
        st.errors, st.limit_errors = relative_errors(st, ref), limit_errors(st, comb)
    summary = {
        "limit": comb,
        "knob_limits": {
            k: {c: {q: e.as_dict() for q, e in qs.items()} for c, qs in lim.items()}
            for k, lim in limits.items()
        },
    }
    t = base_vs_limit(base, summary, ["wedge"], prod)["wedge"]["friction_energy_mj"]
    assert t["asymptotic"] and t["limit"] == pytest.approx(64.0, rel=1e-9)
    assert t["error_vs_limit_pct"] == pytest.approx(0.45 / 64.0 * 100, rel=1e-6)
    p = t["production"]
    assert p["value"] == 63.2
    assert p["signed_error_pct"] == pytest.approx(-0.8 / 64.0 * 100, rel=1e-6)
    assert p["error_vs_limit_pct"] == pytest.approx(0.8 / 64.0 * 100, rel=1e-6)
    assert p["vs_base_pct"] == pytest.approx((63.2 - 64.45) / 64.45 * 100, rel=1e-9)
    assert t["uncertainty_pct"] == pytest.approx(0.25 / 64.0 * 100, rel=1e-6)
    # without a production model the row has no production entry; the CSV a row more with it
    assert "production" not in base_vs_limit(base, summary, ["wedge"])["wedge"]["peak_amplitude_mm"]
    with_p = rows(base_vs_limit(base, summary, ["wedge"], prod))
    without = rows(base_vs_limit(base, summary, ["wedge"]))
    assert len(with_p) == len(without) + 3
    assert [r["error vs limit %"] for r in with_p if "production" in r["limit of"]][2] == (
        pytest.approx(-1.25, rel=1e-6)
    )


def test_a_bad_production_geometry_is_refused_before_any_case(tmp_path):
    """A production geometry file with a value out of range stops the study at once, naming
    the parameter, before a single case of the ladders is computed."""
    from workbench.studies.kinds.fidelity.compute import run_fidelity

    bad = tmp_path / "bad.toml"
    bad.write_text("[rig.mesh]\npad_mm = -1.0\n")
    spec = load_study(PADS, {"production-geometry": str(bad)})
    with pytest.raises(InputError) as e:
        run_fidelity(spec, tmp_path / "out")
    assert e.value.param == "rig.mesh.pad_mm" and "\n" not in str(e.value)
    assert not list((tmp_path / "out").rglob("*.h5"))  # nothing was computed
