"""Property: any parameters in the allowed ranges mesh with matched pairs or get a clear InputError.

Never another exception, never a hang: each example runs under a watchdog
(faulthandler) that kills the process with a traceback if gmsh hangs.
Coarse meshes and few examples keep it to some 20 s.
"""

from __future__ import annotations

import faulthandler
import math
import os

import numpy as np
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from workbench.errors import InputError
from workbench.geometry import build_geometry

WATCHDOG_S = 120.0  # one coarse build takes 1-3 s; anything near this is a hang
# a longer search: UPD_PROPERTY_EXAMPLES=300 python -m pytest tests/test_geometry_property.py
EXAMPLES = int(os.environ.get("UPD_PROPERTY_EXAMPLES", "12"))


def _f(lo: float, hi: float):
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False)


@st.composite
def step(draw, hi: float):
    """A step between two faces: a sliver (refused below 0.5 mm) 1 in 10, else none or real."""
    kind = draw(st.integers(0, 9))
    if kind == 0:
        return draw(_f(1e-12, 0.6))
    return 0.0 if kind < 5 else draw(_f(0.5, hi))


@st.composite
def cases(draw):
    """A rig and a damper drawn so that about half fit the groove and half do not.

    The damper's contact positions are drawn as fractions of the inclined
    platform face (slope distances between the tip edge and the root), then
    perturbed by up to 30 %, so both sides of every fit check are explored.
    """
    beta = draw(_f(15.0, 75.0))
    gap = draw(_f(25.0, 60.0))
    overhang = gap / 2 * draw(_f(0.3, 0.99))
    thickness = draw(_f(8.0, 25.0))
    rig = {
        "blade": {"gap_mm": gap, "thickness_mm": thickness},
        "platform": {
            "angle_deg": beta,
            "overhang_mm": overhang,
            "tip_thickness_mm": draw(_f(0.3, 10.0)),
            "top_below_tip_mm": draw(step(20.0)),
            "width_mm": 50.0 + 2 * draw(step(10.0)) * draw(st.sampled_from([-1, 1])),
        },
        "base": {
            "length_mm": gap + 2 * thickness + 2 * draw(step(20.0)),
            "width_mm": 50.0 + 2 * draw(step(10.0)),
        },
        "mesh": {
            "size_mm": draw(_f(8.0, 14.0)),
            "contact_size_mm": draw(_f(1.5, 4.0)),
            "damper_size_mm": draw(_f(3.0, 8.0)),
            "refine_distance_mm": draw(_f(4.0, 15.0)),
        },
    }
    b = math.radians(beta)
    s_tip, s_root = (gap / 2 - overhang) / math.sin(b), gap / 2 / math.sin(b)
    lo, hi = s_tip + 1.0, s_root - 1.0  # the face less the default edge margin
    sig1 = lo + (hi - lo) * draw(_f(-0.15, 0.7))  # upper end of the contacts
    sig2 = max(lo + (hi - lo) * draw(_f(0.3, 1.15)), sig1 + 0.5)  # lower end
    kind = draw(st.sampled_from(["cone", "cylinder", "wedge"]))
    n = draw(st.integers(2, 30))
    length = rig["platform"]["width_mm"] * draw(_f(0.2, 1.1))
    if kind == "cone":
        alpha = draw(_f(1.0, min(40.0, beta + 5.0)))
        a = math.radians(alpha)
        r1 = sig1 * math.tan(b) * math.cos(a)
        shape = {
            "semi_angle_deg": alpha,
            "r1_mm": max(r1, 0.5),
            "length_mm": length,
            "n_contact_points": n,
        }
    elif kind == "cylinder":
        shape = {
            "radius_mm": max(sig1 * math.tan(b), 0.5),
            "length_mm": length,
            "n_contact_points": n,
        }
    else:
        shape = {
            "top_width_mm": max(2 * sig1 * math.sin(b), 0.5),
            "face_width_mm": sig2 - sig1,
            "length_mm": length,
            "skirt_height_mm": draw(step(8.0)),
            "n_contact_rows": draw(st.integers(2, 6)),
            "n_contact_per_row": draw(st.integers(2, 16)),
        }
    return rig, {kind: shape}


@settings(
    max_examples=EXAMPLES,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(case=cases())
def test_mesh_or_clear_error(tmp_path_factory, case):
    rig, shape = case
    damper = next(iter(shape))
    out = tmp_path_factory.mktemp("prop")
    faulthandler.dump_traceback_later(WATCHDOG_S, exit=True)
    try:
        geo = build_geometry(damper, out, overrides={"rig": rig, **shape})
    except InputError as e:
        # the clear error: names a parameter of the files (or the size) and what is allowed
        assert e.param.startswith(("rig.", f"{damper}.")), str(e)
        assert "expected" in str(e)
        assert not (out / "geometry.h5").exists()
        event(f"refused: {e.param}")
        return
    finally:
        faulthandler.cancel_dump_traceback_later()
    event(f"meshed: {damper}")
    assert geo.stats["max_pair_gap_m"] <= 1e-9
    assert geo.stats["max_point_offset_m"] <= 1e-9
    n = shape[damper].get("n_contact_points")
    if n is not None:
        assert geo.contact.n_pairs == 2 * n
    for k in range(2):
        w = geo.contact.weight[geo.contact.side == k]
        assert np.all(w > 0)
    assert geo.damper_volume_m3 > 0
