"""A ladder that holds another knob away from the base (``points-contact-mesh-size``).

The element size at the contact points is capped by their spacing, so with the base's
contact mesh size a points-per-line level with more points also refines the mesh at the
lines, and the ladder's steps mix two knobs. Held at or below the finest level's spacing,
the size at the points is the same on every level; the knob's error of the base is read at
its pivot (the base's points at the held size) and its correction of the limit is taken
there. Checked here: the plan (every level at the held size, the pivot shared with the
contact ladder, the wedge's cases those of the contact ladder's level), the refusals of a
size the finest level would cap and of a ladder without the base's points, and, on a
synthetic model whose two knobs add with known limits, that the all-knob limit is exact and
each knob's error of the base is its own.
"""

from __future__ import annotations

import pytest

from tests.conftest import ROOT
from tests.test_fidelity_paper_rig import _setting
from workbench.errors import InputError
from workbench.post.fidelity import Setting, combined_limits, ladder_limits
from workbench.studies.engine.spec import load_study

PADS = ROOT / "studies" / "fidelity_paper_rig_pads.toml"


def _size_at_points(comp, st, damper: str) -> float:
    """The element size at the contact points of ``damper`` in ``st``'s model, mm (the
    contact mesh size, capped by the points' spacing and the global size, as the mesher
    gets it: workbench.geometry.build)."""
    from workbench.geometry.layout import make_layout
    from workbench.geometry.params import load_geometry_params
    from workbench.pipeline import geometry_request

    case = next(c for c in comp.cases(st) if c.damper == damper)
    r = geometry_request(case)
    gp = load_geometry_params(r["damper"], r["geometry_file"], r["overrides"], r["size_mm"])
    lay = make_layout(gp)
    return min(gp.rig.mesh.contact_size_mm, lay.contact_spacing, gp.rig.mesh.size_mm)


def test_the_pad_studys_points_ladder_keeps_the_mesh_at_the_lines(tmp_path):
    from workbench.studies.kinds.fidelity.compute import _Computer
    from workbench.studies.kinds.fidelity.ladders import ladder_pivot, plan_settings

    spec = load_study(PADS, {})
    assert spec.fidelity.points_contact_mesh_size == 0.75
    comp = _Computer(spec, tmp_path, False)
    settings, ladders = plan_settings(spec, comp.dampers)
    base, pts = settings[0], ladders["points-per-line"]
    assert [s.values["points-per-line"] for s in pts] == [11, 17, 23, 33, 45]
    for st in pts:  # the other knobs at the base but the contact size
        held = {"points-per-line": st.values["points-per-line"], "contact-mesh-size": 0.75}
        assert st.values == dict(base.values, **held)
        for d in ("cone", "cylinder"):
            assert _size_at_points(comp, st, d) == 0.75, (st.label, d)
    # the pivot is the contact ladder's finest level, one setting in both ladders
    pivot = ladder_pivot("points-per-line", pts, base)
    assert pivot is ladders["contact-mesh-size"][-1] and pivot.values["points-per-line"] == 23
    assert set(dict(pivot.members)) == {"contact-mesh-size", "points-per-line"}
    assert ladder_pivot("modes", ladders["modes"], base) is base
    # the wedge (no points per line): on every level its cases are the pivot's
    wedge = {c.digest for c in comp.cases(pivot) if c.damper == "wedge"}
    for st in pts:
        assert {c.digest for c in comp.cases(st) if c.damper == "wedge"} == wedge
    # without the held size the finest level refines the mesh at the lines: 45 points on
    # the cone are 1.17 mm apart, below the base's 1.5 mm
    plain = load_study(PADS, {"points-contact-mesh-size": None})
    cp = _Computer(plain, tmp_path / "plain", False)
    _, lp = plan_settings(plain, cp.dampers)
    sizes = [_size_at_points(cp, st, "cone") for st in lp["points-per-line"]]
    assert sizes[:3] == [1.5, 1.5, 1.5] and sizes[-1] == pytest.approx(1.167, abs=1e-3)


