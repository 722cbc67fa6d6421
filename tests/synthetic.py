"""Synthetic study results shaped like real ones, for the figure, table and report tests.

Each case is the first-harmonic balance of a one-degree-of-freedom blade
mode (modal mass ``m``, stiffness of the free blades ``k``, structural loss
factor ``eta``) coupled by ``n`` Jenkins elements, one per contact pair.
Pair ``j`` sees the slip ``g_j a`` when the response amplitude is ``a``
(``g_j`` is the pair's share of the relative platform motion, set by the
damper and the mode family) and has stiffness ``kt_j`` and slip limit
``kt_j a_cj``. Its describing function is exact (Griffin): with
``cos(beta) = 1 - 2 a_cj / (g_j a)``,

    k_eq = kt_j (beta - sin(2 beta) / 2) / pi,   E_j = 4 kt_j a_cj (g_j a - a_cj)

(stuck when ``g_j a <= a_cj``: ``k_eq = kt_j``, ``E_j = 0``). Solving
``|k + sum g_j^2 k_eq - m w^2 + i (eta k_s + sum E_j / (pi a^2))| a = F``
for ``w`` at each amplitude gives both sides of the peak, which are laid
end to end in continuation order (low-frequency side up, high side down).
A separation softening (wedge, in-phase) makes the high side fold back; the
points where the frequency runs backwards along the path are marked
unstable, as Hill's method does at the saddle-node turning points of a
single-mode response.

What it shows, as the real studies do (Denimal et al., "On the efficiency
of a conical under-platform damper for turbines"): out-of-phase, every
damper slips along its whole contact; in-phase, the cylinder rolls (pure
linear response, no friction energy beyond round-off), the cone slips at
the two ends of each line and stays stuck in the middle, the wedge slips,
separates and softens. Energies grow with the force. Stuck pairs carry
round-off energies of order 1e-21 J, like a real time march. Fixed seed.
"""

from __future__ import annotations

import numpy as np

from workbench.hbm.forced.branch import Branch
from workbench.post.results import CaseResult, StudyResults

DAMPERS = ("cone", "cylinder", "wedge")
PHASES = (0.0, 180.0)
FORCES = (0.96, 9.6, 30.0)
M_KG = 0.3  # modal mass of the blade mode
BANDS_HZ = {0.0: (290.0, 440.0), 180.0: (330.0, 430.0)}

# (free-blade frequency Hz, stuck frequency Hz, slip amplitude a_c of a pair with g = 1 (m),
#  loss factor, separation softening (fraction of the stuck stiffness), separation onset (m))
_MODEL = {
    ("cone", 0.0): (309.0, 392.0, 6.0e-5, 0.004, 0.0, 0.0),
    ("cylinder", 0.0): (309.0, 309.0, 4.0e-5, 0.004, 0.0, 0.0),
    ("wedge", 0.0): (309.0, 423.0, 4.0e-5, 0.004, 0.08, 5.0e-5),
    ("cone", 180.0): (309.0, 409.5, 6.0e-5, 0.004, 0.0, 0.0),
    ("cylinder", 180.0): (309.0, 409.0, 6.0e-5, 0.004, 0.0, 0.0),
    ("wedge", 180.0): (309.0, 410.5, 6.5e-5, 0.004, 0.0, 0.0),
}


def contact_layout(damper: str, n_per_line: int = 23) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Synthetic contact points (m), sides and normalised positions along the line (0..1).

    Cone and cylinder: ``n_per_line`` points on each of two lines along y
    (side 0 at x < 0, then side 1), ordered from the large end (-y).
    Wedge: on each face a staggered grid of 5 rows of 15/14/15/14/15 points.
    """
    pts, side, xi = [], [], []
    for s, sign in ((0, -1.0), (1, 1.0)):
        if damper == "wedge":
            for row in range(5):
                n = 15 if row % 2 == 0 else 14
                t = (np.arange(n) + (0.5 if row % 2 == 0 else 1.0)) / 15.0
                for tt in t:
                    pts.append(
                        [sign * (0.004 + 0.0015 * row), -0.02 + 0.04 * tt, 0.186 + 0.0015 * row]
                    )
                    side.append(s)
                    xi.append(tt)
        else:
            t = (np.arange(n_per_line) + 0.5) / n_per_line
            for tt in t:
                pts.append([sign * 0.012, -0.02 + 0.04 * tt, 0.196])
                side.append(s)
                xi.append(tt)
    return np.array(pts), np.array(side, dtype=int), np.array(xi)


def _gains(
    damper: str, phase_deg: float, xi: np.ndarray, rng: np.random.Generator, slip_scale: float
) -> np.ndarray:
    """Share of the relative platform motion that each pair has to slip."""
    n = xi.size
    if abs(phase_deg - 180.0) < 1e-9:
        return 1.0 + 0.08 * np.cos(2 * np.pi * xi) + 0.02 * rng.standard_normal(n)
    if damper == "cylinder":
        return np.zeros(n)  # rolls: no slip at all
    if damper == "cone":
        return slip_scale * np.abs(2.0 * xi - 1.0)  # ends slip, the middle rolls
    return 0.9 + 0.1 * rng.random(n)


def _describing(
    gj: np.ndarray, a: float, ac: np.ndarray, kt: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Per pair: equivalent stiffness (N/m, on the modal coordinate) and energy per cycle (J)."""
    u = gj * a
    slip = u > ac
    r = np.where(slip, ac / np.maximum(u, 1e-300), 1.0)
    beta = np.arccos(np.clip(1.0 - 2.0 * r, -1.0, 1.0))
    keq = np.where(slip, kt * (beta - 0.5 * np.sin(2 * beta)) / np.pi, kt)
    energy = np.where(slip, 4.0 * kt * ac * (u - ac), 0.0)
    return gj**2 * keq, energy


