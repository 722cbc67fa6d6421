"""The bladed-disk study's charts: peak and friction energy against engine order, the fan
diagram with the engine-order line. Plain inputs (arrays, lists of dicts): no study module."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ....render.common import pyplot, save_figure, styled
from ....render.palette import damper_color

MARKERS = ("o", "s", "^", "D", "v", "P")


def _per_damper(dampers, forces, eos, values, scale, ylabel, title, path, lower=None, what=""):
    """One panel per damper, one line per force; ``lower`` [damper, force, eo] marks the
    cases whose curve stopped early or peaks on its band edge (ringed, labelled ``what``)."""
    plt = pyplot()
    n = len(dampers)
    fig, axes = plt.subplots(1, n, figsize=(4.2 * n + 0.6, 3.8), squeeze=False, sharey=True)
    for i, (d, ax) in enumerate(zip(dampers, axes[0], strict=True)):
        for j, f in enumerate(forces):
            ax.plot(
                eos,
                values[i, j] * scale,
                marker=MARKERS[j % len(MARKERS)],
                color=damper_color(d),
                alpha=0.45 + 0.55 * (j + 1) / len(forces),
                label=f"{f:g} N",
            )
            if lower is not None and lower[i, j].any():
                m = lower[i, j]
                ax.plot(
                    np.asarray(eos)[m],
                    values[i, j][m] * scale,
                    "o",
                    ms=13,
                    mfc="none",
                    mec="black",
                    label=f"stopped early or at the band edge: {what}",
                )
        ax.set_title(f"{d}")
        ax.set_xlabel("engine order EO")
        ax.set_xticks(eos)
        ax.grid(True, alpha=0.3)
        ax.legend(title="force per blade", fontsize=8)
        if i == 0:
            ax.set_ylabel(ylabel)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


@styled
def plot_peaks_vs_eo(
    dampers, forces, eos, peak_m, n_blades, path: str | Path | None, lower=None
) -> Any:
    """Per damper the peak amplitude (µm) against EO, one line per force;
    ``peak_m``: [damper, force, eo] in metres; ``lower``: which are lower bounds."""
    fig = _per_damper(
        dampers,
        forces,
        eos,
        peak_m,
        1e6,
        "peak |y| at the response point (µm)",
        f"Peak response against engine order, {n_blades} blades",
        path,
        lower,
        "a lower bound",
    )
    return save_figure(fig, path)


@styled
def plot_energy_vs_eo(dampers, forces, eos, energy_j, path: str | Path | None, lower=None) -> Any:
    """Per damper the friction energy per sector and cycle at the peak (mJ) against EO;
    ``energy_j``: [damper, force, eo] in joules; ``lower``: curves without their peak."""
    fig = _per_damper(
        dampers,
        forces,
        eos,
        energy_j,
        1e3,
        "friction energy at the peak (mJ / sector / cycle)",
        "Friction energy dissipated by the damper against engine order",
        path,
        lower,
        "not at the peak",
    )
    return save_figure(fig, path)


def folded_nd(eo: np.ndarray, n_blades: int) -> np.ndarray:
    """The ND an engine order (any real value) excites: the zigzag of the fan diagram."""
    k = np.mod(eo, n_blades)
    return np.minimum(k, n_blades - k)


@styled
def plot_fan_eo(fans, n_blades, worst, cases, path: str | Path | None) -> Any:
    """Fan diagram (damper stuck; ``fans``: damper -> [ND, family] Hz), each case's peak
    frequency at its ND (markers), and for each damper's worst EO the engine-order line
    ``f = EO x speed`` through that crossing (the speed at which it is resonant)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(9.6, 4.8))
    top = 0.0
    for d, hz in fans.items():
        nd = np.arange(hz.shape[0])
        for j in range(hz.shape[1]):
            ax.plot(
                nd,
                hz[:, j],
                "-",
                marker="s",
                ms=3,
                color=damper_color(d),
                label=f"{d} stuck" if j == 0 else None,
            )
        top = max(top, float(np.nanmax(hz[:, 0])))
    for c in cases:
        top = max(top, float(c["peak_hz"]))
        ax.plot(c["nd"], c["peak_hz"], "x", color=damper_color(c["damper"]), ms=7)
    ax.plot([], [], "x", color="k", label="peak of a case (at its EO's ND)")
    done = set()
    for w in worst:
        if w["worst_eo"] == 0 or (w["damper"], w["worst_eo"]) in done:
            continue
        done.add((w["damper"], w["worst_eo"]))
        rev_s = w["peak_hz"] / w["worst_eo"]
        e = np.linspace(0.0, max(w["worst_eo"], n_blades / 2), 400)
        ax.plot(
            folded_nd(e, n_blades),
            e * rev_s,
            ":",
            color=damper_color(w["damper"]),
            lw=1.3,
            label=f"EO line at {60 * rev_s:.0f} rpm ({w['damper']}: worst EO {w['worst_eo']})",
        )
    ax.set_xlabel("nodal diameter k")
    ax.set_ylabel("frequency (Hz)")
    ax.set_title(f"Fan diagram and engine-order excitation, {n_blades} blades")
    ax.set_xlim(-0.3, n_blades // 2 + 0.3)
    ax.set_ylim(0.0, 1.3 * top)  # the first family and the peaks; higher families clipped
    ax.set_xticks(np.arange(0, n_blades // 2 + 1, max(1, (n_blades // 2) // 12)))
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7)
    fig.tight_layout()
    return save_figure(fig, path)


@styled
def plot_k2k_vs_nd(dampers, screen, eo_nds, worst_nd, path: str | Path | None, forces=()) -> Any:
    """The coupling screen per nodal diameter: ``k2/k = 1 - (f_sliding / f_stuck)^2`` of the
    first family against ND, one line per damper (``screen``: rows with ``damper``, ``nd``,
    ``k2_over_k``, ``stuck_hz``, ``sliding_hz``); the NDs the study's engine orders excite
    (``eo_nds``) shaded, each damper's worst ND at the largest force (``worst_nd``) ringed.
    Middle: the stuck and sliding frequencies themselves. Right (rows with ``f_slip_n``):
    the slip onset force per blade of the stuck linear response, the study's ``forces``
    as horizontal lines."""
    plt = pyplot()
    onset = all(r.get("f_slip_n") is not None for r in screen)
    fig, axes = plt.subplots(1, 3 if onset else 2, figsize=(16.0 if onset else 11.0, 4.2))
    ax, bx = axes[0], axes[1]
    n_nd = 1 + max(int(r["nd"]) for r in screen)
    for k in eo_nds:
        for a in axes:
            a.axvspan(k - 0.18, k + 0.18, color="0.88", lw=0, zorder=0)
    for j, d in enumerate(dampers):
        rows = sorted((r for r in screen if r["damper"] == d), key=lambda r: r["nd"])
        nd = np.array([r["nd"] for r in rows])
        k2k = np.array([r["k2_over_k"] for r in rows])
        c = damper_color(d)
        ax.plot(nd, k2k, marker=MARKERS[j % len(MARKERS)], color=c, label=d)
        if d in worst_nd:
            w = int(worst_nd[d])
            ax.plot(w, k2k[list(nd).index(w)], "o", ms=14, mfc="none", mec=c, mew=1.6)
        bx.plot(
            nd, [r["stuck_hz"] for r in rows], "-", marker="s", ms=4, color=c, label=f"{d} stuck"
        )
        bx.plot(
            nd, [r["sliding_hz"] for r in rows], "--", marker="o", ms=4, mfc="none", color=c,
            label=f"{d} sliding",
        )  # fmt: skip
        if onset:
            axes[2].plot(
                nd, [r["f_slip_n"] for r in rows], marker=MARKERS[j % len(MARKERS)], color=c,
                label=d,
            )  # fmt: skip
    if onset:
        cx = axes[2]
        for f in forces:
            cx.axhline(f, color="0.3", ls=":", lw=1.2)
            cx.annotate(f"{f:g} N", (-0.3, f), ha="left", va="bottom", fontsize=8)
        cx.set_xlabel("nodal diameter k")
        cx.set_ylabel("slip onset force per blade (N)")
        cx.set_title("First pair slips (stuck linear response)")
        vals = [*forces, *(r["f_slip_n"] for r in screen)]
        cx.set_yscale("log")  # a rolling damper's onset is orders of magnitude above
        cx.set_ylim(0.6 * min(vals), 1.8 * max(vals))
        cx.legend(fontsize=8, loc="upper right")
    ax.plot([], [], "o", ms=10, mfc="none", mec="k", label="worst EO's ND (largest force)")
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set_xlabel("nodal diameter k")
    ax.set_ylabel("k2/k = 1 - (f_sliding / f_stuck)²  (-)")
    ax.set_title("Stiffness the stuck damper adds (coupling screen)")
    ax.legend(fontsize=8, loc="lower right")
    bx.set_xlabel("nodal diameter k")
    bx.set_ylabel("first-family frequency (Hz)")
    bx.set_title("Stuck and sliding linear limits")
    bx.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    for a in axes:
        a.set_xticks(np.arange(n_nd))
        a.set_xlim(-0.4, n_nd - 0.6)
        a.grid(True, alpha=0.3)
    fig.text(0.01, 0.01, "grey bands: NDs excited by the study's engine orders", fontsize=8)
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    return save_figure(fig, path)


@styled
def plot_worst_status(cases, path: str | Path | None) -> Any:
    """Per damper the contact status of every pair along the worst case's curve (the worst
    EO at the largest force; ``cases``: case records with ``status``, ``side``,
    ``freq_hz``, ``amp_m``, ``stuck_hz``), the peak marked, the counts at the peak in the
    title. Band: 0.9..1.1 times the stuck frequency (hatched where no point was computed)."""
    from ....contact.law import STATUS_NAMES
    from ....render.status_figures import draw_status_panel
    from ....render.study_style import status_legend_handles

    plt = pyplot()
    n = len(cases)
    fig, axes = plt.subplots(1, n, figsize=(4.3 * n + 0.6, 4.6), squeeze=False)
    for k, (c, ax) in enumerate(zip(cases, axes[0], strict=True)):
        i = int(np.argmax(c["amp_m"])) if c["amp_m"] else -1
        f0 = float(c["stuck_hz"])
        draw_status_panel(
            ax, c["freq_hz"], c["status"], c["side"], i, (0.9 * f0, 1.1 * f0), k == n - 1
        )
        counts = ", ".join(
            f"{c['status_at_peak'].get(s, 0)} {s}"
            for s in STATUS_NAMES
            if c["status_at_peak"].get(s)
        )
        stop = "" if c["completed"] else f"\nbranch stopped at {c['freq_hz'][-1]:.1f} Hz"
        ax.set_title(
            f"{c['damper']}: EO {c['eo']} (ND {c['nd']}), {c['force_n']:g} N\n"
            f"peak {c['peak_m'] * 1e3:.3f} mm at {c['peak_hz']:.1f} Hz: {counts}{stop}",
            fontsize=9,
        )
        ax.set_xlabel("frequency (Hz)")
        if k == 0:
            ax.set_ylabel("contact pair (side 0 below, side 1 above the dashed line)")
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    from ....render.palette import NOT_COMPUTED_COLOR, NOT_COMPUTED_EDGE

    extra = [
        Patch(
            facecolor=NOT_COMPUTED_COLOR, edgecolor=NOT_COMPUTED_EDGE, hatch="////",
            label="no point computed",
        ),
        Line2D([], [], color="k", lw=1.6, ls=(0, (2, 1.5)), label="peak"),
    ]  # fmt: skip
    fig.legend(handles=status_legend_handles() + extra, loc="lower center", ncol=6, frameon=False)
    fig.suptitle("Contact status of every pair in each damper's worst case", fontsize=11)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    return save_figure(fig, path)


def render_worst_fields(fields, path: str | Path) -> Path:
    """An off-screen picture of each damper's sector at its worst peak (``fields``: the
    ``worst`` records of :func:`.post.damper_post`, with their VTU), coloured by the largest
    displacement over the period (mm), deformed (exaggerated) as it is at the instant the
    response point is farthest out, the undeformed sector in grey."""
    from ....io import atomic_path
    from ....render.common import offscreen_pyvista

    pv = offscreen_pyvista()
    n = len(fields)
    p = pv.Plotter(shape=(1, n), off_screen=True, window_size=(640 * n, 640), border=False)
    top = max(float(f["max_disp_m"]) for f in fields) * 1e3
    for j, f in enumerate(fields):
        g = pv.read(f["vtu"]).extract_surface(nonlinear_subdivision=1, algorithm="dataset_surface")
        size = float(np.ptp(np.asarray(g.points), axis=0).max())
        scale = 0.08 * size / max(float(f["max_disp_m"]), 1e-300)
        w = g.copy()
        w.points = g.points + scale * 1e-3 * np.asarray(g.point_data["disp_at_peak_instant_mm"])
        p.subplot(0, j)
        p.add_mesh(g, style="wireframe", color="grey", opacity=0.35, line_width=0.5)
        last = j == n - 1
        p.add_mesh(
            w, scalars="disp_max_mm", cmap="viridis", clim=(0.0, top), show_scalar_bar=last,
            scalar_bar_args={"title": "max displacement, mm", "n_labels": 4, "vertical": True,
                             "position_x": 0.72, "position_y": 0.15, "height": 0.6,
                             "width": 0.05, "title_font_size": 16, "label_font_size": 14},
        )  # fmt: skip
        p.add_text(
            f"{f['damper']}: EO {f['eo']} (ND {f['nd']}), {f['force_n']:g} N, "
            f"{f['peak_hz']:.1f} Hz\n"
            f"peak {f['peak_m'] * 1e3:.3f} mm; shape at that instant x{scale:.0f}",
            font_size=10,
        )
        # along the disk axis (y), the blade (radial, z) upright: the tangential (x)
        # vibration in the picture's plane
        p.view_vector((0.0, -1.0, 0.0), viewup=(0.0, 0.0, 1.0))
        p.reset_camera()
        p.camera.zoom(0.85)
    path = Path(path)
    with atomic_path(path) as tmp:
        p.screenshot(str(tmp.with_name(tmp.name + ".png")))
        tmp.with_name(tmp.name + ".png").replace(tmp)
    p.close()
    return path
