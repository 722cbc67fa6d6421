"""Nonlinear modes (EPMC) and the single-nonlinear-mode synthesis: physics checks.

* Jenkins oscillator: the backbone starts at the stuck frequency with the
  viscous ratio, tends to the sliding frequency, and follows the closed-form
  harmonic-1 describing function of the Jenkins element (frequency, damping
  maximum, friction energy per cycle).
* Analytic Jacobian against central finite differences.
* Two-DOF contact example (normal load coupled to the tangential motion):
  peaks synthesised from the backbone against full HBM forced responses.
* A case where the synthesis is not valid (the mode turns into another one)
  is detected automatically, and is indeed wrong there.
"""

from __future__ import annotations

import numpy as np
import pytest

from workbench.contact import ContactElements
from workbench.hbm import SolverOptions, System, frequency_response
from workbench.hbm.core.fourier import Fourier
from workbench.hbm.io.examples import sdof_jenkins, two_dof_contact
from workbench.hbm.nlmodes.backbone import nonlinear_mode, pick_mode, slip_amplitude
from workbench.hbm.nlmodes.epmc import Epmc
from workbench.hbm.nlmodes.epmc_condensed import EpmcCondensed
from workbench.hbm.nlmodes.record import NlModeBranch
from workbench.hbm.nlmodes.synthesis import synthesize