def synthetic_case(
    damper: str,
    phase_deg: float,
    force_n: float,
    *,
    seed: int = 0,
    points: np.ndarray | None = None,
    side: np.ndarray | None = None,
    slip_scale: float = 1.0,
    cf_scale: float = 1.0,
    n_side: int = 120,
    fail_at: float | None = None,
    params: dict | None = None,
    variant: str = "",
) -> CaseResult:
    """One case: a Branch over the family's band, statuses and energies of every pair.

    ``points``/``side`` replace the synthetic layout (e.g. the contact
    points of a built geometry, ordered side 0 then side 1). ``slip_scale``
    scales the in-phase slip of the cone (a cone-angle sweep);
    ``cf_scale`` scales every slip limit (the preload, a CF sweep).
    ``fail_at`` (0..1) cuts the branch at that fraction of its points and
    marks it failed, as a diverged corrector would.
    """
    rng = np.random.default_rng(
        [
            seed,
            int(round(phase_deg)),
            int(round(force_n * 1000)),
            DAMPERS.index(damper) if damper in DAMPERS else 9,
        ]
    )
    if points is None:
        points, side, xi = contact_layout(damper)
    else:
        side = np.asarray(side, dtype=int)
        xi = np.zeros(len(points))
        for s in (0, 1):
            k = np.flatnonzero(side == s)
            y = points[k, 1]
            xi[k] = (y - y.min()) / max(float(np.ptp(y)), 1e-12)
    n = len(points)
    f_free, f_stuck, ac0, eta, soft, onset = _MODEL[(damper, phase_deg)]
    k = M_KG * (2 * np.pi * f_free) ** 2
    gj = _gains(damper, phase_deg, xi, rng, slip_scale)
    kt_total = M_KG * (2 * np.pi * f_stuck) ** 2 - k
    g2 = gj**2
    kt = np.full(n, kt_total / max(float(g2.sum()), 1e-30)) if g2.sum() > 0 else np.zeros(n)
    ac = ac0 * cf_scale * (1.0 + 0.1 * rng.standard_normal(n))
    ks = k + kt_total
    band = BANDS_HZ[phase_deg]

    def terms(a: float) -> tuple[float, float, np.ndarray]:
        keq, energy = _describing(gj, a, ac, kt)
        stiff = k + float(keq.sum())
        if soft:
            stiff -= soft * ks * max(0.0, a / onset - 1.0)
        return stiff, eta * ks + float(energy.sum()) / (np.pi * a * a), energy

    def excess(a: float) -> float:
        return force_n / a - terms(a)[1]

    # largest amplitude: where the two sides of the peak meet
    lo, hi = 1e-12, 1.0
    for _ in range(200):
        mid = np.sqrt(lo * hi)
        lo, hi = (mid, hi) if excess(mid) > 0 else (lo, mid)
    a_max = lo
    w_lo, w_hi = 2 * np.pi * band[0], 2 * np.pi * band[1]
    a_min = force_n / max(abs(ks - M_KG * w_lo**2), abs(ks - M_KG * w_hi**2)) * 0.5
    t = np.sin(0.5 * np.pi * np.linspace(0.0, 1.0, n_side)) ** 1.5
    amps = a_min * (a_max / a_min) ** t
    amps[-1] = a_max * (1 - 1e-9)
    rows = []
    for sign, seq in ((-1.0, amps), (1.0, amps[::-1])):
        for a in seq:
            stiff, damp, energy = terms(a)
            disc = max((force_n / a) ** 2 - damp**2, 0.0)
            w2 = (stiff + sign * np.sqrt(disc)) / M_KG
            if w2 <= 0:
                continue
            f = np.sqrt(w2) / (2 * np.pi)
            if band[0] <= f <= band[1]:
                rows.append((f, a, energy))
    freq = np.array([r[0] for r in rows])
    amp = np.array([r[1] for r in rows])
    energy = np.array([r[2] for r in rows])
    # unstable where the path runs backwards in frequency (a saddle-node fold)
    df = np.diff(freq)
    stable = np.ones(freq.size, bool)
    stable[1:] &= df >= 0
    # status: stuck / stick-slip by slip; separation when the wedge opens in-phase
    u = amp[:, None] * gj[None, :]
    status = np.where(u > ac[None, :], 1, 0).astype(np.int8)
    if damper == "wedge" and phase_deg == 0.0:
        row = np.arange(n) % 73 // 15 if n == 146 else np.zeros(n)
        sep = amp[:, None] > (1.0 + 0.15 * row[None, :]) * onset
        status = np.where(sep, 2, status).astype(np.int8)
        status = np.where(amp[:, None] > (1.6 + 0.15 * row[None, :]) * onset, 3, status)
        energy = np.where(status == 3, 0.0, energy * np.where(status == 2, 0.6, 1.0))
    energy = energy + np.where(status == 0, 1e-21 * rng.random(energy.shape), 0.0)
    npts = freq.size
    if fail_at is not None:
        npts = max(2, int(fail_at * freq.size))
    sl = slice(0, npts)
    w_fric = energy.sum(axis=1)
    w_visc = np.pi * eta * ks * amp**2
    br = Branch(
        level=force_n,
        band_hz=band,
        harmonics=(0, 1, 2, 3),
        nt=64,
        output_names=("blade1_x",),
        freq_hz=freq[sl],
        stable=stable[sl],
        newton_its=np.full(npts, 3),
        energy_residual=np.full(npts, 1e-9),
        out_amp=amp[sl, None] * 1.02,
        out_h1=amp[sl, None],
        out_harm=np.zeros((npts, 7, 1)),
        status=status[sl],
        friction_energy=energy[sl],
        x=np.zeros((npts, 0)),
        work_ext=(w_fric + w_visc)[sl],
        work_visc=w_visc[sl],
        work_friction=w_fric[sl],
        work_normal=np.zeros(npts),
        max_floquet_real=np.where(stable[sl], -1.0, 5.0),
        completed=fail_at is None,
        failed=fail_at is not None,
        message=(
            f"corrector diverged at {freq[npts - 1]:.1f} Hz (DIVERGED_LINE_SEARCH)"
            if fail_at is not None
            else ""
        ),
        timings={"total": 0.5},
    )
    return CaseResult(
        damper=damper,
        phase_deg=phase_deg,
        force_n=force_n,
        branch=br,
        points=np.asarray(points, float),
        side=np.asarray(side, int),
        params=dict(params or {}),
        variant=variant,
        timings={"hbm": 0.5},
    )


