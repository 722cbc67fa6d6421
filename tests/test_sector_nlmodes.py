"""Nonlinear modes on one bladed-disk sector (issue 29 item 3): the EPMC backbone on the
sector's unknowns (:mod:`workbench.hbm.nlmodes.sector_epmc`).

The reference at EO 0 is the EPMC of :mod:`workbench.hbm.nlmodes.epmc` on the whole
6-blade disk assembled on the sector's own cyclic basis
(:func:`workbench.pipeline.sector.full_disk_system`, as tests/test_sector_hbm.py): the
ND-0 mode is a single mode there, so its backbone is well defined on both models. The
same motion has a whole-disk modal amplitude sqrt(6) times the sector's. A travelling
wave (EO 1..N/2 - 1) is one of a degenerate pair on the whole disk, so there it is
checked only against its own linear limit.
"""

from __future__ import annotations

import os
import time

import numpy as np
from test_sector_hbm import HARMONICS, NT, disk  # noqa: F401  (the module's fixture)

N_BLADES = 6


def _newton(prob, y, a, its=30):
    """The EPMC point of ``prob`` at modal amplitude ``a`` from the guess ``y`` (Newton on
    the analytic Jacobian; fails the test if it does not converge): (y, iterations)."""
    for k in range(its):
        r, _, J = prob.residual(y, a, want_jac=True)
        dy = np.linalg.solve(J, -r)
        y = y + dy
        if np.abs(dy[:-2]).max() <= 1e-11 * np.abs(y[:-2]).max():
            return y, k + 1
    raise AssertionError(f"Newton did not converge at modal amplitude {a:.4g}")


def _on_whole_disk(model, x, n, fourier, n_blades):
    """EO 0 sector unknowns ``x`` as whole-disk harmonics (nh * n) per unit whole-disk modal
    amplitude: ND 0's coordinates come first in the whole disk, then the N dampers."""
    from workbench.hbm.core.fourier import Fourier
    from workbench.hbm.core.sector import SectorBalance

    hb = SectorBalance(model, 0, Fourier(fourier.harmonics, fourier.nt))
    mq, md = model.nd[0].K.shape[0], model.Kd.shape[0]
    n_sec = sum(b.K.shape[0] for b in model.nd.values())
    P = np.zeros((fourier.nh, n))
    for b in hb.blocks:
        xb = x[b["sl"]]
        if b["rows"] == (0,):
            parts = [(0, xb[:mq], xb[mq:])]
        else:
            c, s = b["rows"]
            parts = [
                (c, xb[:mq], xb[2 * mq : 2 * mq + md]),
                (s, xb[mq : 2 * mq], xb[2 * mq + md :]),
            ]
        for row, q, d in parts:
            P[row, :mq] = q
            P[row, n_sec:] = np.tile(d, n_blades)
    return P.ravel() / np.sqrt(n_blades)


def test_sector_backbone_at_eo0_equals_the_whole_disks(disk):  # noqa: F811
    from workbench.hbm.core.fourier import Fourier
    from workbench.hbm.core.sector import SectorBalance
    from workbench.hbm.nlmodes.backbone import pick_mode
    from workbench.hbm.nlmodes.epmc import Epmc
    from workbench.pipeline.sector import full_disk_system, sector_backbone

    _, model = disk
    t0 = time.perf_counter()
    bb = sector_backbone(model, 0, relative_range=(0.3, 2.2), harmonics=HARMONICS, nt=NT,
                         n_steps=40, max_points=80)  # fmt: skip
    t_sector = time.perf_counter() - t0
    assert bb.completed and not bb.failed, bb.message
    f = Fourier(HARMONICS, NT)
    f_stuck = SectorBalance(model, 0, f).stuck_frequencies(1, 1)[0]
    assert abs(bb.f_stuck_hz / f_stuck - 1) < 1e-9
    # low amplitude: every contact stuck, the stuck linear mode
    assert not bb.status[0].any()
    assert abs(bb.freq_hz[0] / f_stuck - 1) < 1e-7  # the damping is not quite modal
    # higher: the in-phase platforms make the cylinders roll, most contacts stick; the
    # slipping ones soften the mode and damp it a little (until the damper lifts off at
    # about 2.4 times the first slip)
    assert bb.status[-1].max() >= 1 and bb.freq_hz[-1] < bb.freq_hz[0]
    assert bb.damping_ratio[-1] > bb.damping_ratio[0]

    system, f1, _ = full_disk_system(model, 0)
    full = Epmc(system, f, pick_mode(system, f1))
    assert abs(full.w_lin / (2 * np.pi) / f_stuck - 1) < 1e-7  # eigh on a stiff system
    # the sector's point on the whole disk (every sector and damper moving alike) is the
    # guess; Newton on the whole disk's own equations converges to its own point
    worst, n_its = 0.0, []
    for i in range(bb.n_points):
        a_full = np.sqrt(N_BLADES) * bb.amplitude[i]
        y0 = np.concatenate([_on_whole_disk(model, bb.psi[i], system.n, f, N_BLADES),
                             [2 * np.pi * bb.freq_hz[i], bb.xi[i]]])  # fmt: skip
        y_full, its = _newton(full, y0, a_full)
        n_its.append(its)
        w, xi = y_full[-2], y_full[-1]
        rf = abs(w / (2 * np.pi) / bb.freq_hz[i] - 1)
        rd = abs(xi / (2 * w) / bb.damping_ratio[i] - 1)
        worst = max(worst, rf, rd)
        assert rf < 1e-6 and rd < 1e-6, (i, bb.amplitude[i], rf, rd)
    print(f"EO 0: {bb.n_points} points ({int(bb.status.max(axis=1).astype(bool).sum())} slipping),"
          f" worst relative difference {worst:.1e}, Newton iterations {n_its}; "
          f"sector backbone {t_sector:.2f} s")  # fmt: skip


