"""Which stuck state does a run-up reach? The harmonic balance against a run-up from rest.

Out of phase, a damper is squeezed and released by its platforms once per
period. Where it slips at low normal load and sticks at high load it can
ratchet into its groove and lock there with a raised normal load: a stuck
periodic state with a mean offset, one of the many the harmonic balance can
converge to. This script computes, for one damper on a rig at one force:

1. the harmonic balance curve (``wb.frf``) and its harmonic-1 peak;
2. a run-up from rest at that peak frequency (:func:`workbench.hbm.timedomain.runup.runup`,
   the same contact law, Newmark condensed onto the contact DOFs);

and plots, period by period, the run-up's harmonic-1 amplitude, mean of the
response and the pairs' mean normal load over their preload, with the
harmonic balance's values as lines. It prints the numbers quoted in
docs/FINDINGS.md. A run can be continued (``--continue``) from the state it
saved.

Check the time step: at 30 N (mu 0.3, 9 mm mesh, 408.05 Hz) the cylinder's
run-up with 128 steps per period leaves the harmonic balance state after 15
periods for one at 0.223 mm, and with 256 steps after 140 periods for a
modulated one; with 512 steps it stays (0.3001 mm, mean -0.0900 mm, 360
periods). At 9.6 N with mu 0.5 the locked state is the same at 128 and 512
steps (docs/notes/mean_position.md).

    .venv/bin/python benchmarks/runup_ratchet.py --damper cylinder --force 9.6 \\
        --mu 0.5 --cf 10000 --periods 500 --out results/runup   # ratchets and locks
    .venv/bin/python benchmarks/runup_ratchet.py --periods 300 --out results/runup  # mu 0.3: slips
"""

from __future__ import annotations

import argparse
import json
import pickle
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--damper", default="cylinder", help="cone, cylinder or wedge")
    ap.add_argument("--force", type=float, default=9.6, help="N on each blade")
    ap.add_argument("--phase", type=float, default=180.0, help="inter-blade phase, deg")
    ap.add_argument("--geometry", default=str(ROOT / "geometry" / "paper_rig.toml"))
    ap.add_argument("--mesh-size", type=float, default=14.0, help="mm")
    ap.add_argument(
        "--mu", type=float, default=None, help="friction coefficient (default: the rig's)"
    )
    ap.add_argument(
        "--cf", type=float, default=None, help="centrifugal force, N (default: the rig's)"
    )
    ap.add_argument("--periods", type=int, default=400, help="periods to integrate")
    ap.add_argument("--steps", type=int, default=128, help="steps per period")
    ap.add_argument("--ramp", type=float, default=0.0, help="ramp the force in over N periods")
    ap.add_argument(
        "--continue",
        dest="cont",
        action="store_true",
        help="continue from the state saved in --out",
    )
    ap.add_argument("--out", default=str(ROOT / "results" / "runup"))
    a = ap.parse_args(argv)

    import workbench as wb
    from workbench.hbm.core.ports import observation
    from workbench.hbm.timedomain.runup import runup

    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    tag = f"{a.damper}_{a.phase:g}deg_{a.force:g}N"
    extra = {k: v for k, v in (("mu", a.mu), ("cf", a.cf)) if v is not None}
    tag += "".join(f"_{k}{v:g}" for k, v in extra.items())
    m = wb.model(
        a.damper,
        out=out / "cache",
        geometry=a.geometry,
        mesh_size=a.mesh_size,
        harmonics=[0, 1, 2, 3],
        **extra,
    )
    t0 = time.perf_counter()
    c = wb.frf(m, force_n=a.force, phase_deg=a.phase)
    t_hbm = time.perf_counter() - t0
    b = c.branch
    i = int(np.argmax(b.out_h1[:, 0]))
    f_pk = float(b.freq_hz[i])
    hbm_h1 = float(b.out_h1[i, 0])
    hbm_mean = float(b.out_harm[i, 0, 0])
    prep = m.prepared
    system = prep.system
    model = prep.assembled
    O = observation(system, model.response_dofs[0:1])
    # the harmonic balance's mean normal load ratio at the peak, from its contact march
    from workbench.hbm.core.balance import HarmonicBalance
    from workbench.hbm.core.fourier import Fourier

    hb = HarmonicBalance(system, model.excitation(a.phase), Fourier(b.harmonics, b.nt), O, a.force)
    ev = hb.evaluate(b.x[i], 2 * np.pi * f_pk)
    hbm_n = float(np.mean(-ev.aft.F[0, :, 2] / system.contacts.n0))
    print(
        f"harmonic balance ({t_hbm:.1f} s): peak {f_pk:.2f} Hz, h1 {hbm_h1 * 1e3:.4f} mm, "
        f"mean {hbm_mean * 1e3:+.4f} mm, mean N/N0 {hbm_n:.3f}, "
        f"friction energy {c.summary()['friction_energy_mj']:.3g} mJ"
    )

    state_file = out / f"{tag}.state.pkl"
    start, prev = None, None
    if a.cont and state_file.is_file():
        prev = pickle.loads(state_file.read_bytes())
        start = prev["state"]

    def progress(done: int, total: int) -> None:
        el = time.perf_counter() - t1
        print(f"  run-up: {done}/{total} periods, {el:.0f} s", file=sys.stderr, flush=True)

    t1 = time.perf_counter()
    ru = runup(
        system,
        model.excitation(a.phase),
        a.force,
        f_pk,
        O,
        periods=a.periods,
        steps_per_period=a.steps,
        ramp_periods=a.ramp,
        start=start,
        progress=progress,
    )
    t_run = time.perf_counter() - t1
    h1 = ru.h1[:, 0]
    mean = ru.mean[:, 0]
    nr = ru.normal_ratio.mean(axis=1)
    slip = ru.slip_samples
    if prev is not None:
        h1, mean = np.concatenate([prev["h1"], h1]), np.concatenate([prev["mean"], mean])
        nr, slip = np.concatenate([prev["nr"], nr]), np.concatenate([prev["slip"], slip])
    state_file.write_bytes(pickle.dumps(dict(state=ru.state, h1=h1, mean=mean, nr=nr, slip=slip)))
    onset = int(np.argmax(slip > 0)) if (slip > 0).any() else -1
    rec = dict(
        damper=a.damper,
        force_n=a.force,
        phase_deg=a.phase,
        geometry=a.geometry,
        cf_n=m.settings.get("cf"),
        freq_hz=f_pk,
        hbm_h1_mm=hbm_h1 * 1e3,
        hbm_mean_mm=hbm_mean * 1e3,
        hbm_normal_ratio=hbm_n,
        periods=int(h1.size),
        runup_s=t_run,
        first_slip_period=onset,
        h1_at_first_slip_mm=float(h1[onset] * 1e3) if onset >= 0 else None,
        end_h1_mm=float(h1[-1] * 1e3),
        end_mean_mm=float(mean[-1] * 1e3),
        end_normal_ratio=float(nr[-1]),
        end_slip_samples=int(slip[-1]),
        mu=float(m.prepared.assembled.mu[0]),
        change_last_10_periods=float(abs(h1[-1] - h1[-11]) / h1[-1]) if h1.size > 11 else None,
    )
    (out / f"{tag}.json").write_text(json.dumps(rec, indent=1))
    print(json.dumps(rec, indent=1))
    _plot(out / f"{tag}.png", rec, h1, mean, nr, slip)
    return 0


