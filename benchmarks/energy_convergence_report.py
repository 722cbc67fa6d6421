"""Tables, observed orders and the chart of benchmarks/energy_convergence.py (from its cache)."""

from __future__ import annotations

from pathlib import Path

QUANTITIES = (("energy_v_mj", "E (mJ)"), ("amp_v_mm", "A (mm)"), ("freq_v_hz", "f (Hz)"))


def _ladder(runs, base, ladders, key, case, knob):
    rows = []
    for v in ladders[knob]:
        r = runs.get(key(case, dict(base, **{knob: v})))
        if r is not None:
            rows.append((v, r))
    return rows


def _fmt(x, d=4):
    return "-" if x is None else f"{x:.{d}f}"


def limits(rows, fineness, knob):
    """Richardson estimate (workbench/post/extrapolation.py) of each quantity on a ladder."""
    from workbench.post.extrapolation import richardson

    h = [fineness[knob](v) for v, _ in rows]
    return {q: richardson(h, [r.get(q) for _, r in rows]) for q, _ in QUANTITIES}


def report(runs, base, ladders, fineness, cases, key, out: Path) -> dict:
    """Print every ladder's table and its Richardson limits; write the chart; the limits."""
    found = {}
    for knob in ladders:
        for case in cases:
            rows = _ladder(runs, base, ladders, key, case, knob)
            if len(rows) < 2:
                continue
            est = limits(rows, fineness, knob)
            found[(knob, case)] = (rows, est)
            print(f"\n{knob} ladder, {case} (30 N), others at the main job's setting")
            print(
                f"| {knob} | E (mJ) | A (mm) | f (Hz) | E vs finest (%) | pairs | "
                "k g_t mean (CV) | solve (s) |"
            )
            print("|---|---|---|---|---|---|---|---|")
            e_fin = min(rows, key=lambda t: fineness[knob](t[0]))[1]["energy_v_mj"]
            for v, r in rows:
                e = r["energy_v_mj"]
                d = None if e is None or e_fin in (None, 0) else 100 * (e - e_fin) / e_fin
                kg = _kg(r)
                print(
                    f"| {v} | {_fmt(r['energy_v_mj'], 3)} | {_fmt(r['amp_v_mm'], 5)} | "
                    f"{_fmt(r['freq_v_hz'], 2)} | {_fmt(d, 2)} | {r['n_pairs']} | {kg} | "
                    f"{r['solve_s']} |"
                )
            for q, label in QUANTITIES:
                e = est[q]
                if e.asymptotic:
                    print(
                        f"  {label}: limit {e.value:.5g} +- {e.uncertainty:.2g}, observed order "
                        f"{e.order:.2f}; base off the limit by "
                        f"{_fmt(e.error_pct(_base_value(runs, base, key, case, q)), 2)} %"
                    )
                else:
                    order = "" if e.order is None else f" (fitted order {e.order:.2f})"
                    print(f"  {label}: not asymptotic{order}: {e.reason}")
    chart(found, base, fineness, cases, out / "energy_convergence.png", runs, key)
    return found


def _kg(r: dict) -> str:
    """The structure's tangential compliance at the pairs in units of the spring's: the
    mean over the pairs and its coefficient of variation (workbench/assembly/flexibility)."""
    import numpy as np

    if "kg_t" not in r:
        return "-"
    k = np.asarray(r["kg_t"])
    return f"{k.mean():.2f} ({k.std() / k.mean():.2f})"


def _base_value(runs, base, key, case, q):
    r = runs.get(key(case, dict(base)))
    return None if r is None else r.get(q)


