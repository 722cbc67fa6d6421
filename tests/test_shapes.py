"""The registry of damper shapes: every shape is one module plus its TOML, found by name.

The three shapes of the paper are registered in order; each one's TOML
agrees with its record; the study options, the figures and the CLI list the
registry's names; and a new shape module dropped into the package (here a
cylinder under another name, written to a temporary folder) is found, seated
and styled without any other edit.
"""

from __future__ import annotations

import dataclasses
import shutil
import sys
import tomllib

import numpy as np
import pytest

from workbench.geometry import load_geometry_params, make_layout, shapes
from workbench.geometry import params as gparams


def test_the_three_shapes_are_registered_in_order():
    assert shapes.names()[:3] == ("cone", "cylinder", "wedge")
    assert gparams.DAMPERS == shapes.names()
    for s in shapes.all_shapes():
        assert s.contact in ("line", "face")
        assert gparams.DAMPER_RECORDS[s.name] is s.params


@pytest.mark.parametrize("name", shapes.names())
def test_each_shape_has_its_toml_with_the_record_defaults(name):
    shape = shapes.get(name)
    with open(gparams.DEFAULT_DIR / f"{name}.toml", "rb") as fh:
        data = tomllib.load(fh)[name]
    assert data == dataclasses.asdict(shape.params())
    for option, (field, kind) in shape.study_options.items():
        assert hasattr(shape.params(), field), (option, field)
        assert kind in (int, float)


def test_the_damper_list_comes_from_the_registry():
    from workbench.render.study_style import DAMPER_STYLE
    from workbench.studies.engine.spec import BY_NAME

    assert tuple(BY_NAME["dampers"].default) == shapes.names()
    assert BY_NAME["dampers"].choices == shapes.names()
    assert set(DAMPER_STYLE) == set(shapes.names())


def test_an_unknown_damper_is_refused_with_the_list():
    from workbench.errors import InputError

    with pytest.raises(InputError) as e:
        shapes.get("cnoe")
    assert e.value.param == "damper" and "cone" in str(e.value)


ROD = '''"""A test shape: a cylinder under another name."""
from dataclasses import dataclass

from workbench.config import param
from workbench.geometry.shapes import DamperShape, cylinder


@dataclass(frozen=True)
class RodParams:
    radius_mm: float = param(13.5265, "radius R, mm", lo=0.0, lo_open=True)
    length_mm: float = param(40.0, "length L along y, mm", lo=0.0, lo_open=True)
    n_contact_points: int = param(23, "contact points per contact line", lo=2, hi=400)


SHAPE = DamperShape(name="rod", params=RodParams, contact="line", seat=cylinder.seat,
                    fit_blame=cylinder.fit_blame, hit_blame=cylinder.hit_blame,
                    draw=cylinder.draw, style=("#123456", "-.", "D"),
                    study_options={"points-per-line": ("n_contact_points", int)}, order=50)
'''


@pytest.fixture
def rod(tmp_path, monkeypatch):
    """A shape module 'rod' and its TOML, outside the repository, registered for one test."""
    import workbench.render.study_style  # noqa: F401 - built with the three shapes, as always
    import workbench.study_options  # noqa: F401

    pkg = tmp_path / "shapes"
    pkg.mkdir()
    (pkg / "rod.py").write_text(ROD)
    files = tmp_path / "geometry"
    files.mkdir()
    shutil.copy(gparams.DEFAULT_DIR / "rig.toml", files / "rig.toml")
    (files / "rod.toml").write_text(
        "[rod]\nradius_mm = 12.0\nlength_mm = 36.0\nn_contact_points = 9\n"
    )
    monkeypatch.setattr(shapes, "__path__", [*shapes.__path__, str(pkg)])
    monkeypatch.setattr(gparams, "DEFAULT_DIR", files)
    shapes.rediscover()
    yield shapes.get("rod")
    monkeypatch.undo()
    sys.modules.pop("workbench.geometry.shapes.rod", None)
    shapes.rediscover()


def test_a_new_shape_module_is_found_without_other_edits(rod):
    from workbench.pipeline import geometry_request
    from workbench.render.palette import damper_style
    from workbench.studies.engine.plan import Case

    assert shapes.names() == ("cone", "cylinder", "wedge", "rod")
    gp = load_geometry_params("rod")  # its TOML, through the registry's record
    assert (gp.shape.radius_mm, gp.shape.length_mm, gp.shape.n_contact_points) == (12.0, 36.0, 9)
    lay = make_layout(gp)
    ref = make_layout(
        load_geometry_params(
            "cylinder",
            overrides={"cylinder": {"radius_mm": 12.0, "length_mm": 36.0, "n_contact_points": 9}},
        )
    )
    assert lay.n_pairs == 18 and np.array_equal(lay.points, ref.points)
    assert np.array_equal(lay.weight, ref.weight) and lay.kind == "line"
    # the figures know its style, the studies map their options onto its parameters
    assert damper_style("rod") == ("#123456", "-.", "D")
    case = Case("rod", 0.0, 9.6, {"points-per-line": 5, "cone-angle": 12.0})
    req = geometry_request(case)
    assert req["overrides"] == {"rod": {"n_contact_points": 5}}
