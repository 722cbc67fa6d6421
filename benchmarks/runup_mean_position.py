"""A stuck contact's locked-in force and mean position: harmonic balance against run-ups.

Prints the tables of docs/notes/mean_position.md (two-DOF example and its
planar variant): at each frequency the harmonic balance's periodic state
(harmonics 0-5, 128 samples) and run-ups from rest with the force switched
on or ramped in, each integrated until its periods repeat
(:mod:`workbench.hbm.timedomain.periodic_check`). For the planar variant
with the circular law it also marches each run-up's own last period with
growth 0 and with the law's growth and compares the forces with the
run-up's.

    .venv/bin/python benchmarks/runup_mean_position.py            # about 1 min
    .venv/bin/python benchmarks/runup_mean_position.py --slow     # adds ramps of 10000 periods
"""

from __future__ import annotations

import argparse
import time

import numpy as np

H = (0, 1, 2, 3, 4, 5)
LEVEL = 0.5  # N


def _hbm(ex, freqs):
    from workbench.hbm.core.balance import HarmonicBalance
    from workbench.hbm.core.fourier import Fourier
    from workbench.hbm.forced.response import frequency_response
    from workbench.hbm.timedomain.periodic_check import hbm_state, solve_hbm

    b = frequency_response(ex.system, ex.f1, LEVEL, ex.band_hz, ex.outputs, harmonics=H, nt=128)
    hb = HarmonicBalance(ex.system, ex.f1, Fourier(H, 128), ex.outputs, LEVEL)
    out = {}
    for f in freqs:
        i = int(np.argmin(abs(b.freq_hz - f)))
        out[f] = hbm_state(hb, solve_hbm(hb, f, b.x[i]), f)
    return out


def _hbs(ex):
    from workbench.hbm.core.balance import HarmonicBalance
    from workbench.hbm.core.fourier import Fourier

    return {
        n: HarmonicBalance(ex.system, ex.f1, Fourier(H, n), ex.outputs, LEVEL)
        for n in (128, 256, 512)
    }


def two_dof(law: str, runs) -> None:
    from workbench.hbm.io.examples import two_dof_contact
    from workbench.hbm.timedomain.periodic_check import residual_of, runup_state

    ex = two_dof_contact(law=law)
    freqs = (150.0, 208.6, 186.0)
    hbm = _hbm(ex, freqs)
    hbs = _hbs(ex)
    print(f"\ntwo-DOF example, {law} law, {LEVEL} N: x in um, forces in N")
    print("| case | source | h1 x | mean x | mean T | locked-in c | settled | residual |")
    for f in freqs:
        h = hbm[f]
        print(
            f"| {f:g} Hz | harmonic balance | {h.h1[0] * 1e6:.4f} | {h.mean[0] * 1e6:+.4f} | "
            f"{h.t_mean[0, 0]:.4f} | {h.locked[0, 0]:.4f} (spread {h.locked_spread[0, 0]:.3g}, "
            f"slip {h.n_slip[0]}) | | |"
        )
        for ramp, spp in runs:
            t0 = time.perf_counter()
            r = runup_state(ex.system, ex.f1, LEVEL, f, ex.outputs, ramp, steps_per_period=spp,
                            max_periods=ramp + 4000)  # fmt: skip
            res = residual_of(hbs[spp], r.u, f)[0]
            wall = time.perf_counter() - t0
            print(
                f"| {f:g} Hz | run-up ramp {ramp}, {spp} steps ({wall:.1f} s) | "
                f"{r.h1[0] * 1e6:.4f} | {r.mean[0] * 1e6:+.4f} | {r.t_mean[0, 0]:.4f} | "
                f"{r.locked[0, 0]:.4f} | {r.settled} | {res:.2g} |"
            )


def planar(runs, f_hz: float = 209.0) -> None:
    from workbench.contact.march import march
    from workbench.hbm.core.fourier import Fourier
    from workbench.hbm.io.examples import planar_contact
    from workbench.hbm.timedomain.periodic_check import residual_of, runup_state

    ex = planar_contact("circular")
    el = ex.system.contacts
    g_law = 32  # the growth compared with the march from rest (the law's rule, growth 0)
    h = _hbm(ex, (f_hz,))[f_hz]
    hbs = _hbs(ex)
    print(f"\nplanar variant, circular law, {LEVEL} N, {f_hz:g} Hz (um, N)")
    print(
        f"harmonic balance (growth {g_law}): h1 x {h.h1[0] * 1e6:.4f}, mean x "
        f"{h.mean[0] * 1e6:+.4f}, c {np.round(h.locked[0], 4)}, slip {h.n_slip[0]}"
    )
    print(f"| run-up | run-up c | growth 0: c, max diff | growth {g_law}: c, max diff | residual |")
    for ramp, spp in runs:
        r = runup_state(ex.system, ex.f1, LEVEL, f_hz, ex.outputs, ramp, steps_per_period=spp,
                        max_periods=ramp + 4000)  # fmt: skip
        fo = Fourier(H, r.u.shape[1])
        cells = []
        for g in (0, g_law):
            out = march(
                r.u, fo.E, fo.P, el.mu, el.kt1, el.kt2, el.kn, el.n0, "circular", False,
                active=el.active, lp=el.lp, growth=g,
            )  # fmt: skip
            c = (out["f"][0, :, :2] - el.kt1[0] * r.u[0, :, :2]).mean(axis=0)
            d = np.abs(out["f"][..., :2] - r.f[..., :2]).max()
            cells.append(f"{np.round(c, 4)}, {d:.2g}")
        res = [residual_of(hbs[spp], r.u, f_hz, g)[0] for g in (0, g_law)]
        print(
            f"| ramp {ramp}, {spp} steps (settled {r.settled}) | {np.round(r.locked[0], 4)} | "
            f"{cells[0]} | {cells[1]} | {res[0]:.2g} / {res[1]:.2g} |"
        )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--slow", action="store_true", help="add ramps of 10000 periods")
    a = ap.parse_args(argv)
    runs = [(0, 128), (100, 128), (1000, 256), (3000, 256)]
    two_dof("decoupled", runs)
    two_dof("circular", runs[:2])
    pruns = [(0, 128), (1000, 256), (3000, 256)] + ([(10000, 256)] if a.slow else [])
    planar(pruns)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
