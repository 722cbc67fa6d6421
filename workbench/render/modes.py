"""Mode shapes of the rig and damper as off-screen pyvista pictures.

Input is a :class:`workbench.fe.modes.ModesResult` (plain arrays: P2 node
coordinates, VTK cells, displacement per mode), so nothing here touches
dolfinx. Each picture shows the deformed rig and damper coloured by the
displacement magnitude (relative to its maximum in that mode: mode shapes
have no absolute size) over the undeformed outline, seen along +y so that
bending in x (the first bending pair) reads directly: in-phase, both blade
tips move the same way; out-of-phase, they move towards/away from each other.

Every picture states its deformation scale factor (the shapes are
mass-normalised, so the factor is what makes the largest displacement a
few percent of the rig's height) and has a close-up of the damper in its
groove beneath the full view: the damper opaque on the same colour scale,
the rig around it clipped and translucent, seen along the damper's axis.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..io import atomic_path
from .common import offscreen_pyvista

DEFORM_FRACTION = 0.07  # largest rig displacement drawn as this fraction of the rig height
MAX_FRACTION = 0.12  # ... unless the damper would then move more than this fraction
COLOR_TITLE = "displacement / max"
OUTLINE_COLOR = "#9aa5b1"


def _grids(pv, result) -> dict[str, Any]:
    """One surface per body carrying every mode as a point array ``m<k>``."""
    out = {}
    for name, sh in result.shapes.items():
        grid = pv.UnstructuredGrid(
            np.asarray(sh.cells, dtype=np.int64),
            np.asarray(sh.celltypes, dtype=np.uint8),
            np.asarray(sh.points, dtype=float),
        )
        for k in range(sh.disp.shape[0]):
            grid.point_data[f"m{k}"] = sh.disp[k]
        out[name] = grid.extract_surface(nonlinear_subdivision=1, algorithm="dataset_surface")
    return out


def _scale(result, surfs: dict[str, Any], k: int) -> tuple[float, float]:
    """(deformation factor, max |u| over all bodies) for mode ``k``.

    The rig sets the scale (its bending is what the picture is about); a
    damper that moves much more than the blades is not drawn flying off.
    """
    umax = {n: float(np.linalg.norm(s.point_data[f"m{k}"], axis=1).max()) for n, s in surfs.items()}
    pts = np.vstack([s.points for s in surfs.values()])
    height = float(np.ptp(pts[:, 2])) or 1.0
    ref = umax.get("rig", 0.0) or max(umax.values())
    top = max(umax.values())
    if top <= 0:
        return 0.0, 0.0
    factor = min(DEFORM_FRACTION * height / ref, MAX_FRACTION * height / top)
    return factor, top


def _warped(s, k: int, factor: float, umax: float):
    w = s.warp_by_vector(f"m{k}", factor=factor)
    w.point_data[COLOR_TITLE] = np.linalg.norm(s.point_data[f"m{k}"], axis=1) / (umax or 1.0)
    return w


def _draw(pv, p, result, surfs: dict[str, Any], k: int, title: str) -> None:
    factor, umax = _scale(result, surfs, k)
    first = True
    for s in surfs.values():
        p.add_mesh(s, style="wireframe", color=OUTLINE_COLOR, opacity=0.12, line_width=0.5)
        p.add_mesh(
            _warped(s, k, factor, umax),
            scalars=COLOR_TITLE,
            cmap="viridis",
            clim=(0.0, 1.0),
            smooth_shading=True,
            show_scalar_bar=first,
            scalar_bar_args=dict(
                title=COLOR_TITLE, vertical=True, position_x=0.86, position_y=0.2, height=0.6
            ),
        )
        first = False
    p.add_text(title, font_size=10, position="upper_left")
    p.add_text(_scale_text(factor), font_size=9, position="lower_left")
    p.view_xz()
    p.camera.azimuth = 25.0
    p.camera.elevation = 15.0
    p.camera.zoom(0.95)


def _scale_text(factor: float) -> str:
    return f"deformation drawn x {factor:.3g} (mass-normalised shape, grey wireframe: undeformed)"


CLOSEUP_MARGIN = 0.5  # the close-up box: the damper's bounds grown by this share of its size


def _draw_closeup(pv, p, result, surfs: dict[str, Any], k: int) -> None:
    """The damper (opaque) in the clipped, translucent rig around it, along the damper axis."""
    factor, umax = _scale(result, surfs, k)
    dmp = surfs.get("damper")
    if dmp is None:
        return
    b = np.array(dmp.bounds).reshape(3, 2)
    grow = CLOSEUP_MARGIN * float(np.ptp(b, axis=1).max())
    box = (b + np.array([-grow, grow])).ravel().tolist()
    rig = surfs.get("rig")
    if rig is not None:
        near = _warped(rig, k, factor, umax).clip_box(box, invert=False)
        if near.n_points:
            p.add_mesh(
                near,
                scalars=COLOR_TITLE,
                cmap="viridis",
                clim=(0.0, 1.0),
                opacity=0.4,
                show_scalar_bar=False,
            )
    p.add_mesh(dmp, style="wireframe", color=OUTLINE_COLOR, opacity=0.25, line_width=0.5)
    p.add_mesh(
        _warped(dmp, k, factor, umax),
        scalars=COLOR_TITLE,
        cmap="viridis",
        clim=(0.0, 1.0),
        smooth_shading=True,
        show_scalar_bar=False,
    )
    p.add_text(
        f"close-up: the {result.damper} damper in its groove (same colours and "
        "scale; the platforms around it translucent)",
        font_size=9,
        position="upper_left",
    )
    p.view_xz()
    p.reset_camera(bounds=box)
    p.camera.azimuth = 35.0
    p.camera.elevation = 20.0
    p.camera.zoom(1.2)


def _title(result, k: int) -> str:
    label = result.labels[k] if k < len(result.labels) else ""
    head = (
        f"{result.damper} damper, contact {result.contact}: mode {k + 1}, "
        f"{result.freqs_hz[k]:.1f} Hz"
    )
    return head + (f"\n{label}" if label else "")


def render_modes(result, out_dir: str | Path, *, modes: list[int] | None = None) -> list[Path]:
    """Write ``mode_<k>.png`` for each mode (default all) and ``first_bending.png``.

    ``first_bending.png`` puts the first bending in-phase and out-of-phase
    modes side by side (when both were found). Returns the files written.
    Needs the shapes (``compute_modes(..., shapes=True)``, rank 0).
    """
    if not result.shapes:
        raise ValueError("the result carries no mode shapes (compute_modes(shapes=True), rank 0)")
    pv = offscreen_pyvista()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    surfs = _grids(pv, result)
    n = len(result.freqs_hz)
    ks = list(range(n)) if modes is None else [int(k) for k in modes if 0 <= int(k) < n]
    files = []
    closeup = "damper" in surfs
    rows = 2 if closeup else 1
    weights = dict(row_weights=[2, 1]) if closeup else {}
    for k in ks:
        p = pv.Plotter(
            off_screen=True,
            shape=(rows, 1),
            window_size=(1000, 900 + 450 * closeup),
            border=False,
            **weights,
        )
        _draw(pv, p, result, surfs, k, _title(result, k))
        if closeup:
            p.subplot(1, 0)
            _draw_closeup(pv, p, result, surfs, k)
        files.append(_shot(p, out / f"mode_{k + 1:02d}.png"))
    pair = [k for k in (result.in_phase, result.out_of_phase) if k is not None]
    if pair:
        p = pv.Plotter(
            off_screen=True,
            shape=(rows, len(pair)),
            window_size=(900 * len(pair), 900 + 450 * closeup),
            border=False,
            **weights,
        )
        for j, k in enumerate(pair):
            p.subplot(0, j)
            _draw(pv, p, result, surfs, k, _title(result, k))
            if closeup:
                p.subplot(1, j)
                _draw_closeup(pv, p, result, surfs, k)
        files.append(_shot(p, out / "first_bending.png"))
    return files


def _shot(p, path: Path) -> Path:
    with atomic_path(path) as tmp:
        p.screenshot(str(tmp.with_suffix(".png")))
        tmp.with_suffix(".png").replace(tmp)
    p.close()
    return path
