"""Charts of the fidelity study: error against compute time (matplotlib, Agg).

* :func:`plot_knob`: one knob's levels, one panel per quantity (peak
  amplitude, resonance frequency, friction energy per cycle), log-log,
  one line per condition (force colours as the other study figures), every
  point labelled with its level;
* :func:`plot_pareto`: every measured setting of every knob together, one
  panel per quantity plus the worst of the three, each with its Pareto
  front (non-dominated settings) drawn as a step line, the tolerance as a
  horizontal line and the picked setting circled.

Errors of exactly zero (the reference itself) or below :data:`ERR_FLOOR`
percent have no place on a log axis and are not drawn as if they were
1e-4 %: open markers sit on the bottom edge of the axes, in a band labelled
"< 1e-4 % (reference: 0)". An axis whose values span less than a factor 3
(compute times of settings that cost the same) is linear, so its ticks read
distinct values.
"""

from __future__ import annotations

import math
import re
import weakref
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ....render.common import pyplot, save_figure, styled
from ....render.palette import force_colors
from ....render.study_style import _EXTRA_COLORS, FIGSIZE

ERR_FLOOR = 1e-4  # percent
QUANTITY_TITLES = {
    "peak_amplitude_mm": "peak amplitude",
    "peak_frequency_hz": "resonance frequency",
    "friction_energy_mj": "friction energy per cycle",
    "worst": "worst of the three",
}
KNOB_COLORS = {
    "mesh-size": "#1f6fb4",
    "contact-mesh-size": "#17becf",
    "modes": "#ff7f0e",
    "harmonics": "#2ca02c",
    "nt": "#9467bd",
    "points-per-line": "#8c564b",
    "rigid-damper": "#e377c2",
    "base": "#000000",
    "combined": "#d62728",
}
KNOB_MARKERS = {
    "mesh-size": "o",
    "contact-mesh-size": "h",
    "modes": "s",
    "harmonics": "^",
    "nt": "v",
    "points-per-line": "D",
    "rigid-damper": "P",
    "base": "*",
    "combined": "X",
}


EDGE_Y = 0.035  # axes fraction of the bottom band of errors below the floor
EDGE_TEXT = f"< {ERR_FLOOR:g} % (reference: 0)"
_EDGE_LABELLED: weakref.WeakSet = weakref.WeakSet()  # axes whose bottom band is labelled


def _floor(e: float | None) -> tuple[float | None, bool]:
    """(value to draw, below the floor): below the floor there is no value to draw."""
    if e is None or not math.isfinite(e):
        return None, False
    return (None, True) if e < ERR_FLOOR else (e, False)


def _edge(ax, xs: Sequence[float], **kw) -> None:
    """Open markers on the bottom edge of ``ax`` at data x: errors below the floor."""
    if not xs:
        return
    from matplotlib.transforms import blended_transform_factory

    tr = blended_transform_factory(ax.transData, ax.transAxes)
    ax.plot(list(xs), [EDGE_Y] * len(xs), ls="none", transform=tr, clip_on=False, **kw)
    if ax not in _EDGE_LABELLED:
        ax.text(
            0.01,
            2.2 * EDGE_Y,
            EDGE_TEXT,
            transform=ax.transAxes,
            fontsize=6.5,
            color="0.35",
            va="bottom",
        )
        _EDGE_LABELLED.add(ax)