def chart(found, base, fineness, cases, path: Path, runs, key) -> None:
    """Energy against each knob's fineness, relative to the main job's setting, with the
    Richardson limit (a star and its band) where the ladder is asymptotic."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    knobs = sorted({k for k, _ in found}, key=list(fineness).index)
    if not knobs:
        return
    fig, axes = plt.subplots(1, len(knobs), figsize=(3.6 * len(knobs), 3.6), sharey=True)
    axes = [axes] if len(knobs) == 1 else list(axes)
    colours = dict(zip(cases, ("#0072B2", "#D55E00", "#009E73"), strict=False))
    for ax, knob in zip(axes, knobs, strict=True):
        for case in cases:
            if (knob, case) not in found:
                continue
            rows, est = found[(knob, case)]
            e0 = _base_value(runs, base, key, case, "energy_v_mj")
            if not e0:
                continue
            ok = [(v, r) for v, r in rows if r["energy_v_mj"] is not None]
            h = [fineness[knob](v) for v, _ in ok]
            e = [r["energy_v_mj"] / e0 for _, r in ok]
            ax.plot(h, e, "o-", color=colours[case], label=case, ms=4)
            lim = est["energy_v_mj"]
            if lim.asymptotic:
                ax.plot([0], [lim.value / e0], "*", color=colours[case], ms=10)
                ax.errorbar(
                    [0],
                    [lim.value / e0],
                    yerr=[lim.uncertainty / e0],
                    color=colours[case],
                    capsize=3,
                )
        ax.axhline(1.0, color="0.6", lw=0.8, ls=":")
        ax.set_xlim(left=-0.05 * max(ax.get_xlim()[1], 1e-9))
        ax.set_xlabel(_xlabel(knob))
        ax.set_title(knob)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("friction energy / main job's (-)")
    axes[0].legend(fontsize=7)
    fig.suptitle(
        "Friction energy per cycle at the 30 N peak, paper-like rig "
        "(star: Richardson limit, shown only where asymptotic)",
        fontsize=9,
    )
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    print(f"\nchart: {path}")


def _xlabel(knob: str) -> str:
    return {
        "mesh-size": "global mesh size h (mm)",
        "contact-size": "mesh size at the contact points (mm)",
        "modes": "1 / modes",
        "harmonics": "1 / highest harmonic",
        "nt": "1 / nt",
        "points-per-line": "1 / points per line",
    }[knob]


def pattern_table(runs: dict, variants: dict) -> None:
    """The cone's contact pattern in phase at its peak, per variant: status counts per
    line, where the stuck pairs sit, and the shape of the relative motion along the line
    (tangential amplitude at the ends against the centre, the normal rocking)."""
    import numpy as np

    rows = [(n, runs.get("pattern | " + n)) for n in variants]
    rows = [(n, r) for n, r in rows if r is not None]
    if not rows:
        return
    print("\nThe cone in phase at its peak: contact pattern per variant (per line of 23 pairs)")
    print(
        "| variant | A (mm) | f (Hz) | E (mJ) | stuck / slip / opening | status along line 1 | "
        "along line 2 (large end first) | u_t centre (um) | u_t ends / centre | "
        "u_n ends (um) | mu N0 / kt (um) |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name, r in rows:
        st = np.asarray(r["status"])
        ut, un = (np.asarray(r[k]) for k in ("ut_um", "un_um"))
        n = len(st) // 2
        counts = [int(np.sum(st == s)) / 2 for s in (0, 1)]
        counts.append(int(np.sum(st >= 2)) / 2)
        sym = "#xo"  # stuck, slipping, opening for part of the period
        lines = [
            "".join(sym[min(int(v), 2)] for v in st[:n]),
            "".join(sym[min(int(v), 2)] for v in st[n:]),
        ]
        mid = slice(n // 2 - 2, n // 2 + 3)
        c = float(np.mean(np.r_[ut[:n][mid], ut[n:][mid]]))
        ends = float(np.mean(np.r_[ut[:2], ut[n - 2 : n], ut[n : n + 2], ut[-2:]]))
        une = float(np.mean(np.r_[un[:2], un[n - 2 : n], un[n : n + 2], un[-2:]]))
        lim = float(np.mean(np.asarray(r["n0_n"]) * 1e6 / np.asarray(r["kt_n_per_m"]))) * 0.3
        print(
            f"| {name} | {r['amp_v_mm']:.4f} | {r['freq_v_hz']:.1f} | {r['energy_v_mj']:.2f} | "
            f"{counts[0]:g} / {counts[1]:g} / {counts[2]:g} | `{lines[0]}` | `{lines[1]}` | "
            f"{c:.2f} | "
            f"{ends / c:.2f} | {une:.2f} | {lim:.2f} |"
        )


def same_kg_table(runs: dict, levels, base, key) -> None:
    """Points per line with the contact mesh scaled to hold n h: the quadrature alone."""
    found = []
    for n, h in levels:
        st = dict(base, **{"points-per-line": n, "contact-size": h})
        rs = [runs.get(key(c, st)) for c in ("cone in phase", "cone out of phase")]
        if all(rs):
            found.append((n, h, rs))
    if not found:
        return
    print("\nPoints per line at a fixed n x contact size (the node-to-spring compliance held)")
    print(
        "| points | contact size (mm) | k g_t mean | in phase E / A / f | out of phase E / A / f |"
    )
    print("|---|---|---|---|---|")
    for n, h, (a, b) in found:
        print(
            f"| {n} | {h} | {_kg(a)} | {a['energy_v_mj']:.2f} / {a['amp_v_mm']:.4f} / "
            f"{a['freq_v_hz']:.1f} | {b['energy_v_mj']:.2f} / {b['amp_v_mm']:.4f} / "
            f"{b['freq_v_hz']:.1f} |"
        )
