"""Harmonic balance on one bladed-disk sector against the whole disk (issue 29, 3 and 4(a)).

The reference is the whole 6-blade disk (the coarse mesh of tests/test_disk.py),
every sector and every damper assembled and solved by the ordinary harmonic
balance (``frequency_response`` on a :class:`System`) as one model. To make the
comparison exact (same discretisation) the whole disk is reduced on the cyclic
basis of the sector's own per-ND Craig-Bampton bases
(:func:`workbench.pipeline.sector.full_disk_system`): sector ``j``'s motion is
``sum_k cos(j phi_k) q_k[a] + sin(j phi_k) q_k[b]`` over every ND ``k = 0..N/2``,
its dampers are ``N`` copies of the sector's reduced damper, each tied to
sector ``j``'s right platform and sector ``j + 1``'s left one. The whole disk
then holds every ND, not only the harmonics' own, and its solution is a
travelling wave only if the physics makes it one; reducing the whole disk with
other modes instead would compare two discretisations, not the formulation.
The AFT samples a period with ``nt`` a multiple of N, so each sector's samples
are the same set shifted (the friction march is the same loop).

Each engine order EO = 0..3 is checked: the first stuck frequency of harmonic
1's block equals the whole disk's and the unreduced cyclic FE mode of its ND
(within the Craig-Bampton error, from above); the forced responses of both
models peak at the same frequency with the same amplitude and friction energy
(1e-6 relative: each model is solved at the other's peak frequency too, so a
kinked top with two near-equal local maxima cannot make the test fail by the
search landing on different ones).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
from test_disk import coarse_geometry_file

from workbench.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "geometry" / "paper_rig.toml"
COARSE = {
    "rig": {"mesh": {"size_mm": 25.0, "contact_size_mm": 8.0, "damper_size_mm": 10.0}},
    "cylinder": {"n_contact_points": 3},
}
HARMONICS = (0, 1, 2, 3)
NT = 24  # a multiple of N = 6
FORCE = 30.0  # N: the cylinders slip over the top of every EO's peak


def _contact():
    from workbench.assembly.params import load_contact_params

    return load_contact_params(geometry_file=PAPER)


@pytest.fixture(scope="module")
def disk(tmp_path_factory):
    from workbench.geometry.disk_build import build_disk_sector
    from workbench.pipeline.sector import build_sector_model

    rec = build_disk_sector(
        "cylinder",
        tmp_path_factory.mktemp("sector6"),
        geometry_file=PAPER,
        n_blades=6,
        overrides=COARSE,
    )
    return rec, build_sector_model(rec, _contact(), n_modes=6, n_damper_modes=4)


def _options():
    from workbench.hbm.core.options import SolverOptions

    return SolverOptions(stability=False, peak_ftol=1e-10, peak_iterations=80)


def _at(hb, br, f_hz: float):
    """Output-0 amplitude and friction energy of ``hb`` solved at ``f_hz`` (Newton from the
    branch point nearest in frequency)."""
    x = br.x[int(np.argmin(abs(br.freq_hz - f_hz)))].copy()
    w = 2 * np.pi * f_hz
    for _ in range(40):
        ev = hb.evaluate(x, w)
        if np.abs(ev.r).max() <= 1e-13 * np.abs(x).max():
            break
        x = x - np.linalg.solve(hb.dense_jacobian(ev), ev.r)
    pd = hb.point_data(hb.evaluate(x, w))
    return float(pd.out_h1[0]), float(pd.friction_energy.sum())


def test_engine_order_and_nodal_diameters():
    """Harmonic h lives at ND h EO mod N, folded to N - k (backward) above N/2; bad input
    is one line naming the parameter."""
    from workbench.hbm.core.sector import check_engine_order, nd_of_harmonic

    assert nd_of_harmonic(1, 2, 6) == (2, 2, 1)
    assert nd_of_harmonic(2, 2, 6) == (4, 2, -1)  # backward
    assert nd_of_harmonic(3, 2, 6) == (0, 0, 1)
    assert nd_of_harmonic(1, 5, 6) == (5, 1, -1)  # EO 5 of 6 blades: ND 1 backward
    assert nd_of_harmonic(1, 9, 24) == (9, 9, 1)
    assert check_engine_order(7, 6) == 7 and check_engine_order(3.0, 6) == 3
    for eo, n, param in ((-1, 6, "eo"), (1.5, 6, "eo"), ("2", 6, "eo"), (1, 1, "n_blades")):
        with pytest.raises(InputError) as e:
            check_engine_order(eo, n)
        assert e.value.param == param and "\n" not in str(e.value)


def test_sector_jacobian_is_exact(disk):
    """The analytic Jacobian (and dr/dw) against central differences at a slipping state,
    EO 2 (harmonic 2 backward at ND 2, harmonic 3 at ND 0)."""
    from workbench.hbm.core.fourier import Fourier
    from workbench.hbm.core.sector import SectorBalance

    _, model = disk
    hb = SectorBalance(model, 2, Fourier(HARMONICS, NT), FORCE, dc_anchor=1e-3)
    assert hb.direction[2] == -1 and hb.nd_of_harmonic[3] == 0
    rng = np.random.default_rng(0)
    x = rng.normal(size=hb.N) * 2e-5  # metres: beyond the slip displacement
    w = 2 * np.pi * 500.0
    ev = hb.evaluate(x, w)
    assert np.any(ev.aft.n_slip)
    J = hb.dense_jacobian(ev)
    v = rng.normal(size=hb.N) * 1e-7
    fd = (hb.residual(x + 1e-3 * v, w) - hb.residual(x - 1e-3 * v, w)) / 2e-3
    assert np.abs(J @ v - fd).max() < 1e-6 * np.abs(fd).max()
    assert np.allclose(hb.jvp(ev, v), J @ v, rtol=0, atol=1e-12 * np.abs(J @ v).max())
    fw = (hb.residual(x, w + 1e-3) - hb.residual(x, w - 1e-3)) / 2e-3
    assert np.abs(hb.residual_omega(ev) - fw).max() < 1e-6 * np.abs(fw).max()


def test_linear_limits_match_the_cyclic_fe_modes(disk):
    """Stuck: harmonic 1's block at EO's ND has the unreduced cyclic FE frequency with the
    damper stuck (within the Craig-Bampton error, from above). Sliding without normal
    stiffness (no tangential or normal spring): the bladed sector's own ND frequency."""
    import dataclasses

    from workbench.fe.cyclic import assemble_sector, nd_modes
    from workbench.hbm.core.fourier import Fourier
    from workbench.hbm.core.sector import SectorBalance

    rec, model = disk
    stuck_cs = assemble_sector(rec, _contact(), with_damper=True)
    bare_cs = assemble_sector(rec, with_damper=False)
    loose = dataclasses.replace(model, kt=model.kt * 0, kn=model.kn * 0, n0=model.n0 * 0)
    f = Fourier((0, 1), 8)
    for eo in range(4):
        fe_stuck = nd_modes(stuck_cs, eo, 1)[0][0]
        fe_bare = nd_modes(bare_cs, eo, 1)[0][0]
        hb_stuck = SectorBalance(model, eo, f).stuck_frequencies(1, 1)[0]
        # the free damper's rigid modes sit at 0 Hz: the first blade mode after them
        fr = SectorBalance(loose, eo, f).stuck_frequencies(1, 12)
        hb_bare = fr[fr > 10.0][0]
        for red, fe in ((hb_stuck, fe_stuck), (hb_bare, fe_bare)):
            assert -1e-9 < red / fe - 1 < 2e-3, (eo, red, fe)


