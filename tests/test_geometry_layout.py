"""Seating the dampers in the groove (pure numpy, no gmsh): tangency, frames, weights, checks."""

from __future__ import annotations

import dataclasses
import math
import tomllib

import numpy as np
import pytest

from workbench.errors import InputError
from workbench.geometry import load_geometry_params, make_layout
from workbench.geometry.params import (
    DEFAULT_DIR,
    ConeParams,
    CylinderParams,
    RigParams,
    WedgeParams,
)

# Contact points are computed in mm from closed-form expressions; 1e-6 mm
# (= 1e-9 m, the matching tolerance of the brief) is far above round-off
# (~1e-13 mm for coordinates of ~200 mm).
TOL_MM = 1e-6


# A wide groove (80 mm between the blades, 4 mm tip gap) that seats every cone
# of the angle sweeps below, so those tests are about tangency, not fitting
# (platforms high on the blades: at beta = 20 deg their inclined faces are
# 104 mm deep).
WIDE = {
    "blade": {"gap_mm": 80.0},
    "platform": {"overhang_mm": 38.0, "width_mm": 80.0, "top_below_tip_mm": 60.0},
    "base": {"length_mm": 200.0, "width_mm": 100.0},
}


def wide(**platform):
    return {**WIDE, "platform": {**WIDE["platform"], **platform}}


def layout(damper: str, **tables):
    return make_layout(load_geometry_params(damper, overrides=tables or None))


def cone_radius_error(lay, p: np.ndarray) -> np.ndarray:
    """Distance of points from the cone surface along the radial direction, mm."""
    pl = lay.damper
    w = p - pl["apex"]
    ax = w @ pl["axis"]
    rad = np.linalg.norm(w - ax[:, None] * pl["axis"][None, :], axis=1)
    return rad - ax * math.tan(pl["semi_angle"])


@pytest.mark.parametrize("beta", [30.0, 45.0, 60.0])
@pytest.mark.parametrize("alpha", [5.0, 10.0, 15.0])
def test_cone_touches_both_planes_along_a_generator(beta, alpha):
    lay = layout(
        "cone",
        rig=wide(angle_deg=beta),
        cone={"semi_angle_deg": alpha, "r1_mm": 8.0, "length_mm": 20.0},
    )
    pts = lay.points
    # every contact point is on the cone surface and on its own platform plane
    assert np.abs(cone_radius_error(lay, pts)).max() < TOL_MM
    for k in range(2):
        assert np.abs(lay.plane_distance(pts[lay.side == k], k)).max() < TOL_MM
    # and the whole cone lies on the damper side of both planes (tangent, not cutting):
    # sample the frustum surface densely; the smallest signed distance is 0 (the generator)
    pl = lay.damper
    a = pl["axis"]
    e1 = np.array([1.0, 0.0, 0.0])
    e2 = np.cross(a, e1)
    t = np.linspace(0.0, 1.0, 41)[:, None]
    phi = np.linspace(0.0, 2 * np.pi, 721)[None, :]
    h = pl["r1"] / math.tan(pl["semi_angle"]) + t * pl["length"]
    r = h * math.tan(pl["semi_angle"])
    surf = (
        pl["apex"][None, None, :]
        + h[..., None] * a
        + r[..., None] * (np.cos(phi)[..., None] * e1 + np.sin(phi)[..., None] * e2)
    )
    for k in range(2):
        d = lay.plane_distance(surf.reshape(-1, 3), k)
        assert d.min() > -TOL_MM  # never inside the platform
        assert d.min() < 1e-3 * pl["r2"]  # touches it (sampling resolution: 0.5 deg)


@pytest.mark.parametrize("beta", [20.0, 36.0, 45.0, 60.0, 70.0])
@pytest.mark.parametrize("alpha", [2.0, 10.0, 18.0])
def test_cone_tilt_matches_the_paper_relations(beta, alpha):
    """gamma from the layout obeys the paper's eqs (1)-(3) for the conical damper."""
    lay = layout(
        "cone",
        rig=wide(angle_deg=beta),
        cone={"semi_angle_deg": alpha, "r1_mm": 12.0, "length_mm": 10.0},
    )
    g = math.radians(lay.notes["gamma_deg"])
    ac, b = math.radians(alpha), math.radians(beta)
    eq3 = math.acos(
        math.sqrt(1 - math.tan(ac) ** 2 / math.tan(b) ** 2) / math.sqrt(math.tan(ac) ** 2 + 1)
    )
    assert g == pytest.approx(eq3, abs=1e-12)
    a1 = math.atan(math.tan(b) * math.cos(g))  # eq (1), second line
    assert math.tan(ac) == pytest.approx(math.tan(g) * math.sin(a1), rel=1e-12)
    # the axis tilts in the y-z plane only
    assert lay.damper["axis"][0] == 0.0


