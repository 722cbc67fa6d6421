"""The design rule chart: the nonlinear answer against the linear coupling screen.

For a sweep study (a rig or damper parameter swept), each swept model gives
one point per damper and family: the nonlinear peak growth ``A(F_max) /
A(F_ref)`` (``F_ref`` the study force nearest ``0.32 F_max``, 9.6 N for
30 N) and the friction energy per cycle at ``F_max``, against the screen's
``k2/k`` and its predicted saturation force. Where the single-mode rule
holds, the filled markers (nonlinear) sit on the open ones (screen). The
peaks are max |x(t)| (as docs/FINDINGS.md quotes this chart), colour and
marker name the damper, line style the family (dotted: the screen).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .common import pyplot, save_figure, styled


def design_rule_points(
    cases: Sequence[Any], screen_rows: Sequence[dict[str, Any]]
) -> list[dict[str, Any]]:
    """One record per (damper, family, variant) with both the screen and the nonlinear numbers.

    ``cases``: the study's CaseResults; ``screen_rows``: its screen rows
    (``damper``, ``variant``, ``phase_deg``, ``k2_over_k``, ``f_cap_n``,
    ``growth``, ...). Peaks that a curve did not reach (a case stopped early)
    make the record's nonlinear numbers None, never a value.
    """
    forces = sorted({float(c.force_n) for c in cases})
    if len(forces) < 2:
        return []
    f_max = forces[-1]
    f_ref = min(forces[:-1], key=lambda f: abs(f - 0.32 * f_max))
    out = []
    for row in screen_rows:
        sel = [
            c
            for c in cases
            if c.damper == row["damper"]
            and c.variant == row["variant"]
            and abs(c.phase_deg - row["phase_deg"]) < 1e-9
        ]
        by_f = {float(c.force_n): c for c in sel}
        rec = dict(row)
        rec.update(
            {
                "f_ref_n": f_ref,
                "f_top_n": f_max,
                "growth_nl": None,
                "energy_mj": None,
                "peak_top_mm": None,
            }
        )
        top, ref = by_f.get(f_max), by_f.get(f_ref)
        if top is not None and ref is not None and _reached(top) and _reached(ref):
            a_top = top.summary()["peak_amplitude_mm"]
            a_ref = ref.summary()["peak_amplitude_mm"]
            if a_top and a_ref:
                rec["growth_nl"] = a_top / a_ref
                rec["peak_top_mm"] = a_top
                rec["energy_mj"] = top.summary()["friction_energy_mj"]
        out.append(rec)
    return out


def _reached(case: Any) -> bool:
    """True when the case's curve went over its peak (completed, not stopped early)."""
    b = case.branch
    return bool(b.completed) and not bool(b.failed) and case.peak_index >= 0


@styled
def plot_design_rule(
    points: Sequence[dict[str, Any]], path: str | Path | None, *, title: str = ""
) -> Any:
    """Peak growth and friction energy against k2/k and the predicted saturation force.

    Writes a PNG at ``path`` (or returns the Figure when ``path`` is None)."""
    from .palette import damper_style, family_linestyle

    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(13.5, 4.2))
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for p in points:
        groups.setdefault((p["damper"], p["family"]), []).append(p)
    seps: list[str] = []
    f_top = points[0]["f_top_n"] if points else 0.0
    f_ref = points[0]["f_ref_n"] if points else 0.0
    for (damper, fam), pts in sorted(groups.items()):
        col, _, mk = damper_style(damper)
        fls = family_linestyle(fam)
        lab = f"{damper}, {fam}"
        x = np.array([p["k2_over_k"] for p in pts])
        g_nl = np.array([np.nan if p["growth_nl"] is None else p["growth_nl"] for p in pts])
        g_sc = np.array([np.nan if p["growth"] is None else p["growth"] for p in pts])
        e = np.array([np.nan if p["energy_mj"] is None else p["energy_mj"] for p in pts])
        cap = np.array([np.nan if p["f_cap_n"] is None else p["f_cap_n"] / f_top for p in pts])
        o = np.argsort(x)
        kw = dict(color=col, marker=mk)
        axes[0].plot(x[o], g_nl[o], ls=fls, **kw, label=f"{lab}: harmonic balance")
        axes[0].plot(x[o], g_sc[o], ls=":", mfc="none", **kw, label=f"{lab}: screen")
        axes[1].plot(x[o], e[o], ls=fls, **kw, label=lab)
        axes[2].plot(cap, g_nl, ls="none", **kw, label=lab)
        sep = np.array(["separates" in (p.get("verdict") or "") for p in pts])
        if sep.any():  # the rule ignores lift-off: ring those points
            for ax, xs, ys in ((axes[0], x, g_nl), (axes[2], cap, g_nl)):
                ax.plot(xs[sep], ys[sep], "s", ms=11, mfc="none", color="0.35", zorder=0)
            seps.append(lab)
    ratio = f_top / f_ref if f_ref else np.nan
    for ax in (axes[0], axes[2]):
        ax.axhline(1.3, color="0.4", lw=0.8, ls=":")
        ax.axhline(ratio, color="0.6", lw=0.8, ls="-.")
        tr = ax.get_yaxis_transform()  # x in axes fraction, y in data
        ax.text(
            0.01, 1.3, "levels off (<= 1.3)", va="bottom", fontsize=8, color="0.3", transform=tr
        )
        ax.text(
            0.01, ratio, f"linear ({ratio:.3g})", va="bottom", fontsize=8, color="0.4", transform=tr
        )
        ax.set_ylabel(f"peak growth A({f_top:g} N) / A({f_ref:g} N), A = max |x(t)|")
    k_all = np.array([p["k2_over_k"] for p in points if p["k2_over_k"] > 0])
    log_k = k_all.size > 1 and k_all.max() / k_all.min() > 20
    for ax in axes[:2]:
        if log_k:
            ax.set_xscale("log")
    klab = "k2/k from the coupling screen (-" + (", log)" if log_k else ")")
    if seps:
        axes[0].plot(
            [],
            [],
            "s",
            ms=11,
            mfc="none",
            color="0.35",
            label=f"a pair lifts off below {f_top:g} N (linear estimate)",
        )
    axes[0].set_xlabel(klab)
    axes[0].set_title("peak growth vs stuck coupling")
    axes[1].set_xlabel(klab)
    axes[1].set_ylabel(f"friction energy per cycle at {f_top:g} N (mJ)")
    axes[1].set_title("dissipation vs stuck coupling")
    axes[2].set_xscale("log")
    axes[2].axvline(1.0, color="0.4", lw=0.8, ls=":")
    axes[2].set_xlabel(f"predicted saturation force / {f_top:g} N (-, log)")
    axes[2].set_title("peak growth vs predicted saturation")
    axes[0].legend(fontsize=7, loc="best")
    axes[1].legend(fontsize=7, loc="best")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return save_figure(fig, path)