@pytest.mark.parametrize("eo", [0, 1, 2, 3])
def test_sector_harmonic_balance_equals_the_whole_disk(disk, eo):
    from workbench.hbm.core.balance import HarmonicBalance
    from workbench.hbm.core.fourier import Fourier
    from workbench.hbm.core.sector import SectorBalance
    from workbench.hbm.forced.response import frequency_response
    from workbench.pipeline.sector import full_disk_system, sector_forced_response

    _, model = disk
    opts = _options()
    t0 = time.perf_counter()
    br, info = sector_forced_response(model, eo, FORCE, None, HARMONICS, NT, opts)
    assert info["nd_of_harmonic"]["1"] == eo and br.completed, br.message
    f_stuck = info["stuck_hz"][0]
    i = int(np.argmax(br.out_h1[:, 0]))
    assert 0 < i < len(br.freq_hz) - 1
    f_pk = br.freq_hz[i]
    assert abs(f_pk / f_stuck - 1) < 0.01  # the resonance of the stuck ND
    # EO 0: the cylinders roll with the in-phase platforms and stick; else they slip at the top
    assert (br.status[i].max() >= 1) == (eo > 0)
    # work balance per cycle (harmonic h's viscous work is pi h^2 w x^T C x)
    assert br.energy_residual.max() < 1e-8
    t_sector = time.perf_counter() - t0
    system, f1, O = full_disk_system(model, eo)
    band = (0.999 * f_pk, 1.001 * f_pk)
    bf = frequency_response(system, f1, FORCE, band, O, HARMONICS, NT, opts)
    assert bf.completed, bf.message
    j = int(np.argmax(bf.out_h1[:, 0]))
    assert 0 < j < len(bf.freq_hz) - 1
    fourier = Fourier(HARMONICS, NT)
    hs = SectorBalance(model, eo, fourier, FORCE, dc_anchor=opts.dc_anchor)
    hf = HarmonicBalance(system, f1, fourier, O, FORCE, "auto", "auto", opts.dc_anchor)
    # each model at the other's peak frequency
    a_s, e_s = _at(hs, br, bf.freq_hz[j])
    a_f, e_f = _at(hf, bf, br.freq_hz[i])
    peaks_s = [(br.out_h1[i, 0], br.freq_hz[i]), (a_s, bf.freq_hz[j])]
    peaks_f = [(a_f, br.freq_hz[i]), (bf.out_h1[j, 0], bf.freq_hz[j])]
    (ps, fs), (pf, ff) = max(peaks_s), max(peaks_f)
    assert abs(ps / pf - 1) < 1e-6 and abs(fs / ff - 1) < 1e-6, (peaks_s, peaks_f)
    assert abs(a_s / bf.out_h1[j, 0] - 1) < 1e-6  # the same solution at the same frequency
    e_full = bf.friction_energy[j].sum()  # J per cycle, all six dampers
    assert abs(6 * e_s - e_full) <= 1e-6 * max(abs(e_full), 1e-6 * bf.work_ext[j])
    print(f"EO {eo}: {ps:.6e} m at {fs:.6f} Hz, rel {ps / pf - 1:.1e}; sector {t_sector:.1f} s")