def _plot(path: Path, rec: dict, h1, mean, nr, slip) -> None:
    from matplotlib.figure import Figure

    p = np.arange(1, h1.size + 1)
    fig = Figure(figsize=(7.5, 6.4), layout="constrained")
    ax = fig.subplots(3, 1, sharex=True)
    ax[0].plot(p, h1 * 1e3, color="C0", label="run-up from rest")
    ax[0].axhline(rec["hbm_h1_mm"], color="k", ls="--", lw=1, label="harmonic balance")
    ax[0].set_ylabel("blade 1 harmonic-1\namplitude (mm)")
    ax[0].legend(loc="lower right", fontsize=8)
    ax[1].plot(p, mean * 1e3, color="C1")
    ax[1].axhline(rec["hbm_mean_mm"], color="k", ls="--", lw=1)
    ax[1].set_ylabel("blade 1 mean\ndisplacement (mm)")
    ax[2].plot(p, nr, color="C2", label="mean N / N0 over the pairs")
    ax[2].axhline(rec["hbm_normal_ratio"], color="k", ls="--", lw=1)
    ax2 = ax[2].twinx()
    ax2.plot(p, slip, color="C3", lw=0.8, alpha=0.7, label="slipping samples x pairs")
    ax2.set_ylabel("slipping samples\nx pairs per period", color="C3")
    ax[2].set_ylabel("mean normal load /\npreload (-)", color="C2")
    ax[2].set_xlabel("period")
    mu = f", mu {rec['mu']:g}" if rec.get("mu") is not None else ""
    fig.suptitle(
        f"{rec['damper']}, {rec['phase_deg']:g} deg, {rec['force_n']:g} N{mu} at "
        f"{rec['freq_hz']:.1f} Hz: run-up from rest (lines) vs harmonic balance (dashed)",
        fontsize=9,
    )
    fig.savefig(path, dpi=130)
    print(f"figure: {path}")


if __name__ == "__main__":
    raise SystemExit(main())
