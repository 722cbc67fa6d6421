"""``upd mesh`` as a user runs it: JSON summary, files, picture, one-line errors."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import assert_nonblank

KEYS = (
    "n_nodes",
    "n_cells",
    "n_contact_pairs",
    "max_pair_gap_m",
    "damper_volume_m3",
    "damper_mass_kg",
)


def check_files(out: Path, res) -> None:
    for name in (
        "rig.msh",
        "damper.msh",
        "rig.xdmf",
        "damper.xdmf",
        "rig.h5",
        "damper.h5",
        "geometry.h5",
        "scene.png",
    ):
        assert (out / name).is_file(), name
    assert_nonblank(out / "scene.png")
    assert res.json["files"]["png"] == str(out / "scene.png")


def test_mesh_cone_with_defaults(upd, tmp_path):
    r = upd("mesh", "--damper", "cone", "--out", tmp_path, "--json")
    assert r.code == 0, r
    j = r.json  # stdout is pure JSON (gmsh is silent)
    for k in KEYS:
        assert k in j
    assert j["n_contact_pairs"] == 46
    assert j["max_pair_gap_m"] <= 1e-9
    # the default rig mesh: about 47k P2 nodes (141k DOFs), four to five elements
    # through the 40 mm blades, small enough for the 15-minute paper study
    assert 30_000 <= j["rig_n_nodes"] <= 150_000
    assert j["n_nodes"] == j["rig_n_nodes"] + j["damper_n_nodes"]
    assert j["damper_mass_kg"] == pytest.approx(7800 * j["damper_volume_m3"], rel=1e-12)
    assert j["damper_volume_m3"] == pytest.approx(j["damper_volume_exact_m3"], rel=1e-4)
    assert j["cone_tilt_gamma_deg"] == pytest.approx(14.2159, abs=1e-4)  # asin(sin10/sin45)
    assert j["reused"] is False
    check_files(tmp_path, r)
    again = upd("mesh", "--damper", "cone", "--out", tmp_path, "--json")
    assert again.code == 0 and again.json["reused"] is True
    assert again.json["digest"] == j["digest"]


@pytest.mark.parametrize("damper,pairs", [("cylinder", 46), ("wedge", 146)])
def test_mesh_cylinder_and_wedge(upd, tmp_path, damper, pairs):
    geo = tmp_path / "g.toml"
    geo.write_text("[rig.mesh]\ncontact_size_mm = 2.5\ndamper_size_mm = 5.0\n")
    out = tmp_path / "out"
    r = upd("mesh", "--damper", damper, "--size", "9", "--geometry", geo, "--out", out, "--json")
    assert r.code == 0, r
    j = r.json
    assert j["n_contact_pairs"] == pairs and j["max_pair_gap_m"] <= 1e-9
    assert j["size_mm"] == 9.0
    assert j["contact_size_mm"] <= 2.5  # never coarser than the contact point spacing
    check_files(out, r)


def test_human_output(upd, tmp_path):
    r = upd("mesh", "--damper", "wedge", "--size", "12", "--no-png", "--out", tmp_path)
    assert r.code == 0, r
    assert "max_pair_gap_m: 0" in r.out and "n_contact_pairs: 146" in r.out
    assert not (tmp_path / "scene.png").exists()


@pytest.mark.parametrize(
    "args,toml,needle",
    [
        (["--damper", "con"], None, "did you mean 'cone'"),
        (["--damper", "cone", "--size", "0"], None, "size_mm = 0.0 is not allowed"),
        (["--damper", "cone", "--size", "-3"], None, "size_mm = -3.0 is not allowed"),
        (["--damper", "cone", "--size", "abc"], None, "not a number"),
        (
            ["--damper", "cone"],
            "[cone]\nsemi_angle_deg = 50.0\n",
            "cone.semi_angle_deg = 50.0 is not allowed",
        ),
        (["--damper", "cone"], "[cone]\nlength_mm = 90.0\n", "cone.length_mm = 90.0"),
        (["--damper", "cylinder"], "[cylinder]\nradius_mm = 30.0\n", "cylinder.radius_mm = 30.0"),
        (["--damper", "wedge"], "[wedge]\ntop_width_mm = 2.0\n", "wedge.top_width_mm = 2.0"),
        (
            ["--damper", "cylinder"],
            "[cylinder]\nn_contact_points = 1\n",
            "cylinder.n_contact_points = 1 is not allowed",
        ),
        (
            ["--damper", "wedge"],
            "[rig.mesh]\ncontact_size_mm = -1.0\n",
            "rig.mesh.contact_size_mm = -1.0 is not allowed",
        ),
        (["--damper", "cone"], "[cone]\nsemi_angel_deg = 5.0\n", "did you mean 'semi_angle_deg'"),
        (["--damper", "cone"], "[rig.platfrom]\nangle_deg = 40.0\n", "did you mean 'platform'"),
        (["--damper", "cone", "--geometry", "/nonexistent/g.toml"], None, "an existing TOML file"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(upd, tmp_path, args, toml, needle):
    if toml is not None:
        f = tmp_path / "g.toml"
        f.write_text(toml)
        args = [*args, "--geometry", str(f)]
    r = upd("mesh", *args, "--out", tmp_path / "out", "--json")
    assert r.code == 2, r
    assert r.out == ""
    lines = r.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("upd mesh: error:"), r.err
    assert needle in lines[0], lines[0]
    assert "Traceback" not in r.err