def test_cone_alpha_not_below_beta_is_refused_with_the_reason():
    for alpha in (45.0, 50.0):
        with pytest.raises(InputError) as e:
            layout("cone", cone={"semi_angle_deg": alpha})
        assert e.value.param == "cone.semi_angle_deg"
        assert "rig.platform.angle_deg = 45" in str(e.value)
        assert "vertical" in str(e.value)


def test_cylinder_is_tangent_and_parallel_to_y():
    lay = layout("cylinder")
    R = lay.damper["radius"]
    c = lay.damper["center"]
    for k in range(2):
        # the axis is R from each plane, on the damper side
        assert lay.plane_distance(c, k) == pytest.approx(R, abs=TOL_MM)
        p = lay.points[lay.side == k]
        assert np.abs(lay.plane_distance(p, k)).max() < TOL_MM
        assert np.abs(np.hypot(p[:, 0] - c[0], p[:, 2] - c[2]) - R).max() < TOL_MM
        assert np.all(np.diff(p[:, 1]) > 0)  # ordered from -y to +y


def test_default_cylinder_radius_is_the_cone_mean_radius():
    cone = load_geometry_params("cone").shape
    cyl = load_geometry_params("cylinder").shape
    r_mean = cone.r1_mm + 0.5 * cone.length_mm * math.tan(math.radians(cone.semi_angle_deg))
    assert cyl.radius_mm == pytest.approx(r_mean, abs=1e-4)  # the file gives 4 decimals
    assert cyl.length_mm == cone.length_mm


