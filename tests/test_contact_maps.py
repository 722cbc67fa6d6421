"""Contact status and friction energy painted on a real (coarse) cone mesh, off-screen.

The damper mesh is built once per module with the geometry stage (coarse
sizes, about 2 s); the cases are synthetic (:mod:`tests.synthetic`) but sit
on the geometry's own contact points.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

from tests.conftest import assert_nonblank
from tests.synthetic import synthetic_case, synthetic_study
from workbench.errors import InputError
from workbench.render.contact_maps import render_contact_maps
from workbench.render.palette import STATUS_COLORS
from workbench.render.sections import build_sections

COARSE = {"rig": {"mesh": {"size_mm": 10.0, "contact_size_mm": 2.5, "damper_size_mm": 5.0}}}
SCENE_ROWS = 0.78  # the damper is drawn in the top part of the picture; the legend below


@pytest.fixture(scope="module")
def cone(tmp_path_factory):
    from workbench.geometry import build_geometry

    out = tmp_path_factory.mktemp("cone")
    return build_geometry("cone", out, overrides=COARSE), out


def _case(geo, force_n: float):
    return synthetic_case("cone", 0.0, force_n, points=geo.contact.points, side=geo.contact.side)


def _pixels_of(png, hex_color: str, rows: float = SCENE_ROWS, tol: float = 12 / 255) -> int:
    """Number of pixels within ``tol`` of a colour in the top ``rows`` of the picture."""
    import matplotlib.colors as mc
    import matplotlib.image as mpimg

    img = np.asarray(mpimg.imread(str(png)), dtype=float)[..., :3]
    img = img[: int(rows * img.shape[0])]
    target = np.array(mc.to_rgb(hex_color))
    return int(np.sum(np.all(np.abs(img - target) <= tol, axis=-1)))


def test_status_colours_follow_the_pairs(cone, tmp_path):
    geo, gdir = cone
    slipping = _case(geo, 30.0)  # in-phase cone: the ends slip, the middle stays stuck
    i = slipping.peak_index
    st = slipping.branch.status[i]
    assert (st == 1).sum() > 5 and (st == 0).sum() > 5 and not (st >= 2).any()
    status_png, energy_png = render_contact_maps(slipping, gdir, tmp_path / "slip")
    assert status_png.name == "slip_status.png" and energy_png.name == "slip_energy.png"
    assert_nonblank(status_png)
    assert_nonblank(energy_png)
    stick_slip = _pixels_of(status_png, STATUS_COLORS[1])
    stuck = _pixels_of(status_png, STATUS_COLORS[0])
    assert stick_slip > 500 and stuck > 300, (stick_slip, stuck)
    assert _pixels_of(status_png, STATUS_COLORS[2]) == 0  # no pair separates

    # at the lowest force every pair sticks: no stick-slip colour on the damper
    stuck_case = _case(geo, 0.096)
    assert not stuck_case.branch.status[stuck_case.peak_index].any()
    png, _ = render_contact_maps(stuck_case, gdir, tmp_path / "stuck")
    assert _pixels_of(png, STATUS_COLORS[1]) < 20
    assert _pixels_of(png, STATUS_COLORS[0]) > stuck


def test_energy_picture_changes_with_the_energies(cone, tmp_path):
    geo, gdir = cone
    case = _case(geo, 30.0)
    _, a = render_contact_maps(case, gdir, tmp_path / "a")
    # the same case with no dissipation on platform 2's line paints those spheres at the floor
    quiet = copy.deepcopy(case)
    quiet.branch.friction_energy[:, geo.contact.side == 1] = 0.0
    _, b = render_contact_maps(quiet, gdir, tmp_path / "b")
    import matplotlib.image as mpimg

    ia, ib = (np.asarray(mpimg.imread(str(p)))[..., :3] for p in (a, b))
    assert ia.shape == ib.shape
    changed = np.any(np.abs(ia - ib) > 0.1, axis=-1)
    assert changed.mean() > 2e-3, changed.mean()
    # only the upper half of the damper changed (platform 2's line, x > 0, is drawn on top)
    # platform 2's pairs are now "stuck / 0": grey, not the bottom of the colour map
    from workbench.render.contact_maps import STUCK_COLOR

    assert _pixels_of(b, STUCK_COLOR) > 1.3 * _pixels_of(a, STUCK_COLOR) + 500
    rows = np.flatnonzero(changed.any(axis=1))
    top = int(SCENE_ROWS * ia.shape[0])
    scene = changed[:top]
    upper, lower = scene[: top // 2].sum(), scene[top // 2 :].sum()
    assert upper > 10 * max(lower, 1), (upper, lower, rows.min(), rows.max())


def test_contact_maps_refuse_bad_input(cone, tmp_path):
    geo, gdir = cone
    case = _case(geo, 30.0)
    with pytest.raises(InputError, match="damper.msh"):
        render_contact_maps(case, tmp_path / "nowhere", tmp_path / "x")
    bad = copy.deepcopy(case)
    bad.points = bad.points[:-1]
    with pytest.raises(InputError, match="one point per pair"):
        render_contact_maps(bad, gdir, tmp_path / "x")
    with pytest.raises(InputError, match="point"):
        render_contact_maps(case, gdir, tmp_path / "x", point=10**6)


def test_sections_paint_the_dampers_given(cone, tmp_path):
    geo, gdir = cone
    r = synthetic_study(
        dampers=("cone", "cylinder"),
        phases=(180.0,),
        forces=(9.6, 30.0),
        layouts={"cone": (geo.contact.points, geo.contact.side)},
    )
    sections = build_sections(r, tmp_path, geometry_dirs={"cone": gdir})
    maps = next(s for s in sections if s["id"] == "contact-maps")
    paths = [f["path"] for f in maps["figures"]]
    # the cone (its geometry given) at the highest force; not the cylinder
    assert paths == [
        "figures/contact_out-of-phase_cone_status.png",
        "figures/contact_out-of-phase_cone_energy.png",
    ]
    assert all("F = 30 N" in f["caption"] for f in maps["figures"])
    for p in paths:
        assert_nonblank(tmp_path / p)


def test_energy_scale_is_shared_and_ignores_round_off():
    from workbench.render.contact_maps import energy_scale

    # round-off (1e-18, negative) is below the floor; the rest spans 1e-3..2: log
    lo, hi, log = energy_scale([np.array([1e-18, -1e-20, 2.0]), np.array([1e-3, 0.5])])
    assert (lo, hi, log) == (1e-3, 2.0, True)
    assert energy_scale([np.array([0.5, 1.0])]) == (0.0, 1.0, False)
    assert energy_scale([np.zeros(3)]) == (0.0, 1.0, False)