def _log_axes(ax) -> None:
    """Log-log axes with plain number labels (1, 2, 5 x 10^k; three ticks on a narrow range)."""
    import numpy as np
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter, ScalarFormatter

    fmt = FuncFormatter(lambda v, _: f"{v:.3g}")
    for name in ("x", "y"):
        lo, hi = sorted(ax.dataLim.intervalx if name == "x" else ax.dataLim.intervaly)
        if lo > 0 and hi / lo >= 3.0:
            getattr(ax, f"set_{name}scale")("log")
        else:  # a narrow range: linear, with as many digits as the ticks need
            getattr(ax, f"{name}axis").set_major_formatter(ScalarFormatter(useOffset=False))
    if getattr(ax, "_edge_labelled", False):  # room under the data for the below-floor band
        lo, hi = ax.get_ylim()
        if ax.get_yscale() == "log" and lo > 0:
            ax.set_ylim(lo / (hi / lo) ** 0.15, hi)
        else:
            ax.set_ylim(lo - 0.15 * (hi - lo), hi)
        ax.plot(
            [0, 1], [2 * EDGE_Y, 2 * EDGE_Y], color="0.6", lw=0.8, ls=":", transform=ax.transAxes
        )
    for axis, lim in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
        if axis.get_scale() != "log":
            continue
        axis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(fmt)
        axis.set_minor_formatter(NullFormatter())
        lo, hi = sorted(lim)
        ticks = [t for t in axis.get_major_locator().tick_values(lo, hi) if lo <= t <= hi]
        if len(ticks) < 2 and lo > 0:
            axis.set_ticks([float(f"{t:.2g}") for t in np.geomspace(lo, hi, 3)])
            axis.set_major_formatter(fmt)


def _case_of(cond: str) -> str:
    """'cone 0 deg 30 N' -> 'cone 0 deg': the condition without its force."""
    return re.sub(r"\s*[-+0-9.eE]+ N$", "", cond)


def _case_styles(conds: Sequence[str]) -> dict[str, tuple[str, str]]:
    """condition -> (line style, marker): one per damper and phase (colours: the force)."""
    cases = list(dict.fromkeys(_case_of(c) for c in conds))
    ls = ["-", "--", ":", "-."]
    mk = ["o", "s", "^", "D"]
    return {c: (ls[cases.index(_case_of(c)) % 4], mk[cases.index(_case_of(c)) % 4]) for c in conds}


def _force_of(cond: str) -> float:
    m = re.search(r"([-+0-9.eE]+) N$", cond)
    return float(m.group(1)) if m else 0.0