@pytest.mark.parametrize("damper", ["cone", "cylinder", "wedge"])
def test_frames_weights_and_order(damper):
    lay = layout(damper)
    F = lay.frames
    n = len(lay.points)
    # orthonormal and right-handed
    assert np.allclose(np.einsum("pij,pkj->pik", F, F), np.eye(3)[None], atol=1e-12)
    assert np.allclose(np.linalg.det(F), 1.0, atol=1e-12)
    # n is the platform normal, pointing down into the damper and toward the other blade
    for k in range(2):
        nk = F[lay.side == k, 2]
        assert np.allclose(nk, lay.normals[k][None], atol=0)
        assert np.all(nk[:, 2] < 0) and np.all(nk[:, 0] * (1 if k == 0 else -1) > 0)
    # side 0 first, then side 1, same count
    assert np.all(lay.side[: n // 2] == 0) and np.all(lay.side[n // 2 :] == 1)
    # tributary weights sum to the line length / face area on each side
    for k in range(2):
        assert lay.weight[lay.side == k].sum() == pytest.approx(lay.extent, rel=1e-12)
    if lay.kind == "line":
        # t1 runs along the line, in the order of the points
        for k in range(2):
            p = lay.points[lay.side == k]
            step = np.diff(p, axis=0)
            dirs = step / np.linalg.norm(step, axis=1)[:, None]
            assert np.allclose(dirs, F[lay.side == k, 0][1:], atol=1e-9)


def test_cone_order_is_large_end_first():
    lay = layout("cone")
    for k in range(2):
        r = np.linalg.norm(
            np.cross(lay.points[lay.side == k] - lay.damper["apex"], lay.damper["axis"]), axis=1
        )
        assert np.all(np.diff(r) < 0)  # distance from the axis = local radius, decreasing


def test_wedge_staggered_grid_gives_the_papers_146_points():
    lay = layout("wedge")
    assert lay.n_pairs == 146
    for k in range(2):
        p = lay.points[lay.side == k]
        sig = lay.sigma(p, k)
        rows = np.unique(np.round(sig, 9))
        assert len(rows) == 5
        counts = [int(np.sum(np.isclose(sig, s))) for s in rows[::-1]]  # row 0 is the lowest
        assert counts == [15, 14, 15, 14, 15]
        assert np.abs(lay.plane_distance(p, k)).max() < TOL_MM
        # row-major: within a row y increases, rows go up the slope
        assert np.all(np.diff(sig) <= 1e-12)
    # 2 x 73 with other counts: 4 rows of 10/9/10/9 = 38 per face
    lay = layout("wedge", wedge={"n_contact_rows": 4, "n_contact_per_row": 10})
    assert lay.n_pairs == 76


@pytest.mark.parametrize(
    "damper,volume",
    [
        (
            "cone",
            lambda p: (
                math.pi
                * p.length_mm
                / 3
                * (
                    p.r1_mm**2
                    + p.r1_mm * (p.r1_mm + p.length_mm * math.tan(math.radians(p.semi_angle_deg)))
                    + (p.r1_mm + p.length_mm * math.tan(math.radians(p.semi_angle_deg))) ** 2
                )
            ),
        ),
        ("cylinder", lambda p: math.pi * p.radius_mm**2 * p.length_mm),
    ],
)
def test_analytic_volumes(damper, volume):
    lay = layout(damper)
    assert lay.volume == pytest.approx(volume(lay.params.shape), rel=1e-12)


def test_wedge_volume_from_its_section():
    lay = layout("wedge")
    p = lay.params.shape
    b = lay.beta
    top = p.top_width_mm
    bottom = top + 2 * p.face_width_mm * math.sin(b)
    trapezoid = 0.5 * (top + bottom) * p.face_width_mm * math.cos(b)
    assert lay.volume == pytest.approx(
        (trapezoid + bottom * p.skirt_height_mm) * p.length_mm, rel=1e-12
    )


@pytest.mark.parametrize(
    "damper,tables,param",
    [
        ("cone", {"cone": {"length_mm": 80.0}}, "cone.length_mm"),  # longer than the platform
        ("cone", {"cone": {"r1_mm": 2.0}}, "cone.r1_mm"),  # small end above the tip edge
        ("cone", {"cone": {"r1_mm": 18.0, "length_mm": 20.0}}, "cone.length_mm"),  # hits blades
        ("cylinder", {"cylinder": {"radius_mm": 3.0}}, "cylinder.radius_mm"),
        ("cylinder", {"cylinder": {"radius_mm": 25.0}}, "cylinder.radius_mm"),
        ("cylinder", {"cylinder": {"length_mm": 110.0}}, "cylinder.length_mm"),
        ("wedge", {"wedge": {"top_width_mm": 4.0}}, "wedge.top_width_mm"),
        ("wedge", {"wedge": {"face_width_mm": 30.0}}, "wedge.face_width_mm"),
        ("wedge", {"wedge": {"length_mm": 99.5}}, "wedge.length_mm"),
        ("cone", {"rig": {"platform": {"overhang_mm": 20.0}}}, "rig.platform.overhang_mm"),
        (
            "cone",
            {"rig": {"platform": {"top_below_tip_mm": 300.0}}},
            "rig.platform.top_below_tip_mm",
        ),
        ("cone", {"rig": {"base": {"length_mm": 60.0}}}, "rig.base.length_mm"),
        ("cone", {"rig": {"response": {"height_mm": 320.0}}}, "rig.response.height_mm"),
        (
            "cone",
            {
                "rig": {
                    "blade": {"height_mm": 25.0},
                    "excitation": {"height_mm": 5.0},
                    "platform": {"top_below_tip_mm": 0.0},
                    "response": {"height_mm": 10.0},
                }
            },
            "rig.blade.height_mm",
        ),  # hits the base
    ],
)
def test_dampers_that_do_not_fit_are_refused_naming_the_parameter(damper, tables, param):
    with pytest.raises(InputError) as e:
        layout(damper, **tables)
    assert e.value.param == param, str(e.value)
    assert "expected" in str(e.value)


@pytest.mark.parametrize(
    "damper,tables,param",
    [
        ("cone", {"rig": {"mesh": {"size_mm": 0.0}}}, "rig.mesh.size_mm"),
        ("cone", {"rig": {"mesh": {"size_mm": -2.0}}}, "rig.mesh.size_mm"),
        ("cone", {"rig": {"mesh": {"contact_size_mm": 0.0}}}, "rig.mesh.contact_size_mm"),
        ("wedge", {"rig": {"mesh": {"damper_size_mm": -1.0}}}, "rig.mesh.damper_size_mm"),
        ("cone", {"cone": {"r1_mm": 0.0}}, "cone.r1_mm"),
        ("wedge", {"wedge": {"length_mm": -40.0}}, "wedge.length_mm"),
        ("cone", {"cone": {"n_contact_points": 1}}, "cone.n_contact_points"),
        ("cylinder", {"cylinder": {"n_contact_points": 0}}, "cylinder.n_contact_points"),
        ("wedge", {"wedge": {"n_contact_per_row": 1}}, "wedge.n_contact_per_row"),
        ("cone", {"cone": {"n_contact_points": 2.5}}, "cone.n_contact_points"),
        ("cone", {"rig": {"platform": {"angle_deg": 95.0}}}, "rig.platform.angle_deg"),
        ("cone", {"cone": {"semi_angel_deg": 12.0}}, "cone.semi_angel_deg"),  # typo -> hint
        ("cone", {"rig": {"mesh": {"size_mm": 0.05}}}, "rig.mesh.size_mm"),  # far too many cells
        ("cone", {"rig": {"fit": {"clearance_mm": 0.0}}}, "rig.fit.clearance_mm"),
        # slivers: a step between faces is either absent or at least rig.fit.min_feature_mm
        ("cone", {"rig": {"platform": {"tip_thickness_mm": 0.2}}}, "rig.platform.tip_thickness_mm"),
        ("cone", {"rig": {"platform": {"top_below_tip_mm": 0.2}}}, "rig.platform.top_below_tip_mm"),
        ("cone", {"rig": {"platform": {"width_mm": 100.6}}}, "rig.platform.width_mm"),
        ("cone", {"rig": {"base": {"width_mm": 50.4}}}, "rig.base.width_mm"),
        ("cone", {"rig": {"base": {"length_mm": 70.2}}}, "rig.base.length_mm"),
        ("wedge", {"wedge": {"skirt_height_mm": 0.2}}, "wedge.skirt_height_mm"),
    ],
)
def test_bad_values_are_refused_naming_the_parameter(damper, tables, param):
    with pytest.raises(InputError) as e:
        layout(damper, **tables)
    assert e.value.param == param, str(e.value)


def test_unknown_key_and_table_get_a_hint():
    with pytest.raises(InputError, match="did you mean 'semi_angle_deg'"):
        layout("cone", cone={"semi_angel_deg": 12.0})
    with pytest.raises(InputError, match="did you mean 'rig'"):
        load_geometry_params("cone", overrides={"rigg": {}})
    with pytest.raises(InputError, match="did you mean 'cone'"):
        load_geometry_params("cnoe")


def test_size_override_and_file_layering(tmp_path):
    f = tmp_path / "g.toml"
    f.write_text("[cone]\nsemi_angle_deg = 12.0\n[rig.platform]\nangle_deg = 50.0\n")
    gp = load_geometry_params("cone", f, {"cone": {"r1_mm": 9.0}}, size_mm=7.5)
    assert gp.shape.semi_angle_deg == 12.0 and gp.shape.r1_mm == 9.0
    assert gp.rig.platform.angle_deg == 50.0 and gp.rig.mesh.size_mm == 7.5
    assert gp.shape.length_mm == 40.0  # untouched defaults survive the merge
    with pytest.raises(InputError) as e:
        load_geometry_params("cone", size_mm=0.0)
    assert e.value.param == "size_mm"


@pytest.mark.parametrize(
    "name,record",
    [
        ("rig", RigParams),
        ("cone", ConeParams),
        ("cylinder", CylinderParams),
        ("wedge", WedgeParams),
    ],
)
def test_files_and_record_defaults_agree(name, record):
    """The TOML files are what users read; the dataclass defaults must say the same."""
    with open(DEFAULT_DIR / f"{name}.toml", "rb") as fh:
        data = tomllib.load(fh)[name]
    assert data == dataclasses.asdict(record())


def test_steps_below_the_cad_tolerance_are_closed():
    """A 1e-9 mm step is no step: the faces are drawn flush instead of as a sliver."""
    lay = layout(
        "wedge",
        wedge={"skirt_height_mm": 1e-9},
        rig={
            "base": {"width_mm": 100.0 + 1e-9},
            "platform": {"top_below_tip_mm": 1e-9, "width_mm": 100.0 - 1e-9},
        },
    )
    assert len(lay.damper["section_xz"]) == 4  # no vertical sides
    assert lay.base.dy == 100.0 and lay.platform_y == (-50.0, 50.0)
    assert lay.platform_xz[0][:, 1].max() == lay.blades[0].z0 + lay.blades[0].dz