@styled
def plot_screen_vs_curves(
    screen_rows: Sequence[dict[str, Any]], cases: Sequence[Any], path: str | Path | None
) -> Any:
    """The coupling screen's predicted peak against the harmonic balance's, per family.

    For each damper and family: the single-mode friction estimate of the
    peak against the force (:func:`workbench.assembly.screen.predicted_peak`:
    linear up to the slip onset, then levelling off towards the predicted
    saturation force), dotted, and the harmonic-1 peaks of the curves, solid
    with markers; a short bar marks the screen's separation onset, which the
    estimate ignores. Log-log; colour, marker: the damper.
    """
    from ..assembly.screen import predicted_peak
    from ..post.results import family_name
    from .palette import damper_style

    fams = list(
        dict.fromkeys(str(r.get("family") or family_name(r["phase_deg"])) for r in screen_rows)
    )
    plt = pyplot()
    fig, axes = plt.subplots(
        1,
        max(len(fams), 1),
        figsize=(4.6 * max(len(fams), 1) + 1.4, 4.0),
        squeeze=False,
        layout="constrained",
        sharey=True,
    )
    forces = sorted({float(c.force_n) for c in cases})
    if not forces:
        forces = [float(screen_rows[0].get("f_max_n") or 1.0)]
    fx = np.geomspace(min(forces), max(forces), 60) if len(forces) > 1 else np.array(forces)
    for k, fam in enumerate(fams):
        ax = axes[0, k]
        for row in (
            r for r in screen_rows if (r.get("family") or family_name(r["phase_deg"])) == fam
        ):
            if row.get("variant"):
                continue
            col, ls, mk = damper_style(row["damper"])
            r, fs, cap = row.get("stuck_peak_m_per_n"), row.get("f_slip_n"), row.get("f_cap_n")
            if r and fs is not None and cap is not None:
                y = [predicted_peak(r, fs, cap, f) * 1e3 for f in fx]
                ax.plot(fx, y, color=col, ls=":", lw=1.8)
            own = sorted(
                (
                    c
                    for c in cases
                    if c.damper == row["damper"]
                    and not c.variant
                    and abs(c.phase_deg - row["phase_deg"]) < 1e-9
                    and c.h1_peak_index >= 0
                ),
                key=lambda c: c.force_n,
            )
            if own:
                ax.plot(
                    [c.force_n for c in own],
                    [c.h1_mm[c.h1_peak_index] for c in own],
                    color=col,
                    ls=ls,
                    marker=mk,
                    lw=1.6,
                    label=row["damper"],
                )
            sep = row.get("f_sep_n")
            if sep is not None and min(forces) <= sep <= max(forces) and r:
                a = (
                    predicted_peak(r, fs, cap, sep) * 1e3
                    if fs is not None and cap
                    else r * sep * 1e3
                )
                ax.plot([sep, sep], [a / 1.25, a * 1.25], color=col, lw=2.5)
        if len(forces) > 1:
            ax.set_xscale("log")
            ax.set_yscale("log")
        ax.set_title(fam, fontsize=10)
        ax.set_xlabel("excitation force F (N)")
        from .common import readable_log

        readable_log(ax)
    axes[0, 0].set_ylabel("vibration amplitude at resonance,\nharmonic 1 (mm)")
    from matplotlib.lines import Line2D

    handles = axes[0, 0].get_legend_handles_labels()[0] + [
        Line2D([], [], color="0.3", ls=":", lw=1.8, label="screen estimate"),
        Line2D([], [], color="0.3", lw=2.5, label="screen: separation onset"),
    ]
    fig.legend(handles=handles, loc="outside right upper", fontsize=8)
    fig.suptitle("coupling screen (dotted) against the harmonic balance", fontsize=11)
    return save_figure(fig, path)
