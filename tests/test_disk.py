"""The bladed-disk sector: periodic mesh, cyclic modes per nodal diameter, full-disk check, CB.

A coarse 6-blade disk of the paper-like rig's section with the cylinder
damper (3 contact points a line, 25 mm elements): the verification of the
cyclic formulation is exact algebra on the same discretisation, so a coarse
mesh checks it as well as a fine one.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from workbench.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "geometry" / "paper_rig.toml"
COARSE = {
    "rig": {"mesh": {"size_mm": 25.0, "contact_size_mm": 8.0, "damper_size_mm": 10.0}},
    "cylinder": {"n_contact_points": 3},
}


def _sector(tmp: Path, n: int = 6, bore: str = "clamped"):
    from workbench.geometry.disk_build import build_disk_sector

    return build_disk_sector(
        "cylinder", tmp, geometry_file=PAPER, n_blades=n, bore=bore, overrides=COARSE
    )


@pytest.fixture(scope="module")
def clamped(tmp_path_factory):
    return _sector(tmp_path_factory.mktemp("disk6"))


@pytest.fixture(scope="module")
def free(tmp_path_factory):
    return _sector(tmp_path_factory.mktemp("disk6free"), bore="free")


def _contact():
    from workbench.assembly.params import load_contact_params

    return load_contact_params(geometry_file=PAPER)


def test_cyclic_faces_and_contacts_match_by_the_rotation(clamped):
    """Every right-face node is a left-face node turned by 2 pi / N (gmsh setPeriodic), to
    round-off; every side-1 platform point turned back by 2 pi / N is a node of this sector."""
    from workbench.fe.cyclic import assemble_sector

    cs = assemble_sector(clamped, _contact())
    R = cs.rot
    face = cs.body[cs.slave] == 0
    d = np.linalg.norm(cs.coords[cs.slave[face]] - cs.coords[cs.master[face]] @ R.T, axis=1)
    assert face.sum() > 20 and d.max() < 1e-12  # metres; coordinates are ~0.3 m
    img = cs.body[cs.slave] == 2
    d = np.linalg.norm(cs.coords[cs.slave[img]] - cs.coords[cs.master[img]] @ R.T, axis=1)
    assert img.sum() == 3 and d.max() < 1e-12
    # the rotation turns theta toward +x: R e_z = (sin alpha, 0, cos alpha)
    a = 2 * math.pi / 6
    assert np.allclose(R @ [0, 0, 1], [math.sin(a), 0, math.cos(a)], atol=1e-15)


@pytest.mark.parametrize("with_damper", [False, True])
def test_full_disk_modes_equal_the_cyclic_modes(clamped, with_damper):
    """The 6-sector disk assembled from rotated sector copies (nodes merged by coordinates)
    has the union of the cyclic sector's spectra of nodal diameters 0..3, pairs twice: same
    discretisation, so the same numbers to the eigen solver's accuracy (1e-8 relative)."""
    from workbench.fe.cyclic import assemble_sector, eigen, nd_modes, to_hz
    from workbench.fe.cyclic_full import full_disk_matrices, match_spectra

    cs = assemble_sector(clamped, _contact(), with_damper=with_damper)
    nd = {k: nd_modes(cs, k, 3)[0] for k in cs.nodal_diameters()}
    K, M, _ = full_disk_matrices(cs)
    lam, _ = eigen(K, M, 14)
    r = match_spectra(to_hz(lam), nd, 6)
    assert r["n_compared"] >= 12
    assert set(r["nd"]) == {0, 1, 2, 3}
    assert r["worst_rel"] < 1e-8, r


