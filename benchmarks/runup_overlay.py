"""Overlay several run-ups of ``benchmarks/runup_ratchet.py`` against their harmonic balance.

Each run is a directory and tag written by ``runup_ratchet.py`` (its
``<tag>.json`` and ``<tag>.state.pkl``); the harmonic balance's lines are
the first run's. Plots, period by period, blade 1's harmonic-1 amplitude,
its mean and the pairs' mean normal load over their preload.

    .venv/bin/python benchmarks/runup_overlay.py \\
        results/runup/cylinder_180deg_30N:"128 steps, switched on" \\
        results/runup_ramp/cylinder_180deg_30N:"128 steps, ramp 100" \\
        --out docs/figures/runup_cylinder_30N.png
"""

from __future__ import annotations

import argparse
import json
import pickle
from pathlib import Path

import numpy as np


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+", help="path/to/<tag>[:label] (without .json)")
    ap.add_argument("--out", required=True, help="figure path (.png)")
    a = ap.parse_args(argv)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.5, 6.4), layout="constrained")
    ax = fig.subplots(3, 1, sharex=True)
    rec = None
    for k, spec in enumerate(a.runs):
        path, _, label = spec.partition(":")
        r = json.loads(Path(path + ".json").read_text())
        s = pickle.loads(Path(path + ".state.pkl").read_bytes())
        rec = rec or r
        p = np.arange(1, len(s["h1"]) + 1)
        kw = dict(color=f"C{k}", lw=1.0, label=label or Path(path).parent.name)
        ax[0].plot(p, np.asarray(s["h1"]) * 1e3, **kw)
        ax[1].plot(p, np.asarray(s["mean"]) * 1e3, **kw)
        ax[2].plot(p, s["nr"], **kw)
    for i, key in enumerate(("hbm_h1_mm", "hbm_mean_mm", "hbm_normal_ratio")):
        lab = "harmonic balance" if i == 0 else None
        ax[i].axhline(rec[key], color="k", ls="--", lw=1, label=lab)
    ax[0].set_ylabel("blade 1 harmonic-1\namplitude (mm)")
    ax[1].set_ylabel("blade 1 mean\ndisplacement (mm)")
    ax[2].set_ylabel("mean normal load /\npreload (-)")
    ax[2].set_xlabel("period")
    ax[0].legend(loc="lower right", fontsize=7)
    fig.suptitle(
        f"{rec['damper']}, {rec['phase_deg']:g} deg, {rec['force_n']:g} N, mu {rec['mu']:g}, "
        f"at the harmonic balance peak {rec['freq_hz']:.2f} Hz: run-ups from rest",
        fontsize=9,
    )
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(a.out, dpi=130)
    print(f"figure: {a.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
