"""The picture of ``upd mesh``: the rig with the damper seated in its groove.

Three views side by side:

1. the whole rig in a three-quarter view (base clamped at the bottom), with
   the excitation and response points marked by arrows along x;
2. the groove cut at the middle of the contact lines and seen along +y: the
   roof-shaped groove of the two inclined platform faces with the damper's
   section seated in it (the cone's section is an ellipse: its axis tilts);
3. the groove seen from below and in front, the platforms translucent, with
   the contact points (one colour per platform) along the contact lines.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..geometry.records import BuiltGeometry
from ..io import atomic_path
from .common import offscreen_pyvista
from .palette import ARROW_COLORS, RIG_COLOR, SIDE_COLORS, damper_color

EXC_COLOR, RESP_COLOR = ARROW_COLORS


def mm_text(value_m: float, digits: int = 1) -> str:
    """A length in m written in mm with ``digits`` decimals, never "-0.0"."""
    out = f"{1e3 * value_m:.{digits}f}"
    return out[1:] if out.startswith("-") and float(out) == 0.0 else out


def _surface(pv, msh: Path):
    """Outer surface of a second-order tetrahedral mesh (curved, subdivided for display)."""
    from ..geometry.mshio import GMSH_TO_VTK_TET10, read_tet10

    x, conn = read_tet10(msh)
    cells = np.hstack([np.full((conn.shape[0], 1), 10), conn[:, GMSH_TO_VTK_TET10]]).ravel()
    grid = pv.UnstructuredGrid(cells, np.full(conn.shape[0], pv.CellType.QUADRATIC_TETRA), x)
    surf = grid.extract_surface(nonlinear_subdivision=2, algorithm="dataset_surface")
    return grid, surf


def render_scene(geo: BuiltGeometry, png: str | Path, title: str | None = None) -> Path:
    """Write a PNG of the rig and the seated damper with the contact points marked."""
    pv = offscreen_pyvista()
    rig_grid, rig = _surface(pv, Path(geo.rig_msh))
    dam_grid, damper = _surface(pv, Path(geo.damper_msh))
    pts = geo.contact.points
    side = geo.contact.side
    y_mid = float(np.median(pts[:, 1]))
    groove = max(float(np.ptp(pts[:, 0])), float(np.ptp(pts[:, 2])), 0.01)
    radius = 0.035 * groove
    look = dict(smooth_shading=True, ambient=0.25, diffuse=0.8, specular=0.1)
    damper_rgb = damper_color(geo.damper)  # the damper's colour in every figure
    p = pv.Plotter(off_screen=True, shape=(1, 3), window_size=(2100, 800), border=False)

    # 1. the whole rig
    p.subplot(0, 0)
    p.add_mesh(rig, color=RIG_COLOR, **look)
    p.add_mesh(damper, color=damper_rgb, **look)
    for name, where, color in (
        ("excitation", geo.excitation_points, EXC_COLOR),
        ("response", geo.response_points, RESP_COLOR),
    ):
        for k in range(2):
            out = np.sign(where[k, 0])  # the outer faces look away from x = 0
            start = where[k] + out * np.array([0.035, 0.0, 0.0])
            p.add_mesh(pv.Arrow(start=start, direction=(-out, 0.0, 0.0), scale=0.035), color=color)
        p.add_point_labels(
            where[:1] + np.array([-0.04, 0.0, 0.012]),
            [f"{name} (x)"],
            text_color=color,
            font_size=14,
            shape_opacity=0.0,
            show_points=False,
            always_visible=True,
        )
    p.add_text(title or f"rig + {geo.damper} damper", font_size=11, position="upper_edge")
    p.add_axes(line_width=2)
    p.view_vector((-0.6, -1.0, 0.45), viewup=(0.0, 0.0, 1.0))
    p.reset_camera()
    p.camera.zoom(1.2)

    # 2. section through the groove at the middle of the contact lines, seen along +y
    p.subplot(0, 1)
    rig_cut = rig_grid.slice(normal=(0.0, 1.0, 0.0), origin=(0.0, y_mid, 0.0)).clean()
    dam_cut = dam_grid.slice(normal=(0.0, 1.0, 0.0), origin=(0.0, y_mid, 0.0)).clean()
    flat = dict(ambient=1.0, diffuse=0.0, specular=0.0)
    p.add_mesh(rig_cut, color=RIG_COLOR, **flat)
    p.add_mesh(dam_cut, color=damper_rgb, **flat)
    for body in (rig_cut, dam_cut):
        p.add_mesh(
            body.extract_feature_edges(
                boundary_edges=True,
                feature_edges=False,
                manifold_edges=False,
                non_manifold_edges=False,
            ),
            color="#333333",
            line_width=2,
        )
    near = np.abs(pts[:, 1] - y_mid) <= np.abs(pts[:, 1] - y_mid).min() + 1e-9
    for k in range(2):
        sel = pts[near & (side == k)]
        if len(sel):
            p.add_mesh(
                pv.PolyData(sel).glyph(
                    geom=pv.Sphere(radius=1.5 * radius), scale=False, orient=False
                ),
                color=SIDE_COLORS[k],
                lighting=False,
            )
    p.add_text(
        f"section at y = {mm_text(y_mid)} mm, seen along +y", font_size=11, position="upper_edge"
    )
    c = np.array([0.0, y_mid, float(np.mean(pts[:, 2]))])
    p.camera.parallel_projection = True
    p.camera.focal_point = c
    p.camera.position = c + np.array([0.0, -1.0, 0.0])
    p.camera.up = (0.0, 0.0, 1.0)
    p.camera.parallel_scale = 2.2 * groove
    p.reset_camera_clipping_range()

    # 3. from below and in front, platforms translucent, every contact point
    p.subplot(0, 2)
    p.add_mesh(rig, color=RIG_COLOR, opacity=0.3, **look)
    p.add_mesh(damper, color=damper_rgb, opacity=0.45, **look)
    for k in range(2):
        sel = pts[side == k]
        p.add_mesh(
            pv.PolyData(sel).glyph(geom=pv.Sphere(radius=radius), scale=False, orient=False),
            color=SIDE_COLORS[k],
            label=f"contact points, platform {k + 1}",
            lighting=False,
        )
    p.add_legend(bcolor="white", face="circle", size=(0.36, 0.09), loc="lower left")
    gap = float(geo.stats.get("max_pair_gap_m", float("nan")))
    gap_text = (
        "matched node to node (gap zero)"
        if gap == 0.0
        else f"largest pair gap {mm_text(gap, 4)} mm"
        if gap == gap
        else "pair gap not recorded"
    )
    p.add_text(
        f"{geo.contact.n_pairs} contact pairs, {gap_text}",
        font_size=11,
        position="upper_edge",
    )
    c = np.asarray(geo.damper_centroid, dtype=float)
    span = max(float(np.ptp(pts[:, 1])), groove)
    p.camera.focal_point = c
    p.camera.position = c + np.array([-0.8, -1.6, -0.7]) * 2.0 * span
    p.camera.up = (0.0, 0.0, 1.0)
    p.camera.view_angle = 30.0
    p.reset_camera_clipping_range()

    png = Path(png)
    with atomic_path(png) as tmp:
        shot = tmp.with_name(tmp.name + ".png")
        p.screenshot(str(shot))
        shot.replace(tmp)
    p.close()
    return png