def synthetic_study(
    dampers: tuple[str, ...] = DAMPERS,
    phases: tuple[float, ...] = PHASES,
    forces: tuple[float, ...] = FORCES,
    *,
    seed: int = 0,
    fail: tuple[str, float, float] | None = None,
    layouts: dict[str, tuple[np.ndarray, np.ndarray]] | None = None,
    name: str = "synthetic",
) -> StudyResults:
    """A comparison study: every damper x family x force (plan order).

    ``fail = (damper, phase_deg, force_n)`` makes that case's branch stop
    at 60 % of its points with a failure message.
    """
    cases = []
    for d in dampers:
        for p in phases:
            for f in forces:
                failing = fail is not None and fail == (d, p, f)
                pts, sd = (layouts or {}).get(d, (None, None))
                cases.append(
                    synthetic_case(
                        d, p, f, seed=seed, points=pts, side=sd, fail_at=0.6 if failing else None
                    )
                )
    return StudyResults(
        name=name,
        kind="comparison",
        cases=cases,
        inputs={"dampers": list(dampers), "phases": list(phases), "forces": list(forces)},
        timings={"hbm": 0.5 * len(cases)},
    )


def synthetic_sweep(
    option: str,
    values: tuple[float, ...],
    *,
    dampers: tuple[str, ...] = DAMPERS,
    phases: tuple[float, ...] = PHASES,
    forces: tuple[float, ...] = (30.0,),
    seed: int = 0,
) -> StudyResults:
    """A sweep study of ``option`` ("cf", N, or "cone-angle", deg) over ``values``.

    CF scales the slip limits (preload) in proportion to ``value / values[0]``;
    the cone angle scales the cone's in-phase slip by the paper's eq 6
    (``workbench.analytic.max_slip_ratio``) relative to 10 deg. Dampers other
    than the cone ignore the cone angle.
    """
    from workbench.analytic import max_slip_ratio

    cases = []
    for d in dampers:
        for p in phases:
            for f in forces:
                for v in values:
                    kw: dict = {}
                    if option == "cf":
                        kw["cf_scale"] = v / values[0]
                    elif option == "cone-angle" and d == "cone":
                        kw["slip_scale"] = float(
                            max_slip_ratio(v, 45.0, 10.0, 40.0)
                            / max_slip_ratio(10.0, 45.0, 10.0, 40.0)
                        )
                    cases.append(
                        synthetic_case(
                            d, p, f, seed=seed, params={option: v}, variant=f"{option}={v:g}", **kw
                        )
                    )
    return StudyResults(
        name=f"sweep-{option}",
        kind="sweep",
        cases=cases,
        inputs={
            "sweep": option,
            "sweep-values": list(values),
            "dampers": list(dampers),
            "phases": list(phases),
            "forces": list(forces),
        },
    )