def test_upd_disk_frf_writes_the_receptance_and_the_branch(tmp_path, upd):
    """`upd disk --frf --eo 5` on 6 blades: EO 5 is ND 1 travelling backward (said in the
    summary and the HDF5), the branch file carries units, the PNG is drawn; a negative EO is
    a one-line error naming --eo."""
    import h5py
    from conftest import assert_nonblank

    geo = coarse_geometry_file(tmp_path, COARSE)
    out = tmp_path / "out"
    r = upd("disk", "--geometry", str(geo), "--damper", "cylinder", "--n-blades", "6",
            "--families", "1", "--frf", "--eo", "5", "--force", "30", "--frf-modes", "6",
            "--out", str(out), "--json")  # fmt: skip
    assert r.code == 0, r.err
    s = r.json["sector"]
    assert s["nd_of_harmonic"]["1"] == 1 and s["direction_of_harmonic"]["1"] == "backward"
    assert s["nd_of_harmonic"]["2"] == 2 and s["direction_of_harmonic"]["2"] == "backward"
    assert s["completed"] and 0.95 < s["peak_hz"] / s["stuck_hz"][0] < 1.01
    assert s["stability"].startswith("not computed")
    with h5py.File(s["files"]["sector_h5"]) as h:
        assert h["freq_hz"].attrs["unit"] == "Hz" and h["out_amp"].attrs["unit"] == "m"
        assert h["friction_energy"].attrs["unit"] == "J"
        assert '"direction_of_harmonic"' in h.attrs["problem"]
    assert_nonblank(Path(s["files"]["sector_png"]))
    r = upd("disk", "--geometry", str(geo), "--n-blades", "6", "--frf", "--eo", "-1",
            "--out", str(tmp_path / "bad"))  # fmt: skip
    assert r.code == 2 and r.err.strip().count("\n") == 0 and "--eo" in r.err