def test_travelling_wave_backbone_starts_at_its_linear_limit(disk):  # noqa: F811
    """EO 2 of 6: harmonic 1 a forward wave at ND 2, harmonic 2 a backward one at ND 2,
    harmonic 3 at ND 0. Below the first slip the stuck ND-2 mode; above it the friction
    softens and damps the mode strongly; each point balances its energy."""
    from workbench.hbm.core.fourier import Fourier
    from workbench.hbm.core.sector import SectorBalance
    from workbench.pipeline.sector import sector_backbone

    _, model = disk
    t0 = time.perf_counter()
    bb = sector_backbone(model, 2, relative_range=(0.3, 3.0), harmonics=HARMONICS, nt=NT,
                         n_steps=8, max_points=60)  # fmt: skip
    t = time.perf_counter() - t0
    assert bb.completed and not bb.failed, bb.message
    f_stuck = SectorBalance(model, 2, Fourier(HARMONICS, NT)).stuck_frequencies(1, 1)[0]
    assert abs(bb.f_stuck_hz / f_stuck - 1) < 1e-9
    # (the undamped stuck frequency: the viscous damping is not quite modal, 4e-7 here)
    assert not bb.status[0].any() and abs(bb.freq_hz[0] / f_stuck - 1) < 1e-6
    assert bb.status[-1].min() >= 1 and bb.freq_hz[-1] < 0.97 * f_stuck
    assert bb.damping_ratio.max() > 5 * bb.damping_ratio[0]
    assert bb.energy_residual.max() < 1e-6
    print(f"EO 2: {bb.n_points} points, {bb.freq_hz[0]:.4f} -> {bb.freq_hz[-1]:.4f} Hz, "
          f"D up to {bb.damping_ratio.max():.3f}; {t:.2f} s")  # fmt: skip


def test_sector_epmc_jacobian_is_exact(disk):  # noqa: F811
    """The analytic Jacobian of the sector EPMC against central differences at a slipping
    state of a travelling wave (EO 1)."""
    from workbench.hbm.core.fourier import Fourier
    from workbench.hbm.nlmodes.sector_epmc import SectorEpmc

    _, model = disk
    prob = SectorEpmc(model, 1, Fourier(HARMONICS, NT))
    rng = np.random.default_rng(1)
    y = prob.linear_guess()
    y[: prob.N] += rng.normal(size=prob.N) * np.abs(y[: prob.N]).max() * 0.3
    a = 5 * prob.slip_amplitude()
    r, res, J = prob.residual(y, a, want_jac=True)
    assert np.any(res.n_slip)
    v = rng.normal(size=prob.n_unknowns) * prob.var_scale() * 1e-3 * np.abs(y[: prob.N]).max()
    v[prob.N :] *= 1e-3
    fd = (prob.residual(y + 1e-3 * v, a)[0] - prob.residual(y - 1e-3 * v, a)[0]) / 2e-3
    assert np.abs(J @ v - fd).max() < 1e-6 * np.abs(fd).max()


def test_upd_disk_backbone_writes_the_sector_backbone(tmp_path, upd):
    """`upd disk --backbone --eo 1` on 6 blades: the backbone of the ND-1 travelling wave
    starts at its stuck frequency, softens and is written with its CSV."""
    import csv

    from test_disk import coarse_geometry_file
    from test_sector_hbm import COARSE

    from workbench.hbm.nlmodes.record import NlModeBranch

    geo = coarse_geometry_file(tmp_path, COARSE)
    r = upd("disk", "--geometry", str(geo), "--damper", "cylinder", "--n-blades", "6",
            "--families", "1", "--backbone", "--eo", "1", "--frf-modes", "6",
            "--out", str(tmp_path / "out"), "--json")  # fmt: skip
    assert r.code == 0, r.err
    s = r.json["sector_backbone"]
    assert "sector" not in r.json and s["eo"] == 1 and s["n_points"] > 10
    f0, f1 = s["freq_hz"]
    assert abs(f0 / s["stuck_hz"] - 1) < 1e-6 and f1 < 0.97 * f0
    nm = NlModeBranch.load(s["files"]["h5"])
    assert nm.n_points == s["n_points"] and nm.damping_ratio.max() == s["damping_ratio_max"]
    with open(s["files"]["csv"]) as fh:
        assert len(list(csv.reader(fh))) == s["n_points"] + 1
    assert os.path.getsize(s["files"]["png"]) > 10_000  # the backbone's four panels