def jenkins_df(X: np.ndarray, kt: float, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """Harmonic-1 describing function of a Jenkins element: (k_eq, k_d) at amplitude X."""
    X = np.asarray(X, dtype=float)
    xs = fs / kt
    keq = np.full_like(X, kt)
    kd = np.zeros_like(X)
    s = X > xs
    phi = np.arccos(1 - 2 * xs / X[s])
    keq[s] = kt / np.pi * (phi - np.sin(2 * phi) / 2)
    kd[s] = 4 * fs * (X[s] - xs) / (np.pi * X[s] ** 2)
    return keq, kd


@pytest.fixture(scope="module")
def jenkins():
    ex = sdof_jenkins()
    b = nonlinear_mode(
        ex.system, harmonics=(1,), outputs=[0], relative_range=(0.1, 1000.0), n_steps=80
    )  # fine steps near the damping maximum
    return ex, b


def test_jenkins_backbone_limits(jenkins):
    ex, b = jenkins
    m, k, kt = 0.1, ex.info["k"], ex.info["kt"]
    assert b.completed and not b.failed, b.message
    f_stuck = np.sqrt((k + kt) / m) / (2 * np.pi)
    f_slide = np.sqrt(k / m) / (2 * np.pi)
    # small amplitude: the stuck linear mode with its own viscous ratio (D = xi / 2w)
    assert b.freq_hz[0] == pytest.approx(f_stuck, rel=1e-9)
    assert b.damping_ratio[0] == pytest.approx(0.005, rel=1e-9)
    assert b.status[0, 0] == 0
    # large amplitude (1000 x slip onset): the sliding frequency, the element slips
    assert b.freq_hz[-1] == pytest.approx(f_slide, rel=5e-4)
    assert b.status[-1, 0] == 1
    # frequency decreases monotonically from stuck to sliding
    assert np.all(np.diff(b.freq_hz) <= 1e-9 * f_stuck)
    # every point closes its energy balance (xi feeds what C and friction take)
    assert b.energy_residual.max() < 1e-6


def test_jenkins_backbone_against_describing_function(jenkins):
    ex, b = jenkins
    m, k, kt = 0.1, ex.info["k"], ex.info["kt"]
    fs = 0.5 * 2.0
    X = b.out_h1[:, 0]  # harmonic-1 displacement amplitude, m
    assert X == pytest.approx(b.amplitude / np.sqrt(m), rel=1e-9)  # a^2 = m X^2
    keq, kd = jenkins_df(X, kt, fs)
    c = 2 * 0.005 * np.sqrt((k + kt) / m) * m
    w = np.sqrt((k + keq) / m)
    D = c / (2 * m * w) + kd / (2 * (k + keq))
    # AFT with 32 samples per period places the slip instants within T/32: the describing
    # function is matched to 0.1 % in frequency and 2 % of the largest damping
    assert b.freq_hz == pytest.approx(w / (2 * np.pi), rel=1e-3)
    assert np.abs(b.damping_ratio - D).max() < 0.02 * D.max()
    # the damping maximum: closed form on a fine grid against the backbone
    Xg = np.geomspace(X[0], X[-1], 20001)
    kq, kdg = jenkins_df(Xg, kt, fs)
    Dg = c / (2 * m * np.sqrt((k + kq) / m)) + kdg / (2 * (k + kq))
    i, ig = int(np.argmax(b.damping_ratio)), int(np.argmax(Dg))
    assert b.damping_ratio[i] == pytest.approx(Dg[ig], rel=0.01)
    # where: between the neighbours of the largest sampled value, which are close
    assert X[i - 1] <= Xg[ig] <= X[i + 1]
    assert X[i + 1] / X[i - 1] < 1.6  # two steps of at most 2 ln(a1/a0) / n_steps
    # friction energy per cycle: 4 Fs (X - Xs) once the element slips
    slip = X > 2 * fs / kt
    e = b.friction_energy[slip, 0]
    assert e == pytest.approx(4 * fs * (X[slip] - fs / kt), rel=0.02)


def test_epmc_jacobian_finite_differences():
    ex = two_dof_contact()
    p = Epmc(ex.system, Fourier((0, 1, 2, 3)), 0, ex.outputs)
    b = nonlinear_mode(
        ex.system, mode=0, harmonics=(0, 1, 2, 3), relative_range=(0.5, 5.0), n_steps=6
    )
    i = b.n_points // 2
    assert b.status[i, 0] == 1  # stick-slip: the contact Jacobian is not trivial
    y = np.concatenate([b.psi[i], [2 * np.pi * b.freq_hz[i], b.xi[i]]])
    a = float(b.amplitude[i])
    _, _, J = p.residual(y, a, want_jac=True)
    Jf = np.empty_like(J)
    for j in range(y.size):
        h = 1e-7 * max(abs(y[j]), 1.0)
        yp, ym = y.copy(), y.copy()
        yp[j] += h
        ym[j] -= h
        Jf[:, j] = (p.residual(yp, a)[0] - p.residual(ym, a)[0]) / (2 * h)
    # central differences of a piecewise-smooth march: agreement to 1e-6 of the largest entry
    assert np.abs(J - Jf).max() < 1e-6 * np.abs(J).max()


def _peaks(ex, b, harmonics):
    opts = SolverOptions(stability=False)
    out = []
    for lv in ex.levels:
        br = frequency_response(
            ex.system, ex.f1, lv, ex.band_hz, ex.outputs, harmonics=harmonics, options=opts
        )
        i = br.peak(0)
        out.append((br.freq_hz[i], br.out_amp[i, 0], synthesize(b, ex.f1, lv, 0)))
    return out


def test_sdof_synthesis_reproduces_hbm_peaks():
    ex = sdof_jenkins()
    H = (0, 1, 3)
    b = nonlinear_mode(ex.system, f1=ex.f1, harmonics=H, outputs=ex.outputs, levels=ex.levels)
    for f_h, a_h, s in _peaks(ex, b, H):
        assert s.valid, s.reasons
        # the single-mode theory is exact for one DOF but for the shape of the friction
        # loop at other frequencies: 2 % on the peak (measured: 0.2 % at most)
        assert s.peak_amplitude == pytest.approx(a_h, rel=0.02)
        assert s.peak_freq_hz == pytest.approx(f_h, rel=0.01)


def test_two_dof_synthesis_against_full_hbm():
    """Two DOF, normal load following the motion: 4 levels from stuck to sliding.

    Tolerance: 2 % on the peak amplitude where the synthesis says it is valid
    (measured 1.2 % at most), 3 % on its frequency; the level whose peak has
    a damping ratio of 0.19 (a flat, heavily damped peak) is flagged.
    """
    ex = two_dof_contact()
    H = (0, 1, 2, 3)
    b = nonlinear_mode(
        ex.system, f1=ex.f1, band_hz=ex.band_hz, harmonics=H, outputs=ex.outputs, levels=ex.levels
    )
    assert b.completed, b.message
    assert b.mode == 0
    assert b.freq_hz[0] == pytest.approx(b.linear_hz[0], rel=1e-9)
    assert b.freq_hz[-1] < 0.55 * b.freq_hz[0]  # slides: the tangential spring is lost
    valid = []
    for f_h, a_h, s in _peaks(ex, b, H):
        valid.append(s.valid)
        if s.valid:
            assert s.peak_amplitude == pytest.approx(a_h, rel=0.02)
            assert s.peak_freq_hz == pytest.approx(f_h, rel=0.03)
        else:
            assert any("damping ratio" in r for r in s.reasons)
    assert valid == [True, False, True, True]


def test_invalid_synthesis_is_detected():
    """A stiff Jenkins element holds the second mass of a chain: once it slips, the first
    mode turns into the in-phase sliding mode (the backbone folds back in amplitude and
    its shape changes); the synthesis says so, and it is indeed wrong there."""
    m = 0.1
    K = np.array([[8e4, -4e4], [-4e4, 4e4]])
    el = ContactElements.from_dofs(2, [[1]], mu=0.5, kt=4e5, n0=2.0)
    sysm = System(M=np.eye(2) * m, K=K, zeta=0.005, contacts=el)
    f1 = np.array([1.0, 0.0j])
    H = (0, 1, 3)
    b = nonlinear_mode(sysm, f1=f1, harmonics=H, outputs=[0])
    assert b.completed, b.message
    assert np.any(np.diff(b.amplitude) < 0)  # the fold passed by arc length
    assert b.mac.min() < 0.5
    s = synthesize(b, f1, 0.5, 0)
    assert not s.valid
    assert any("folds" in r for r in s.reasons)
    br = frequency_response(
        sysm, f1, 0.5, (45.0, 150.0), [0], harmonics=H, options=SolverOptions(stability=False)
    )
    err = abs(s.peak_amplitude / br.out_amp[br.peak(0), 0] - 1)
    assert err > 0.05


def test_branch_save_load_csv(tmp_path, jenkins):
    _, b = jenkins
    p = b.save(tmp_path / "nm.h5")
    c = NlModeBranch.load(p)
    assert c.n_points == b.n_points
    np.testing.assert_array_equal(c.psi, b.psi)
    assert c.harmonics == b.harmonics and c.completed == b.completed
    csv = b.to_csv(tmp_path / "nm.csv")
    assert len(csv.read_text().splitlines()) == b.n_points + 1


def test_condensed_form_matches_all_dofs():
    """The condensed unknowns (contact displacements + the followed mode) give the same
    backbone as the unknowns on every DOF; its Jacobian matches finite differences."""
    from workbench.hbm.io.examples import line_damper_rig
    from workbench.hbm.nlmodes.backbone import pick_mode, slip_amplitude
    from workbench.hbm.nlmodes.epmc_condensed import EpmcCondensed

    ex = line_damper_rig(n_per_line=3)
    mode = pick_mode(ex.system, ex.f1, ex.band_hz)
    kw = dict(
        mode=mode, harmonics=(0, 1, 3), outputs=ex.outputs, relative_range=(0.8, 1.8), n_steps=6
    )
    bc = nonlinear_mode(ex.system, space="condensed", **kw)
    bp = nonlinear_mode(ex.system, space="physical", **kw)
    assert bc.n_points > 5 and bp.n_points > 5
    assert bc.damping_ratio.max() > 0.05  # through the slip transition
    lo, hi = max(bc.amplitude[0], bp.amplitude[0]), min(bc.amplitude[-1], bp.amplitude[-1])
    A = np.geomspace(lo, hi, 7)[1:-1]
    # both interpolated between their own points: 0.5 % in frequency, 0.01 in D
    fc, fp = np.interp(A, bc.amplitude, bc.freq_hz), np.interp(A, bp.amplitude, bp.freq_hz)
    assert fc == pytest.approx(fp, rel=5e-3)
    dc = np.interp(A, bc.amplitude, bc.damping_ratio)
    dp = np.interp(A, bp.amplitude, bp.damping_ratio)
    assert np.abs(dc - dp).max() < 0.01
    # Jacobian of the condensed form at a slipping state
    p = EpmcCondensed(ex.system, Fourier((0, 1, 3)), mode, ex.outputs)
    a = 1.4 * slip_amplitude(ex.system, mode)
    y = p.linear_guess()
    y = y + 1e-3 * np.random.default_rng(0).standard_normal(y.size) * np.abs(y).max()
    _, _, J = p.residual(y, a, want_jac=True)
    Jf = np.empty_like(J)
    for j in range(y.size):
        h = 1e-7 * max(abs(y[j]), 1e-3)
        yp, ym = y.copy(), y.copy()
        yp[j] += h
        ym[j] -= h
        Jf[:, j] = (p.residual(yp, a)[0] - p.residual(ym, a)[0]) / (2 * h)
    assert np.abs(J - Jf).max() < 1e-5 * np.abs(J).max()


def test_plateau_rule():
    """The amplitude-limit rule fires on a flat amplitude with rising damping only."""
    from workbench.hbm.nlmodes.problem import plateau
    from workbench.hbm.path.problem import Stop

    flat = dict(amplitude=[1.0, 1.0005, 1.001, 1.001, 1.0012, 1.0015], damping_ratio=[])
    flat["damping_ratio"] = [0.010, 0.011, 0.012, 0.013, 0.0125, 0.0121]
    with pytest.raises(Stop, match="amplitude stalls at 1.002"):
        plateau(flat, 6)
    plateau(flat, 0)  # off
    plateau(flat, 7)  # too few points yet
    rising = dict(amplitude=[1.0, 1.01, 1.02, 1.03, 1.04, 1.05], damping_ratio=[0.01] * 5 + [0.02])
    plateau(rising, 6)  # the amplitude still grows
    level = dict(amplitude=flat["amplitude"], damping_ratio=[0.010] * 5 + [0.0119])
    plateau(level, 6)  # the damping does not rise by a fifth


def test_chord_and_krylov_newton_land_on_the_same_points():
    """Full Newton (dense LU at every iteration), the chord iterations (dense LU every 3rd)
    and Newton-Krylov (GMRES on the exact Jacobian with a lagged LU preconditioner, the
    default on condensed problems) give the same synthesised peaks (solved points,
    tolerance 1e-10) where valid, the Krylov one with fewer factorisations; a level beyond
    an unfinished backbone's end is flagged with the backbone's reason."""
    from workbench.hbm.io.examples import line_damper_rig

    ex = line_damper_rig(n_per_line=3, family="out-of-phase", k_line_n_per_m2=5e8, mu=0.5)
    kw = dict(
        f1=ex.f1, band_hz=ex.band_hz, harmonics=(0, 1, 3), outputs=ex.outputs, max_fold_points=20
    )
    levels = (0.096, 3.84, 30.0)
    setups = {"full": ("dense", 1), "chord": ("dense", 3), "krylov": ("auto", 3)}
    runs = {
        k: nonlinear_mode(ex.system, levels=levels, linear=lin, jacobian_lag=lag, **kw)
        for k, (lin, lag) in setups.items()
    }
    syn = {k: [synthesize(b, ex.f1, lv, 0, ex.band_hz) for lv in levels] for k, b in runs.items()}
    for k in ("chord", "krylov"):
        for a, b in zip(syn["full"][:2], syn[k][:2], strict=True):
            assert a.valid and b.valid
            assert b.peak_amplitude == pytest.approx(a.peak_amplitude, rel=1e-6)
            assert b.peak_freq_hz == pytest.approx(a.peak_freq_hz, rel=1e-6)
    fact = {k: b.timings["factorisations"] for k, b in runs.items()}
    assert fact["krylov"] < fact["chord"] < fact["full"], fact
    assert runs["krylov"].timings["krylov_its"] > 0 and runs["full"].timings["krylov_its"] == 0
    for k, b in runs.items():
        assert not b.failed, b.message
        top = syn[k][-1]
        if not b.completed and not top.valid:  # ended before the largest level's peak
            assert b.message in " ".join(top.reasons)


def test_condensed_tangent_operator():
    """The condensed problem's Jacobian operator: its products equal the dense matrix, and
    both equal central differences of the residual, the ``ln a`` column included (exact:
    ``d(G/a)/d ln a = D X - G/a``) at a state with stick-slip and partial lift-off."""
    from workbench.hbm.io.examples import line_damper_rig
    from workbench.hbm.nlmodes.backbone import pick_mode, slip_amplitude

    ex = line_damper_rig(n_per_line=3, family="out-of-phase", k_line_n_per_m2=5e8, mu=0.5)
    mode = pick_mode(ex.system, ex.f1, ex.band_hz)
    p = EpmcCondensed(ex.system, Fourier((0, 1, 3)), mode, ex.outputs)
    a = 3.0 * slip_amplitude(ex.system, mode)
    y = p.linear_guess()
    y = y + 1e-2 * np.random.default_rng(0).standard_normal(y.size) * np.abs(y).max()
    _, res, T = p.tangent(y, a)
    st = np.asarray(res.status).ravel()
    # stick-slip (1) and partial separation (2): the contact Jacobian is not trivial
    assert np.any(st == 1) and np.all((st == 1) | (st == 2))
    J = T.dense()
    assert J.shape == (y.size, y.size + 1)
    v = np.random.default_rng(1).standard_normal(y.size + 1)
    assert np.abs(T.matvec(v) - J @ v).max() < 1e-12 * np.abs(J @ v).max()
    Jf = np.empty_like(J)
    for j in range(y.size + 1):
        if j < y.size:
            h = 1e-7 * max(abs(y[j]), 1e-3)
            yp, ym = y.copy(), y.copy()
            yp[j] += h
            ym[j] -= h
            Jf[:, j] = (p.residual(yp, a)[0] - p.residual(ym, a)[0]) / (2 * h)
        else:  # ln a, with a step where rounding and curvature balance
            h = 1e-5
            rp, rm = p.residual(y, a * np.exp(h))[0], p.residual(y, a * np.exp(-h))[0]
            Jf[:, j] = (rp - rm) / (2 * h)
    assert np.abs(J - Jf).max() < 1e-6 * np.abs(J).max()
    assert np.abs(J[:, -1] - Jf[:, -1]).max() < 1e-6 * np.abs(Jf[:, -1]).max()


def test_stuck_range_is_one_step():
    """Below the first slip every contact sticks: the continuation takes one step from the
    first point to just below the slip amplitude (the mode is linear there)."""
    from workbench.hbm.nlmodes.backbone import slip_amplitude

    ex = two_dof_contact()
    b = nonlinear_mode(ex.system, f1=ex.f1, band_hz=ex.band_hz, harmonics=(0, 1, 2, 3))
    a_slip = slip_amplitude(ex.system, b.mode)
    assert b.amplitude[0] < 0.1 * a_slip and np.all(b.status[0] == 0)
    assert b.amplitude[1] == pytest.approx(0.999 * a_slip, rel=1e-6)  # the next point
    # the stuck mode's frequency holds across the step (to 0.1 %: the preload's mean
    # part moves the first slip a little from the linear estimate, where it is solved)
    assert b.freq_hz[1] == pytest.approx(b.freq_hz[0], rel=1e-3)


def test_synthesised_flanks_sampled_across_the_stuck_range():
    """The continuation crosses the stuck range in one step; the synthesised curve still
    samples its flanks there (the mode is linear: fixed frequency and rates, output
    proportional to amplitude), and those samples are the stuck oscillator's exact
    receptance (Jenkins oscillator, one DOF: the single-mode theory is exact while it
    sticks)."""
    ex = sdof_jenkins()
    sysm = ex.system
    H = (0, 1, 3)
    b = nonlinear_mode(sysm, f1=ex.f1, harmonics=H, outputs=ex.outputs, levels=ex.levels)
    stuck_rows = ~np.any(b.status > 0, axis=1)
    y_stuck = b.out_amp[stuck_rows, 0].max()
    assert stuck_rows.sum() <= 3  # the stuck range is one or two steps of the backbone
    Ks, M, C = sysm.regularised_stiffness(), sysm.M, sysm.damping_matrix()
    checked = 0
    for lv in ex.levels:
        s = synthesize(b, ex.f1, lv, 0)
        on = s.out_amp < 0.999 * y_stuck
        if s.peak_amplitude > y_stuck:  # the peak is past the first slip: flanks are stuck
            assert on.sum() >= 20
        for side in (s.freq_hz < s.peak_freq_hz, s.freq_hz > s.peak_freq_hz):
            yy = s.out_amp[side & on]
            if yy.size > 1:  # no jump along a stuck flank (it was one straight segment)
                assert np.max(yy[1:] / yy[:-1]) < 1.3 and np.min(yy[1:] / yy[:-1]) > 1 / 1.3
        Wr = 2 * np.pi * s.freq_hz[on]
        exact = [abs(np.linalg.solve(Ks - W**2 * M + 1j * W * C, lv * ex.f1)[0]) for W in Wr]
        np.testing.assert_allclose(s.out_amp[on], exact, rtol=1e-6)
        checked += int(on.sum())
    assert checked > 40


def test_a_peak_inside_a_coarse_segment_whose_output_bends_is_flagged():
    """Across the stuck range (one continuation step) the Jenkins oscillator is linear: a
    peak there is exact and valid. If the output per modal amplitude changed across that
    segment (as a shakedown of stuck contacts shifts the mean position on the FE rig), the
    interpolated peak would be a guess: the synthesis says so and is not valid."""
    import dataclasses

    from workbench.hbm.nlmodes.backbone import slip_amplitude

    ex = sdof_jenkins()
    b = nonlinear_mode(ex.system, f1=ex.f1, harmonics=(0, 1, 3), outputs=ex.outputs)
    assert b.amplitude[1] > 10 * b.amplitude[0]  # the stuck range in one step
    # a level whose peak lies inside that segment: the stuck peak x = F / (2 zeta k)
    a_mid = 0.5 * slip_amplitude(ex.system, b.mode)
    lv = None
    for cand in np.geomspace(1e-3, 1.0, 61):
        s = synthesize(b, ex.f1, cand, 0)
        if b.amplitude[0] * 1.5 < s.peak_modal_amplitude < a_mid:
            lv = float(cand)
            break
    assert lv is not None
    s = synthesize(b, ex.f1, lv, 0)
    assert s.valid, s.reasons
    bent = b.out_amp.copy()
    bent[1] *= 1.05  # the far end's output per amplitude 5 % off the near end's
    s2 = synthesize(dataclasses.replace(b, out_amp=bent), ex.f1, lv, 0)
    assert not s2.valid
    assert any("coarse segment" in r and "5.0 %" in r for r in s2.reasons), s2.reasons


def test_a_failed_last_point_never_leaves_the_range_uncovered(monkeypatch):
    """The point exactly at the largest amplitude may fail to converge: the backbone then
    ends at the converged step past it (it still covers the range it claims), never at
    the point before with ``completed`` set as if it had reached the end."""
    from workbench.hbm.nlmodes.problem import BackboneCorrector as Snes

    ex = sdof_jenkins()
    a_slip = slip_amplitude(ex.system, pick_mode(ex.system, ex.f1))
    a0, a1 = 0.5 * a_slip, 20.0 * a_slip
    real = Snes.solve
    hit = []

    def solve(self, Y0, c=None, Yp=None):
        if c is None and float(Y0[-1]) == np.log(a1):  # the guess placed at the end
            hit.append(float(Y0[-1]))
            return Y0, False, 1
        return real(self, Y0, c, Yp)

    monkeypatch.setattr(Snes, "solve", solve)
    b = nonlinear_mode(ex.system, harmonics=(1,), outputs=[0], amplitude_range=(a0, a1))
    assert hit, "the end point was never tried: the test does not test"
    assert b.completed and not b.failed, b.message
    assert b.amplitude[-1] >= a1 * (1 - 1e-12)
    assert np.all(np.diff(b.amplitude) > 0)