def test_the_ends_of_the_eo_range_behave_like_the_rigs_two_families(tmp_path):
    """On the paper-like rig's blade (6 blades, coarse): at EO 0 (the rig's in-phase family)
    the cylinder rolls (stuck at the peak, its stuck frequency within 1 % of the bladed disk
    without damper) while the cone stiffens the blades by more than 15 %; at EO N/2 (out of
    phase) the three dampers are alike: stuck frequencies within 4 % and 30 N peaks within
    20 % of each other (the rig: 409-412 Hz, 0.30-0.37 mm; docs/FINDINGS.md). About 15 s."""
    import dataclasses

    from workbench.fe.cyclic import assemble_sector, nd_modes
    from workbench.geometry.disk_build import build_disk_sector
    from workbench.hbm.core.fourier import Fourier
    from workbench.hbm.core.sector import SectorBalance
    from workbench.pipeline.sector import build_sector_model, sector_forced_response

    mesh = COARSE["rig"]
    points = {
        "cone": {"n_contact_points": 3},
        "cylinder": {"n_contact_points": 3},
        "wedge": {"n_contact_rows": 2, "n_contact_per_row": 3},
    }
    f = Fourier((0, 1), 8)
    stuck, peaks = {}, {}
    bare_hz = None
    for d, pts in points.items():
        rec = build_disk_sector(
            d, tmp_path / d, geometry_file=PAPER, n_blades=6, overrides={"rig": mesh, d: pts}
        )
        if bare_hz is None:
            bare_hz = nd_modes(assemble_sector(rec, with_damper=False), 0, 1)[0][0]
        model = build_sector_model(rec, _contact(), [0, 3], n_modes=6, n_damper_modes=4)
        stuck[d] = [SectorBalance(model, eo, f).stuck_frequencies(1, 1)[0] for eo in (0, 3)]
        br, _ = sector_forced_response(model, 3, FORCE, None, HARMONICS, NT, _options())
        assert br.completed, (d, br.message)
        peaks[d] = br.out_amp[:, 0].max()
        if d == "cylinder":
            b0, _ = sector_forced_response(model, 0, FORCE, None, HARMONICS, NT, _options())
            assert b0.completed and b0.status.max() == 0  # it rolls: never slips
        if d == "cone":  # with the mean unknowns in the arc length the slip onset is passed
            opts = dataclasses.replace(_options(), dc_weight=1.0)
            b0, _ = sector_forced_response(model, 0, FORCE, None, HARMONICS, NT, opts)
            i = int(b0.out_amp[:, 0].argmax())
            assert b0.completed, b0.message
            assert b0.status[i].max() >= 1 and b0.friction_energy[i].sum() > 0  # slips at the top
            assert 0 < i < len(b0.freq_hz) - 1 and b0.freq_hz[i] < stuck[d][0]  # a softened peak
    assert abs(stuck["cylinder"][0] / bare_hz - 1) < 0.01
    assert stuck["cone"][0] > 1.15 * bare_hz
    f3 = np.array([s[1] for s in stuck.values()])
    assert f3.max() / f3.min() < 1.04, stuck
    p3 = np.array(list(peaks.values()))
    assert p3.max() / p3.min() < 1.2, peaks


def test_api_sector_frf(tmp_path):
    """wb.sector_frf: EO 7 of 6 blades is ND 1 forward; a negative EO is refused before
    any meshing, naming eo."""
    import workbench as wb

    with pytest.raises(InputError) as e:
        wb.sector_frf("cylinder", -1, 30.0, n_blades=6, out=tmp_path / "bad")
    assert e.value.param == "eo" and not (tmp_path / "bad").exists()
    br, info = wb.sector_frf(
        "cylinder", 7, FORCE, n_blades=6, geometry_file=PAPER, out=tmp_path / "d",
        modes=6, band_hz=(455.0, 470.0), overrides=COARSE,
    )  # fmt: skip
    assert info["nd_of_harmonic"]["1"] == 1 and info["direction_of_harmonic"]["1"] == "forward"
    assert br.completed and br.freq_hz[0] == 455.0 and br.out_amp.shape[1] == 1
