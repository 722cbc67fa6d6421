"""Contact status and friction energy painted on the damper at resonance (pyvista, off-screen).

For one case (a damper, a family, a force) and one point of its branch
(default: the resonance peak), two pictures of the damper seen from above
the groove (through the platforms, which are left out), its surface
translucent:

* ``*_status.png``: every contact pair as a sphere at its contact point,
  coloured by its status over the period (stuck, stick-slip, partial or
  full separation; the colours of :data:`.palette.STATUS_COLORS`, so the
  3-D maps and the status charts agree), with the count of each; the
  damper's surface in the damper's own colour;
* ``*_energy.png``: the same spheres coloured by the friction energy per
  cycle of each pair in mJ, on a log colour scale when the values span
  more than two decades. Pairs at or below the energy floor (1e-6 of the
  largest, :data:`workbench.post.tables.ENERGY_FLOOR_REL`) are light grey
  and counted as "zero (no slip)". A study draws all its maps on one colour scale
  (:func:`energy_scale` over every mapped case), so in-phase and
  out-of-phase maps, and the dampers, compare by colour.

The damper surface comes from ``damper.msh`` of the damper's geometry
folder (the second-order tetrahedra's outer faces); the contact points come
from the case itself, so a case with another contact layout is still drawn
at its own points.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io import atomic_path
from ..post.results import STATUS_NAMES, CaseResult
from .common import offscreen_pyvista
from .palette import ENERGY_CMAP, STATUS_COLORS, ZERO_ENERGY_COLOR, damper_color

log = logging.getLogger(__name__)

LOG_FLOOR = 1e-6  # log colour scale: values below this fraction of the largest sit at the floor
WINDOW = (1300, 1000)


def damper_surface(msh: str | Path):
    """The outer surface (pyvista PolyData, metres) of a second-order tetrahedral mesh."""
    from ..geometry.mshio import GMSH_TO_VTK_TET10, read_tet10

    pv = offscreen_pyvista()
    msh = Path(msh)
    if not msh.is_file():
        raise InputError("damper mesh", str(msh), "an existing damper.msh (upd mesh writes it)")
    x, conn = read_tet10(msh)
    cells = np.hstack([np.full((conn.shape[0], 1), 10), conn[:, GMSH_TO_VTK_TET10]]).ravel()
    grid = pv.UnstructuredGrid(cells, np.full(conn.shape[0], pv.CellType.QUADRATIC_TETRA), x)
    return grid.extract_surface(nonlinear_subdivision=1, algorithm="dataset_surface")


def _sphere_radius(points: np.ndarray) -> float:
    """A sphere radius that keeps neighbouring contact points apart (0.35 of their spacing)."""
    from scipy.spatial import cKDTree

    if len(points) < 2:
        return 1e-3
    d, _ = cKDTree(points).query(points, k=2)
    return 0.35 * float(np.median(d[:, 1]))


def _camera(p, surface) -> None:
    """Look down on the damper from above (+z), slightly tilted, with x up on the screen.

    Platform 1's contact (x < 0) is then at the bottom of the picture and
    platform 2's at the top, as in the status charts (side 0 below the
    dashed line); the damper's axis (y) runs across the picture.
    """
    c = np.asarray(surface.center, dtype=float)
    p.camera.focal_point = c
    p.camera.position = c + np.array([-0.1, -0.12, 1.0])
    p.camera.up = (1.0, 0.0, 0.0)
    p.camera.view_angle = 30.0
    p.reset_camera()
    p.camera.zoom(1.15)
    # lift the damper into the upper part of the picture: the legend goes below it
    cam = p.camera
    fp, pos = np.asarray(cam.focal_point), np.asarray(cam.position)
    height = 2.0 * np.linalg.norm(pos - fp) * np.tan(np.radians(cam.view_angle / 2.0))
    up = np.asarray(cam.up) / np.linalg.norm(cam.up)
    cam.focal_point = fp - 0.13 * height * up
    cam.position = pos - 0.13 * height * up
    p.reset_camera_clipping_range()


def _screenshot(p, png: Path) -> Path:
    with atomic_path(png) as tmp:
        shot = tmp.with_name(tmp.name + ".png")
        p.screenshot(str(shot))
        shot.replace(tmp)
    p.close()
    return png


STUCK_COLOR = ZERO_ENERGY_COLOR  # a pair that dissipates nothing (kept importable)


def energy_scale(energies) -> tuple[float, float, bool]:
    """(lowest, highest, log) colour range of friction energies (mJ) above the floor."""
    from ..post.tables import energy_floor

    e = (
        np.concatenate([np.ravel(np.asarray(v, dtype=float)) for v in energies])
        if len(energies)
        else np.zeros(0)
    )
    e = e[np.isfinite(e)]
    floor = energy_floor(e)
    up = e[e > floor]
    if up.size == 0:
        return 0.0, 1.0, False
    top = float(up.max())
    if top / float(up.min()) > 100.0:
        return float(up.min()), top, True
    return 0.0, top, False


def _heading(case: CaseResult, i: int) -> str:
    f = case.freq_hz[i]
    what = "resonance" if i == case.h1_peak_index else f"point {i}"
    fail = "  (branch failed)" if case.branch.failed else ""
    return (
        f"{case.damper}, {case.family}, F = {case.force_n:g} N: {what} at {f:.1f} Hz, "
        f"vibration amplitude (harmonic 1) {case.h1_mm[i]:.3g} mm{fail}"
    )


def render_contact_maps(
    case: CaseResult,
    geometry_dir: str | Path,
    out_stem: str | Path,
    *,
    point: int | None = None,
    scale: tuple[float, float, bool] | None = None,
) -> list[Path]:
    """Write ``<out_stem>_status.png`` and ``<out_stem>_energy.png``; return both paths.

    ``geometry_dir`` holds the damper's ``damper.msh``; ``point`` is the
    index on the case's branch (default: its resonance, the harmonic-1 peak); ``scale`` the
    energy colour range (:func:`energy_scale`; default: this case's own).
    """
    pv = offscreen_pyvista()
    geometry_dir = Path(geometry_dir)
    n_pts = case.branch.n_points
    i = case.h1_peak_index if point is None else int(point)
    if n_pts == 0 or not 0 <= i < n_pts:
        raise InputError("point", point, f"an index of the case's branch (0..{n_pts - 1})")
    pts = np.asarray(case.points, dtype=float)
    status = np.asarray(case.branch.status[i]).astype(int)
    energy = np.asarray(case.energy_mj[i], dtype=float)
    if pts.shape != (status.size, 3):
        raise InputError("case.points", pts.shape, f"({status.size}, 3): one point per pair")
    surface = damper_surface(geometry_dir / "damper.msh")
    radius = _sphere_radius(pts)
    sphere = pv.Sphere(radius=radius, theta_resolution=16, phi_resolution=16)
    look = dict(smooth_shading=True, ambient=0.3, diffuse=0.7, specular=0.05)
    out_stem = Path(out_stem)
    heading = _heading(case, i)
    side = np.asarray(case.side, dtype=int)

    def base(opacity: float = 0.3) -> object:
        # the damper in its own colour; fainter under the energy colours
        p = pv.Plotter(off_screen=True, window_size=WINDOW)
        p.add_mesh(surface, color=damper_color(case.damper), opacity=opacity, **look)
        p.add_text(heading, font_size=11, position="upper_edge")
        # label the first pair of each side, so the numbering of the status charts can be found
        for s in (0, 1):
            k = np.flatnonzero(side == s)
            if k.size:
                p.add_point_labels(
                    pts[k[:1]],
                    [f"pair {k[0] + 1} (platform {s + 1})"],
                    font_size=13,
                    shape_opacity=0.6,
                    point_size=1,
                    always_visible=True,
                    show_points=False,
                )
        p.add_axes(line_width=2, viewport=(0.86, 0.0, 1.0, 0.16))
        return p

    # status: one glyph set per status, a legend with the counts
    p = base()
    counts = np.bincount(np.clip(status, 0, 3), minlength=4)
    for k in range(4):
        sel = status == k
        if sel.any():
            glyphs = pv.PolyData(pts[sel]).glyph(geom=sphere, scale=False, orient=False)
            p.add_mesh(glyphs, color=STATUS_COLORS[k], lighting=False)
    p.add_legend(
        [[f"{STATUS_NAMES[k]} ({counts[k]})", STATUS_COLORS[k]] for k in range(4)],
        bcolor="white",
        face="circle",
        size=(0.28, 0.14),
        loc="lower left",
    )
    _camera(p, surface)
    status_png = _screenshot(p, out_stem.with_name(out_stem.name + "_status.png"))

    # energy: pairs above the floor coloured on the (shared) scale, the others grey
    from ..post.tables import ENERGY_FLOOR_REL, STUCK_TEXT

    p = base(0.15)
    lo, hi, log_scale = scale if scale is not None else energy_scale([energy])
    floor = ENERGY_FLOOR_REL * hi if hi > 0 else 0.0
    slip = np.isfinite(energy) & (energy > floor)
    n_stuck = int((~slip).sum())
    title = "friction energy per cycle (mJ)" + (", log" if log_scale else "")
    if scale is not None:
        title += "; one scale for every map of the study"
    if slip.any():
        cloud = pv.PolyData(pts[slip])
        cloud["energy_mj"] = np.clip(energy[slip], lo if log_scale else 0.0, hi)
        glyphs = cloud.glyph(geom=sphere, scale=False, orient=False)
        p.add_mesh(
            glyphs,
            scalars="energy_mj",
            cmap=ENERGY_CMAP,
            clim=(lo, hi),
            log_scale=log_scale,
            lighting=False,
            scalar_bar_args=dict(
                title="",
                vertical=False,
                n_labels=5,
                fmt="%.1e",
                position_x=0.25,
                position_y=0.035,
                width=0.5,
                height=0.08,
                label_font_size=13,
            ),
        )
        p.add_text(title, position=(int(0.25 * WINDOW[0]), int(0.125 * WINDOW[1])), font_size=11)
    if n_stuck:
        glyphs = pv.PolyData(pts[~slip]).glyph(geom=sphere, scale=False, orient=False)
        p.add_mesh(glyphs, color=STUCK_COLOR, lighting=False)
        p.add_legend(
            [[f"{STUCK_TEXT} ({n_stuck}): <= {ENERGY_FLOOR_REL:g} x {hi:.2g} mJ", STUCK_COLOR]],
            bcolor="white",
            face="circle",
            size=(0.3, 0.06),
            loc="upper left",
        )
    p.add_text(
        f"total {float(energy[slip].sum()):.3g} mJ per cycle over {energy.size} pairs",
        font_size=10,
        position="lower_left",
    )
    _camera(p, surface)
    energy_png = _screenshot(p, out_stem.with_name(out_stem.name + "_energy.png"))
    log.debug("contact maps of %s: %s, %s", case.case_id, status_png, energy_png)
    return [status_png, energy_png]
