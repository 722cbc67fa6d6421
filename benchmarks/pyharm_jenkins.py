"""pyHarm's side of the comparison in bench_hbm.py (run by the pyHarm interpreter, not ours).

The single-DOF Jenkins oscillator (m = 1, k = 1, c = 0.02, kt = 20,
mu N = 1; dimensionless) forced by ``level cos(w t)``, over w = 0.5..3
rad/s with pyHarm's pseudo-arc-length corrector, the same harmonics and
time samples as ours. Prints one JSON object: for each largest step
``--ds-max`` (a comma-separated list: the accuracy/time trade-off of
pyHarm's one step knob), per level the process CPU time of the solve
(compilation excluded: a warm-up run first; the least of ``--repeat``
runs), the number of accepted points,
and the peak inside the band (largest |x(t)| over the period, from the
harmonics on 4096 phases, over the points with w <= the band end: pyHarm
steps past the band end and has no point on it) and its frequency.

pyHarm is benchmark-only, never a dependency of the workbench: install it in
its own virtual environment (it needs numpy 2 and jax) ::

    python3 -m venv .venv-bench && .venv-bench/bin/pip install pyharm-os

    python benchmarks/pyharm_jenkins.py --levels 0.5,1,1.5,2,3 --nh 7 --nti 128
"""

from __future__ import annotations

import argparse
import json
import logging
import time
import warnings

import numpy as np


def run(level: float, nh: int, nti: int, band: tuple[float, float], ds_max: float) -> dict:
    import pyHarm

    d = {
        "system": {"type": "Base", "nh": nh, "nti": nti},
        "substructures": {
            "sub": {
                "type": "substructure",
                "ndofs": 1,
                "matrix": {"M": np.eye(1), "K": np.eye(1), "C": 0.02 * np.eye(1)},
            }
        },
        "connectors": {
            "force": {"type": "CosinusForcing", "connect": {"sub": [0]}, "dirs": [0], "amp": level},
            "jen": {
                "type": "Jenkins", "connect": {"sub": [0]}, "dirs": [0],
                "mu": 1.0, "N0": 1.0, "k": 20.0,
            },
        },
        "analysis": {
            "FRF": {
                "study": "frf", "puls_inf": band[0], "puls_sup": band[1],
                "corrector": "pseudo_arc_length", "ds0": 0.01, "ds_min": 1e-6,
                "ds_max": ds_max, "verbose": False,
            }
        },
        "export": {"status": False},
    }  # fmt: skip
    m = pyHarm.Maestro(d)
    t0 = time.process_time()
    m.operate()
    cpu = time.process_time() - t0
    sols = [s for s in m.nls["FRF"].SolList if s.flag_accepted]
    ph = 2 * np.pi * np.arange(4096) / 4096
    ks = np.arange(1, nh + 1)
    B = np.hstack([np.ones((ph.size, 1)), np.empty((ph.size, 2 * nh))])
    B[:, 1::2] = np.cos(np.outer(ph, ks))
    B[:, 2::2] = np.sin(np.outer(ph, ks))
    amps = np.array([np.abs(B @ np.asarray(s.x)[:-1]).max() for s in sols])
    om = np.array([float(np.asarray(s.x)[-1]) for s in sols])
    i = int(np.argmax(np.where(om <= band[1], amps, -np.inf)))
    return dict(
        level=level, cpu_s=cpu, points=len(sols), peak_amplitude=float(amps[i]),
        peak_omega=float(om[i]), omega_end=float(om.max()),
    )  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--levels", default="0.5,1,1.5,2,3")
    ap.add_argument("--nh", type=int, default=7)
    ap.add_argument("--nti", type=int, default=128)
    ap.add_argument("--band", default="0.5,3.0", help="w0,w1 in rad/s")
    ap.add_argument(
        "--ds-max", default="0.1", help="pyHarm's largest step (its default 0.1), or a list"
    )
    ap.add_argument(
        "--repeat", type=int, default=3, help="runs of each curve; the least CPU is kept"
    )
    ap.add_argument(
        "--whole",
        action="store_true",
        help="the five curves once, no warm-up (the whole process is what is timed, from outside)",
    )
    a = ap.parse_args()
    logging.disable(logging.WARNING)
    warnings.simplefilter("ignore")
    band = tuple(float(v) for v in a.band.split(","))
    if a.whole:  # what a user's script does: import, solve each level once, print the peaks
        d = float(a.ds_max.split(",")[0])
        rows = [run(float(v), a.nh, a.nti, band, d) for v in a.levels.split(",")]
        print(json.dumps(dict(tool="pyHarm", ds_max=d, levels=rows)))
        return
    t0 = time.process_time()
    run(1.0, a.nh, a.nti, (0.9, 1.1), 0.1)  # compile numba/jax kernels (cached on disk)
    warm = time.process_time() - t0
    levels = [float(v) for v in a.levels.split(",")]

    def timed(v: float, d: float) -> dict:  # the least CPU of repeats (machine noise)
        r = run(v, a.nh, a.nti, band, d)
        for _ in range(a.repeat - 1):
            r["cpu_s"] = min(r["cpu_s"], run(v, a.nh, a.nti, band, d)["cpu_s"])
        return r

    sweep = [
        dict(ds_max=float(d), levels=[timed(v, float(d)) for v in levels])
        for d in a.ds_max.split(",")
    ]
    import pyHarm

    print(json.dumps(dict(tool="pyHarm", version=getattr(pyHarm, "__version__", "?"),
                          warm_up_cpu_s=warm, nh=a.nh, nti=a.nti, sweep=sweep)))  # fmt: skip


if __name__ == "__main__":
    main()