@pytest.mark.parametrize(
    "over, param",
    [
        ({"points-contact-mesh-size": 1.2}, "points-contact-mesh-size"),  # 45 points cap it
        ({"levels-points-per-line": [11, 33, 45]}, "levels-points-per-line"),  # no pivot
        ({"points-contact-mesh-size": 0.1}, "points-contact-mesh-size"),  # out of range
    ],
)
def test_a_held_size_the_ladder_cannot_keep_is_refused(over, param):
    from workbench.studies.kinds.fidelity.ladders import plan_settings

    with pytest.raises(InputError) as e:
        spec = load_study(PADS, over)
        plan_settings(spec, ["cone", "cylinder", "wedge"])
    assert e.value.param == param and "\n" not in str(e.value)


def test_a_held_ladder_corrects_at_its_pivot_and_errs_by_its_own_knob():
    """q = 10 + 0.1 h^2 + 20 / n^2 (h the contact size in mm, n points): the knobs add, the
    limit is 10. The base is 1.5 mm, 23 points; the contact ladder 3 / 1.5 / 1 / 0.75 mm at
    23 points, the points ladder 11 / 17 / 23 / 33 at 0.75 mm (its pivot: 23 at 0.75 mm,
    the contact ladder's finest level); the reference 0.75 mm and 33 points. The all-knob
    limit is 10 to round-off; the points knob's error of the base is 20/23^2 against its
    limit, not the contact size's 0.1 (1.5^2 - 0.75^2) on top of it, which reading the
    base against the points limit would add."""
    from workbench.post.fidelity import limit_errors, relative_errors
    from workbench.studies.kinds.fidelity.compute import _knob_limits
    from workbench.studies.kinds.fidelity.report_base import base_vs_limit

    def q(h: float, n: int) -> float:
        return 10.0 + 0.1 * h**2 + 20.0 / n**2

    def setting(label: str, h: float, n: int, role: str = "knob") -> Setting:
        st = _setting("contact-mesh-size", h, {"cone": q(h, n)})
        st.label, st.values, st.role = label, {"contact-mesh-size": h, "points-per-line": n}, role
        return st

    base = setting("base", 1.5, 23, "base")
    contact = [setting("contact 3", 3.0, 23), base, setting("contact 1", 1.0, 23),
               setting("contact 0.75", 0.75, 23)]  # fmt: skip
    pivot = contact[-1]
    points = [setting(f"{n} at 0.75", 0.75, n) for n in (11, 17)] + [pivot]
    points.append(setting("33 at 0.75", 0.75, 33))
    ladders = {"contact-mesh-size": contact, "points-per-line": points}
    ref = setting("reference", 0.75, 33, "reference")
    limits = ladder_limits(ladders)
    comb = combined_limits(ref, ladders, limits)
    e = comb["cone"]["friction_energy_mj"]
    assert e["trusted"] and e["value"] == pytest.approx(10.0, abs=1e-9)
    for st in (base, ref):
        st.errors, st.limit_errors = relative_errors(st, ref), limit_errors(st, comb)
    summary = {"limit": comb, "knob_limits": _knob_limits(limits, ladders, base)}
    assert summary["knob_limits"]["points-per-line"]["cone"]["friction_energy_mj"][
        "pivot_label"] == "contact 0.75"  # fmt: skip
    row = base_vs_limit(base, summary, ["cone"])["cone"]["friction_energy_mj"]
    assert row["error_vs_limit_pct"] == pytest.approx((q(1.5, 23) - 10.0) / 10.0 * 100, rel=1e-9)
    k = row["knobs"]
    # each knob's limit: 10 + the other knob's share at that ladder's held values
    assert k["points-per-line"]["limit"] == pytest.approx(10.0 + 0.1 * 0.75**2, rel=1e-9)
    assert k["contact-mesh-size"]["limit"] == pytest.approx(10.0 + 20.0 / 23**2, rel=1e-9)
    assert k["points-per-line"]["at"] == "contact 0.75" and k["contact-mesh-size"]["at"] == "base"
    lim_p = 10.0 + 0.1 * 0.75**2
    assert k["points-per-line"]["error_vs_limit_pct"] == pytest.approx(
        20.0 / 23**2 / lim_p * 100, rel=1e-9
    )
    lim_c = 10.0 + 20.0 / 23**2
    assert k["contact-mesh-size"]["error_vs_limit_pct"] == pytest.approx(
        0.1 * 1.5**2 / lim_c * 100, rel=1e-9
    )