@styled
def plot_knob(
    knob: str,
    levels: Sequence[str],
    times_s: Sequence[float],
    errors: dict[str, dict[str, Sequence[float | None]]],
    path: str | Path,
    held: str = "",
) -> Path:
    """Error vs time of one knob's levels: ``errors[quantity][condition][level]`` in percent.
    ``held``: the other knobs the ladder holds away from the base, in words ("" none)."""
    plt = pyplot()
    qs = list(errors)
    fig, axes = plt.subplots(1, len(qs), figsize=(FIGSIZE[0] * 1.6, FIGSIZE[1] * 0.95))
    axes = list(axes) if len(qs) > 1 else [axes]
    conds = list(next(iter(errors.values()))) if errors else []
    colors = force_colors([_force_of(c) for c in conds])
    styles = _case_styles(conds)
    for ax, q in zip(axes, qs, strict=True):
        for cond in conds:
            col = colors[_force_of(cond)]
            ls, mk = styles[cond]
            xs, ys, low = [], [], []
            for t, e in zip(times_s, errors[q][cond], strict=True):
                y, fl = _floor(e)
                if fl:
                    low.append(t)
                if y is None:
                    continue
                xs.append(t)
                ys.append(y)
            ax.plot(xs, ys, ls=ls, marker=mk, color=col, lw=1.3, ms=5, label=cond)
            _edge(ax, low, marker=mk, ms=5, mfc="white", mec=col)
        _log_axes(ax)
        for i, (t, lab) in enumerate(zip(times_s, levels, strict=True)):
            ys = [_floor(errors[q][c][i])[0] for c in conds]
            ys = [y for y in ys if y is not None]
            if ys:
                ax.annotate(
                    lab, (t, max(ys)), textcoords="offset points", xytext=(3, 4), fontsize=7
                )
            else:  # every condition below the floor: label it on the edge
                from matplotlib.transforms import blended_transform_factory

                ax.annotate(
                    lab,
                    (t, EDGE_Y),
                    textcoords="offset points",
                    xytext=(3, 4),
                    fontsize=7,
                    xycoords=blended_transform_factory(ax.transData, ax.transAxes),
                )
        ax.set_xlabel("compute time of the setting, s")
        ax.set_ylabel(f"{QUANTITY_TITLES.get(q, q)} error, %")
        ax.set_title(QUANTITY_TITLES.get(q, q), fontsize=10)
    if len(conds) <= 4:  # a few: inside the first panel
        axes[0].legend(title="condition", loc="best")
        fig.tight_layout()
    else:  # more would hide the data: one row of columns below the panels
        ncol = min(len(conds), 6)
        fig.legend(*axes[0].get_legend_handles_labels(), title="condition", loc="lower center",
                   ncol=ncol, fontsize=7, frameon=False)  # fmt: skip
        rows = -(-len(conds) // ncol)
        fig.tight_layout(rect=(0, 0.06 + 0.045 * rows, 1, 0.95))
    where = f"; {held}" if held else ""
    fig.suptitle(
        f"{knob}: error vs compute time (other knobs at the base setting{where})", fontsize=11
    )
    return save_figure(fig, path)


def pareto_indices(times: Sequence[float], errs: Sequence[float | None]) -> list[int]:
    """Non-dominated (time, error) points, cheapest first (see post.pareto.pareto_front)."""
    from ....post.pareto import pareto_front

    return pareto_front(list(zip(times, errs, strict=True)))


@styled
def plot_pareto(
    points: Sequence[dict[str, Any]],
    path: str | Path,
    *,
    tolerance_pct: float | None = None,
    picked: str | None = None,
    reference_time_s: float | None = None,
) -> Path:
    """All settings: error vs time per quantity and the worst error, with the Pareto fronts.

    ``points``: dicts with ``label``, ``group`` (the knob moved, "base" or
    "combined"), ``time_s`` and the errors in percent under the quantity
    keys and ``worst`` (None when the setting could not be compared).
    ``reference_time_s``: drawn as a vertical line (the reference has no
    error to draw).
    """
    plt = pyplot()
    qs = ["peak_amplitude_mm", "peak_frequency_hz", "friction_energy_mj", "worst"]
    fig, axes = plt.subplots(2, 2, figsize=(FIGSIZE[0] * 1.5, FIGSIZE[1] * 1.6))
    groups = list(dict.fromkeys(p["group"] for p in points))
    extra = iter(_EXTRA_COLORS)
    gcol = {g: KNOB_COLORS.get(g) or next(extra, "#7f7f7f") for g in groups}
    for ax, q in zip(axes.ravel(), qs, strict=True):
        for g in groups:
            sel = [p for p in points if p["group"] == g]
            xs, ys, low = [], [], []
            for p in sel:
                y, f = _floor(p.get(q))
                if f:
                    low.append(p["time_s"])
                if y is not None:
                    xs.append(p["time_s"])
                    ys.append(y)
            m = KNOB_MARKERS.get(g, "o")
            if xs:
                ax.scatter(
                    xs,
                    ys,
                    marker=m,
                    s=34,
                    label=g,
                    facecolors=gcol[g],
                    edgecolors=gcol[g],
                    zorder=3,
                )
            _edge(ax, low, marker=m, ms=6, mfc="white", mec=gcol[g], label=None if xs else g)
        front = pareto_indices([p["time_s"] for p in points], [p.get(q) for p in points])
        front = [i for i in front if _floor(points[i][q])[0] is not None]
        if front:
            fx = [points[i]["time_s"] for i in front]
            fy = [_floor(points[i][q])[0] for i in front]
            ax.step(
                fx, fy, where="post", color="0.2", lw=1.2, ls="--", zorder=2, label="Pareto front"
            )
            for i in front:
                ax.annotate(
                    points[i]["label"],
                    (points[i]["time_s"], _floor(points[i][q])[0]),
                    textcoords="offset points",
                    xytext=(3, -9),
                    fontsize=6.5,
                )
        if reference_time_s is not None:
            ax.axvline(
                reference_time_s,
                color="0.45",
                lw=1.0,
                ls="-.",
                label=f"reference ({reference_time_s:.0f} s)",
            )
        if q == "worst" and tolerance_pct is not None:
            ax.axhline(
                tolerance_pct,
                color="#d62728",
                lw=1.0,
                ls=":",
                label=f"tolerance {tolerance_pct:g} %",
            )
        if picked is not None and q == "worst":
            for p in points:
                y = _floor(p.get(q))[0]
                if p["label"] == picked and y is not None:
                    ax.scatter(
                        [p["time_s"]],
                        [y],
                        s=180,
                        facecolors="none",
                        edgecolors="#d62728",
                        lw=1.8,
                        zorder=4,
                        label="picked",
                    )
        _log_axes(ax)
        ax.set_xlabel("compute time of the setting, s")
        ax.set_ylabel(f"{QUANTITY_TITLES[q]} error, %")
        ax.set_title(QUANTITY_TITLES[q] + (" (max over conditions)"), fontsize=10)
    axes[1, 1].legend(loc="best", fontsize=7)
    fig.suptitle("every setting: error vs compute time, with the Pareto front", fontsize=11)
    fig.tight_layout()
    return save_figure(fig, path)


@styled
def plot_base_vs_limit(
    points: Sequence[dict[str, Any]],
    base: dict[str, Any],
    path: str | Path,
) -> Path:
    """Error against the extrapolated limit vs compute time, the base setting per case.

    ``points``: every setting, dicts with ``label``, ``group`` (the knob moved,
    "base", "reference"), ``time_s`` and per quantity its worst error against
    the limit (percent) over the cases where the limit is trusted (None: none
    is). ``base``: ``time_s`` and per quantity a list of ``(case, error %,
    uncertainty %)`` for the trusted cases, ``untrusted[quantity]``: the
    cases with no trusted limit, named on the panel instead of a number, and optional
    ``stuck[quantity]``: the cases whose base value is 0 (a stuck damper's energy),
    counted on the panel, never drawn as an error.
    Optional ``production`` (per quantity, as the base's lists) and
    ``production_time_s``: the production job's own model, drawn hollow.
    """
    plt = pyplot()
    qs = ["peak_amplitude_mm", "peak_frequency_hz", "friction_energy_mj"]
    units = {"peak_amplitude_mm": "mm", "peak_frequency_hz": "Hz", "friction_energy_mj": "mJ"}
    prod = base.get("production") or {}
    fig, axes = plt.subplots(1, 3, figsize=(FIGSIZE[0] * 1.9, FIGSIZE[1] * 1.15))
    groups = list(dict.fromkeys(p["group"] for p in points))
    extra = iter(_EXTRA_COLORS)
    gcol = {g: KNOB_COLORS.get(g) or next(extra, "#7f7f7f") for g in groups}
    gcol["reference"] = "0.45"
    all_cases = list(
        dict.fromkeys(
            [c for q in qs for c, _, _ in base[q]]
            + [c for q in qs for c in base["untrusted"][q]]
            + [c for q in qs for c in base.get("stuck", {}).get(q, [])]
        )
    )
    colors = force_colors([_force_of(c) for c in all_cases])
    styles = _case_styles(all_cases)
    handles: dict[str, Any] = {}
    for ax, q in zip(axes, qs, strict=True):
        drawn = False
        for g in groups:
            sel = [p for p in points if p["group"] == g and _floor(p.get(q))[0] is not None]
            if sel:
                h = ax.scatter(
                    [p["time_s"] for p in sel],
                    [_floor(p[q])[0] for p in sel],
                    marker=KNOB_MARKERS.get(g, "o"),
                    s=26,
                    color=gcol[g],
                    alpha=0.55,
                    zorder=2,
                )
                handles.setdefault(f"{g} (worst case)", h)
                drawn = True
        # the lowest error drawn: a band reaching zero (uncertainty >= error) ends a third
        # of it lower, with an arrow down (a log axis has no zero)
        ys = [_floor(p.get(q))[0] for p in points] + [
            max(e, ERR_FLOOR) for _, e, _ in base[q] + prod.get(q, [])
        ]
        ys = [y for y in ys if y is not None]
        bottom = min(ys) / 3.0 if ys else ERR_FLOOR
        for marks, t0, label, hollow in (
            (base[q], base["time_s"], "base: {}", False),
            (prod.get(q, []), base.get("production_time_s"), "production model (hollow)", True),
        ):
            for i, (case, e, u) in enumerate(marks):
                x = t0 * 1.07 ** (i - (len(marks) - 1) / 2)
                h = _case_bar(ax, x, e, u, bottom, styles[case][1], colors[_force_of(case)],
                              hollow=hollow)  # fmt: skip
                handles.setdefault(label.format(case), h)
                drawn = True
        if drawn:
            _log_axes(ax)
        else:
            ax.set_xticks([])
            ax.set_yticks([])
        bad = base["untrusted"][q]
        stuck = base.get("stuck", {}).get(q, [])
        if bad or stuck:
            n_all = len(all_cases)
            names = "\n".join(bad) if len(bad) <= 4 else "(the report names them)"
            text = f"no trusted limit for {len(bad)} of {n_all} cases (no error given):\n" + names
            if stuck:  # a stuck damper's energy: 0, and no error is relative to 0
                text = (text + "\n" if bad else "") + f"0 (stuck) for {len(stuck)}: no error"
            ax.text(
                0.02,
                0.98,
                text,
                transform=ax.transAxes,
                fontsize=7,
                va="top",
                ha="left",
                bbox=dict(boxstyle="round", fc="#fff3e0", ec="#e69500", lw=0.8),
                zorder=5,
            )
        ax.set_xlabel("compute time of the setting, s")
        ax.set_ylabel("error against the limit, %")
        ax.set_title(f"{QUANTITY_TITLES[q]} ({units[q]})", fontsize=10)
    fig.legend(
        list(handles.values()),
        list(handles),
        loc="lower center",
        ncol=min(5, max(1, len(handles))),
        fontsize=7,
        frameon=False,
    )
    fig.suptitle(
        "error against the extrapolated limit vs compute time: every setting (worst of the "
        "cases with a trusted limit) and the base per case (+- the limit's uncertainty; "
        "an arrow: the band reaches 0)",
        fontsize=10,
    )
    rows = math.ceil(len(handles) / min(5, max(1, len(handles))))
    fig.tight_layout(rect=(0, 0.04 + 0.035 * rows, 1, 0.95))
    return save_figure(fig, path)


def _case_bar(ax, x, e, u, bottom, marker, color, hollow=False):
    """One case's error against the limit at ``x``, +- ``u`` (percent): a band that
    reaches zero ends at ``bottom`` with an arrow down (a log axis has no zero); hollow
    for the production model, edged black for the base."""
    y = max(e, ERR_FLOOR)
    u = u or 0.0
    to_zero = y - u <= bottom
    face = {"mfc": "white", "mec": color} if hollow else {"mec": "black"}
    h = ax.errorbar([x], [y], yerr=[[y - bottom if to_zero else u], [u]], marker=marker, ms=8,
                    color=color, capsize=3, ls="none", zorder=4, **face)  # fmt: skip
    if to_zero:
        ax.plot([x], [bottom], marker="v", ms=5, color=color, zorder=4)
    return h


def stuck_cases(table: dict[str, dict[str, dict[str, Any]]], q: str) -> list[str]:
    """The conditions of ``report_base.base_vs_limit``'s ``table`` whose base value of
    ``q`` is 0: a damper stuck at the peak dissipates nothing, and no error is relative to
    0, so the charts name these cases instead of drawing an error."""
    return [c for c, qs in table.items() if qs[q].get("base") == 0.0]


@styled
def plot_base_per_knob(table: dict[str, dict[str, dict[str, Any]]], path: str | Path) -> Path:
    """The base's error against each knob's own limit, per case, with its uncertainty.

    ``table``: condition -> quantity -> the row of
    ``report_base.base_vs_limit`` (``knobs``: knob -> ``error_vs_limit_pct``,
    ``uncertainty_pct``). A knob whose limit is not trusted for a case gets a
    grey cross on the bottom edge and no number; a case whose base value is 0 (a damper
    stuck at the peak dissipates nothing) says so instead.
    """
    from matplotlib.transforms import blended_transform_factory

    plt = pyplot()
    qs = ["peak_amplitude_mm", "peak_frequency_hz", "friction_energy_mj"]
    conds = list(table)
    knobs = list(dict.fromkeys(k for c in conds for q in qs for k in table[c][q]["knobs"]))
    fig, axes = plt.subplots(1, 3, figsize=(FIGSIZE[0] * 1.9, FIGSIZE[1] * 1.2))
    width = 0.8 / max(1, len(knobs))
    for ax, q in zip(axes, qs, strict=True):
        tr = blended_transform_factory(ax.transData, ax.transAxes)
        ys = []
        stuck = set(stuck_cases(table, q))
        for i, c in enumerate(conds):
            if c in stuck:  # a stuck damper's energy: 0, and no error is relative to 0
                ax.text(i, 0.04, "0 (stuck)", transform=tr, rotation=90, ha="center",
                        va="bottom", fontsize=7, color="0.4")  # fmt: skip
        for j, knob in enumerate(knobs):
            for i, c in enumerate(conds):
                d = table[c][q]["knobs"].get(knob)
                if d is None or c in stuck:
                    continue  # the knob does not reach this damper, or nothing to measure
                x = i - 0.4 + width * (j + 0.5)
                e, u = d["error_vs_limit_pct"], d["uncertainty_pct"] or 0.0
                if e is None:
                    ax.plot([x], [0.03], marker="x", ms=5, color="0.6", transform=tr, clip_on=False)
                    continue
                y = max(e, ERR_FLOOR)
                ys.append(y)
                ax.errorbar(
                    [x],
                    [y],
                    yerr=[[min(u, 0.999 * y)], [u]],
                    marker=KNOB_MARKERS.get(knob, "o"),
                    ms=6,
                    color=KNOB_COLORS.get(knob, "0.3"),
                    capsize=2,
                    ls="none",
                    label=knob if i == 0 or knob not in ax.get_legend_handles_labels()[1] else None,
                )
        ax.set_yscale("log")
        if ys:
            ax.set_ylim(min(ys) / 10.0, max(ys) * 3.0)
        ax.set_xticks(range(len(conds)))
        if len(conds) <= 6:  # two lines each fit side by side
            ax.set_xticklabels([c.replace(" deg ", "°\n") for c in conds], fontsize=7)
        else:  # more: upright, one line each, so neighbours do not overlap
            ax.set_xticklabels([c.replace(" deg ", "° ") for c in conds], fontsize=6.5,
                               rotation=90)  # fmt: skip
        ax.set_xlim(-0.5, len(conds) - 0.5)
        for i in range(1, len(conds)):
            ax.axvline(i - 0.5, color="0.85", lw=0.8)
        ax.set_ylabel("error of the base against the knob's limit, %")
        units = {"peak_amplitude_mm": "mm", "peak_frequency_hz": "Hz", "friction_energy_mj": "mJ"}
        ax.set_title(f"{QUANTITY_TITLES[q]} ({units[q]})", fontsize=10)
    handles, labels = [], []
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            if lab not in labels:
                handles.append(h)
                labels.append(lab)
    from matplotlib.lines import Line2D

    handles.append(Line2D([], [], ls="none", marker="x", color="0.6"))
    labels.append("not trusted: no limit, no error")
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=7, frameon=False)
    fig.suptitle(
        "the base against each knob's own limit (Richardson, least squares or a bound; the "
        "other knobs at the base), "
        "+- that limit's uncertainty",
        fontsize=10,
    )
    fig.tight_layout(rect=(0, 0.07, 1, 0.95))
    return save_figure(fig, path)