def test_rigid_body_modes_sit_at_their_nodal_diameters(free):
    """Free bore: a rigid turn about the disk axis and an axial shift are ND-0 zero-energy
    fields; an in-plane shift of the whole disk is ND 1 with a = e_x, b = e_z (sector j sees
    R(-j alpha) e_x = cos(j alpha) e_x + sin(j alpha) e_z); b = -e_z is not rigid. The
    eigen solve finds two zero frequencies at ND 0, two pairs at ND 1, none at ND 2 and 3."""
    from workbench.fe.cyclic import assemble_sector, nd_matrices, nd_modes

    cs = assemble_sector(free, _contact())
    m = cs.master_dofs()
    X = cs.coords[m // 3]
    comp = m % 3

    def energy(k, field):
        Kk, Mk, _ = nd_matrices(cs, k)
        return float(field @ (Kk @ field)), float(field @ (Mk @ field))

    turn = np.cross([0.0, 1.0, 0.0], X)[np.arange(len(m)), comp]
    e, mass = energy(0, turn)
    k_scale = abs(cs.K.diagonal()).max()
    assert abs(e) < 1e-12 * k_scale * mass / cs.M.diagonal().max()
    ex, ez = (comp == 0).astype(float), (comp == 2).astype(float)
    good, _ = energy(1, np.concatenate([ex, ez]))
    bad, _ = energy(1, np.concatenate([ex, -ez]))
    assert abs(good) < 1e-9 * abs(bad) and bad > 0
    zero_hz = 1e-3  # a rigid mode's round-off frequency; the first elastic mode is ~100 Hz
    f0, f1 = nd_modes(cs, 0, 3)[0], nd_modes(cs, 1, 3)[0]
    f2, f3 = nd_modes(cs, 2, 1)[0], nd_modes(cs, 3, 1)[0]
    assert np.all(f0[:2] < zero_hz) and f0[2] > 10
    assert np.all(f1[:2] < zero_hz) and f1[2] > 10
    assert f2[0] > 10 and f3[0] > 10


def test_craig_bampton_per_nodal_diameter_converges_from_above(clamped):
    """Reduced onto the platform contact nodes (both halves), each ND's lowest frequencies lie
    above the unreduced ones (Rayleigh-Ritz) and approach them as fixed-interface modes are
    added: 30 modes within 1e-3 of the first three."""
    import scipy.linalg as sl

    from workbench.fe.cyclic import assemble_sector, nd_modes, to_hz
    from workbench.fe.cyclic_cb import reduce_nd

    cs = assemble_sector(clamped, with_damper=False)
    for k in (0, 1, 3):
        exact = nd_modes(cs, k, 3)[0]
        errs = []
        for n_modes in (6, 30):
            r = reduce_nd(cs, k, n_modes)
            assert r.n_boundary == r.copies * 3 * 6
            f = to_hz(sl.eigh(r.K, r.M, eigvals_only=True))
            f = f[0::2] if r.copies == 2 else f
            rel = (f[:3] - exact) / exact
            assert rel.min() > -1e-9  # an upper bound, to round-off
            errs.append(rel.max())
        assert errs[1] < errs[0] and errs[1] < 1e-3, (k, errs)


@pytest.mark.parametrize(
    "n, over, param",
    [
        (1, {}, "disk.n_blades"),  # fewer than two blades
        (4, {}, "disk.n_blades"),  # the hub would reach the axis
        (
            16,
            {"rig": {"base": {"height_mm": 10.0}, "platform": {"top_below_tip_mm": 20.0}}},
            "disk.n_blades",
        ),  # the sector angle overlaps the blade at its root
        (36, {"cylinder": {"radius_mm": 40.0}}, "cylinder.radius_mm"),  # damper too big
        (
            8,
            {"cylinder": {"radius_mm": 27.0}, "rig": {"platform": {"top_below_tip_mm": 150.0}}},
            "disk.n_blades",
        ),  # the damper, low in the groove, would touch the radial blade leaning in
        (36, {"rig": {"platform": {"overhang_mm": 36.0}}}, "rig.platform.overhang_mm"),
    ],
)
def test_bad_disk_input_names_the_parameter(n, over, param):
    from workbench.geometry.disk import load_disk_params, make_disk_layout
    from workbench.geometry.params import load_geometry_params

    with pytest.raises(InputError) as e:
        gp = load_geometry_params("cylinder", PAPER, over or None)
        make_disk_layout(gp, load_disk_params(n_blades=n))
    assert e.value.param == param
    assert "\n" not in str(e.value) and "expected" in str(e.value)
    if "more blades, or a smaller damper" in str(e.value):
        assert "radial blade" in str(e.value)
    elif param == "disk.n_blades" and n > 1:  # the smallest number of blades that fits
        assert e.value.allowed.endswith("<= disk.n_blades <= 400")


def test_upd_disk_bad_input_is_one_line(upd, tmp_path):
    r = upd("disk", "--geometry", str(PAPER), "--n-blades", "4", "--out", str(tmp_path / "o"))
    assert r.code == 2
    assert r.err.strip().count("\n") == 0 and "disk.n_blades = 4" in r.err
    assert "6 <= disk.n_blades <= 400" in r.err


def coarse_geometry_file(tmp: Path, coarse: dict | None = None) -> Path:
    """The paper-like rig's geometry file with the coarse mesh of ``coarse`` (default
    :data:`COARSE`), written to ``tmp/coarse.toml`` for the command line."""
    coarse = COARSE if coarse is None else coarse
    data = tomllib.loads(PAPER.read_text())
    data["rig"]["mesh"] = coarse["rig"]["mesh"]
    data["cylinder"].update(coarse["cylinder"])
    lines = []
    for table, body in data.items():
        for sub, vals in body.items():
            if isinstance(vals, dict):
                lines.append(f"[{table}.{sub}]")
                lines += [f"{k} = {v!r}" for k, v in vals.items()]
        flat = {k: v for k, v in body.items() if not isinstance(v, dict)}
        if flat:
            lines.append(f"[{table}]")
            lines += [f"{k} = {v!r}" for k, v in flat.items()]
    geo = tmp / "coarse.toml"
    geo.write_text("\n".join(lines) + "\n")
    return geo


def test_upd_disk_writes_the_fan_diagram(tmp_path, upd):
    """`upd disk` on the coarse 6-blade disk: the fan's rows are nodal diameters 0..3, the
    stuck damper stiffens the first family at every ND but 0 (the cylinder rolls there), and
    fan.png is drawn."""
    from conftest import assert_nonblank

    geo = coarse_geometry_file(tmp_path)
    out = tmp_path / "out"
    r = upd("disk", "--geometry", str(geo), "--damper", "cylinder", "--n-blades", "6",
            "--families", "2", "--cb-modes", "12", "--out", str(out), "--json")  # fmt: skip
    assert r.code == 0, r.err
    s = r.json
    stuck, free = np.array(s["fan_hz_stuck"]), np.array(s["fan_hz_free"])
    assert stuck.shape == (4, 2) and free.shape == (4, 2)
    assert np.all(stuck[1:, 0] > 1.05 * free[1:, 0])
    assert abs(stuck[0, 0] / free[0, 0] - 1) < 0.05
    assert_nonblank(out / "fan.png")
    # the per-ND Craig-Bampton models: ND 1 carries both copies, its first frequency a pair
    # just above the unreduced no-damper frequency of the fan
    import scipy.linalg as sl

    from workbench.fe.cyclic import to_hz
    from workbench.fe.cyclic_cb import load_reduced

    models = load_reduced(s["files"]["cyclic_cb_h5"])
    assert sorted(models) == [0, 1, 2, 3] and models[1].copies == 2 and models[0].copies == 1
    f1 = to_hz(sl.eigh(models[1].K, models[1].M, eigvals_only=True, subset_by_index=[0, 1]))
    assert abs(f1[1] / f1[0] - 1) < 1e-9
    assert -1e-5 < f1[0] / free[1, 0] - 1 < 1e-3  # from above; the fan rounds to 1e-3 Hz


def test_complex_form_has_the_real_forms_eigenvalues(clamped):
    """The Hermitian ND-1 matrices on U = a - i b (what a complex harmonic balance uses) have
    the real cos/sin form's frequencies, each once; ND N-1 (the other travelling direction)
    is their complex conjugate."""
    from scipy.sparse.linalg import eigsh

    from workbench.fe.cyclic import assemble_sector, complex_nd_matrices, nd_modes, to_hz

    cs = assemble_sector(clamped, with_damper=False)
    ref = nd_modes(cs, 1, 3)[0]
    Kc, Mc = complex_nd_matrices(cs, 1)
    lam = eigsh(Kc.tocsc(), k=3, M=Mc.tocsc(), sigma=-1.0, which="LM", return_eigenvectors=False)
    assert np.allclose(np.sort(to_hz(lam.real)), ref, rtol=1e-9, atol=0)
    Kb, _ = complex_nd_matrices(cs, 5)
    assert abs(Kb - Kc.conj()).max() <= 1e-12 * abs(Kc).max()


def test_second_build_reuses_the_meshes(clamped, tmp_path):
    """Same inputs: the record and meshes are reused (digest equal, files untouched);
    another number of blades is another digest."""
    folder = clamped.sector_msh.parent
    before = clamped.sector_msh.stat().st_mtime_ns
    again = _sector(folder)
    assert again.digest == clamped.digest and again.sector_msh.stat().st_mtime_ns == before
    assert (folder / "sector.vtu").is_file() and (folder / "damper.vtu").is_file()
    other = _sector(tmp_path, n=7)
    assert other.digest != clamped.digest and other.n_blades == 7
    assert abs(other.stats["sector_angle_deg"] - 360 / 7) < 1e-12


def test_reduced_sector_with_stuck_damper_matches_the_cyclic_modes(clamped):
    """The per-ND reduced sector tied to its damper through the interface bookkeeping a
    sector harmonic balance will use (side 1 through R and the phase phi) has the stuck
    cyclic frequencies of the unreduced extended sector: from above, within 3e-4 with 40
    fixed-interface modes, at ND 0, 1 and 3 (the b-copy sign of side 1 flipped gives -1.5e-3
    and +5.7e-3 at ND 1; R^T for R gives 12 %)."""
    import scipy.linalg as sl

    from workbench.fe.coupling import pair_springs
    from workbench.fe.cyclic import assemble_sector, damper_matrices, nd_modes, to_hz
    from workbench.fe.cyclic_cb import reduce_nd, stuck_nd_system

    cp = _contact()
    bare = assemble_sector(clamped, with_damper=False)
    stuck = assemble_sector(clamped, cp)
    Kd, Md, _, dnode = damper_matrices(clamped)
    S = pair_springs(clamped.contact, cp)
    for k in (0, 1, 3):
        exact = nd_modes(stuck, k, 3)[0]
        K, M = stuck_nd_system(reduce_nd(bare, k, 40), Kd, Md, dnode, S, bare.rot)
        f = to_hz(sl.eigh(K, M, eigvals_only=True, subset_by_index=[0, 5]))
        f = f[0::2] if k == 1 else f[:3]
        rel = (f - exact) / exact
        # "from above" to round-off: on this coarse mesh (the cylinder's half meshed and
        # mirrored, one tetrahedron of quality 0.08) SLEPc and a dense solver give the
        # unreduced frequencies only to 4e-8 of each other, and 80 modes put the first
        # ND 3 frequency 1.4e-7 above the exact one where 40 put it 8.5e-8 above (the
        # reduced value moves by round-off, not truncation): 1e-9 held on whole meshes
        assert rel.min() > -1e-7 and rel.max() < 3e-4, (k, rel)


def test_pads_on_the_disk_stiffen_every_nodal_diameter_and_keep_the_full_disk_check(tmp_path):
    """Contact pads (12 mm on this coarse mesh, so that each pad holds nodes) tie nodes of the
    sector and of the damper: a positive semidefinite penalty local to one sector, so every
    cyclic frequency rises (or stays) and the disk assembled from rotated sector copies has
    the same spectrum as the cyclic sector (the check without pads, above)."""
    from workbench.fe.cyclic import assemble_sector, eigen, nd_modes, to_hz
    from workbench.fe.cyclic_full import full_disk_matrices, match_spectra
    from workbench.geometry.disk_build import build_disk_sector

    over = {"rig": dict(COARSE["rig"], mesh=dict(COARSE["rig"]["mesh"], pad_mm=12.0))}
    over["cylinder"] = COARSE["cylinder"]
    rec = build_disk_sector("cylinder", tmp_path, geometry_file=PAPER, n_blades=6, overrides=over)
    bare = build_disk_sector(
        "cylinder", tmp_path / "bare", geometry_file=PAPER, n_blades=6, overrides=COARSE
    )
    cs, cs0 = assemble_sector(rec, _contact()), assemble_sector(bare, _contact())
    assert cs.K.shape == cs0.K.shape and np.array_equal(cs.coords, cs0.coords)
    dK = (cs.K - cs0.K).tocsr()
    tied = np.unique(dK.nonzero()[0] // 3)
    assert {0, 1} <= set(cs.body[tied].tolist())  # pads on the sector and on the damper
    dofs = (3 * tied[:, None] + np.arange(3)[None, :]).ravel()
    w = np.linalg.eigvalsh(dK[dofs][:, dofs].toarray())
    assert w.min() > -1e-9 * w.max()  # positive semidefinite
    for k in cs.nodal_diameters():
        f, f0 = to_hz(nd_modes(cs, k, 3)[0]), to_hz(nd_modes(cs0, k, 3)[0])
        assert np.all(f >= f0 * (1 - 1e-9)) and np.any(f > f0 * (1 + 1e-6)), k
    nd = {k: nd_modes(cs, k, 3)[0] for k in cs.nodal_diameters()}
    K, M, _ = full_disk_matrices(cs)
    lam, _ = eigen(K, M, 14)
    r = match_spectra(to_hz(lam), nd, 6)
    assert r["n_compared"] >= 12 and r["worst_rel"] < 1e-8, r
