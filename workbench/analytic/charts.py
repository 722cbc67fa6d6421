"""Data behind the analytic charts: tables of arrays, written as CSV.

Each function returns a :class:`Table` in long ("tidy") form: one row per
point, one column per quantity, units in the column names. The pictures are
drawn by :mod:`workbench.render.analytic_plots` from these tables, so a CSV
holds exactly what its PNG shows.

The paper's figures use fixed families (platform angle 36/45/60 deg, R1
5/10/20 mm, L 40/50/60 mm, cone angles 5/10/15 deg). Here the design being
studied is added to each family when it is not already in it, so that the
charts also answer "where does my damper sit".
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..io import atomic_path
from .cone import ConeDesign, _alpha1, _gamma, _max_slip, section_slip_ratio
from .rigid import in_phase_motion, rigid_body_kinematics, sweep_cone_angle

PAPER_BETAS_DEG = (36.0, 45.0, 60.0)
PAPER_R1S_MM = (5.0, 10.0, 20.0)
PAPER_LENGTHS_MM = (40.0, 50.0, 60.0)
PAPER_CONE_ANGLES_DEG = (5.0, 10.0, 15.0)


@dataclass(frozen=True)
class Table:
    """Named columns of equal length (numbers, or strings for labels)."""

    name: str  # file stem
    title: str
    columns: dict[str, np.ndarray]

    def __post_init__(self) -> None:
        lengths = {k: len(v) for k, v in self.columns.items()}
        assert len(set(lengths.values())) <= 1, lengths

    def __len__(self) -> int:
        return len(next(iter(self.columns.values()))) if self.columns else 0

    def __getitem__(self, key: str) -> np.ndarray:
        return self.columns[key]

    def where(self, **equal: float | str) -> Table:
        """The rows whose columns equal the given values."""
        mask = np.ones(len(self), dtype=bool)
        for k, v in equal.items():
            col = self.columns[k]
            mask &= np.isclose(col, v) if col.dtype.kind == "f" else (col == v)
        return Table(self.name, self.title, {k: c[mask] for k, c in self.columns.items()})

    def write_csv(self, path: str | Path) -> Path:
        """Write the table as CSV (header row of column names) atomically."""
        path = Path(path)
        keys = list(self.columns)
        with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
            wr = csv.writer(fh)
            wr.writerow(keys)
            for row in zip(*(self.columns[k] for k in keys), strict=True):
                wr.writerow([f"{v:.10g}" if isinstance(v, float | np.floating) else v for v in row])
        return path


#: The last cone angle of a sweep sits this far below beta (deg): the damper is
#: then within about a third of a degree of vertical, and both slip estimates
#: have nearly reached their limits, while the 3-D solve stays well conditioned.
VERTICAL_MARGIN_DEG = 1e-3


def cone_angle_grid(beta_deg: float, step_deg: float = 0.25) -> np.ndarray:
    """Cone angles from 0 up to just below ``beta_deg``, about ``step_deg`` apart.

    The last point is ``beta_deg - VERTICAL_MARGIN_DEG``, so curves run to the
    vertical limit without reaching the excluded ``alpha_c = beta``.
    """
    n = max(int(np.ceil(beta_deg / step_deg)), 4) + 1
    grid = np.linspace(0.0, beta_deg, n)
    grid[-1] = beta_deg - VERTICAL_MARGIN_DEG
    return grid


def _with(values: tuple[float, ...], extra: float) -> list[float]:
    return sorted(set(values) | {float(extra)})


def inclination_table(design: ConeDesign, step_deg: float = 0.25) -> Table:
    """Inclination gamma and alpha_1 vs cone angle, beta 36, 45, 60 deg and the design (Fig. 3)."""
    cols: dict[str, list] = {
        "beta_deg": [],
        "cone_angle_deg": [],
        "gamma_deg": [],
        "alpha1_deg": [],
    }
    for beta in _with(PAPER_BETAS_DEG, design.beta_deg):
        ac = cone_angle_grid(beta, step_deg)
        g = _gamma(np.radians(ac), np.radians(beta))
        cols["beta_deg"].append(np.full(ac.shape, beta))
        cols["cone_angle_deg"].append(ac)
        cols["gamma_deg"].append(np.degrees(g))
        cols["alpha1_deg"].append(np.degrees(_alpha1(g, np.radians(beta))))
    return Table(
        "inclination_vs_cone_angle",
        "Damper inclination vs cone angle (paper Fig. 3)",
        {k: np.concatenate(v) for k, v in cols.items()},
    )


def slip_along_table(design: ConeDesign, n_points: int = 41) -> Table:
    """Slip along the damper for cone angles 5, 10, 15 deg and the design's (Fig. 5).

    Columns: paper eq 6 (signed, the same on both lines) and the exact 3-D
    rigid-body slip on each line (longitudinal, transverse, magnitude).
    Cone angles at or above ``beta_deg`` are left out.
    """
    cols: dict[str, list] = {
        k: []
        for k in (
            "cone_angle_deg",
            "side",
            "position_mm",
            "slip_ratio_paper",
            "longitudinal_slip_ratio_3d",
            "transverse_slip_ratio_3d",
            "slip_ratio_3d",
        )
    }
    for ac in _with(PAPER_CONE_ANGLES_DEG, design.cone_angle_deg):
        if ac >= design.beta_deg:
            continue
        d = design.replace(cone_angle_deg=ac)
        kin = rigid_body_kinematics(d, in_phase_motion(), n_points)
        paper = section_slip_ratio(d, kin.position_mm)
        for k in range(2):
            cols["cone_angle_deg"].append(np.full(n_points, ac))
            cols["side"].append(np.full(n_points, k))
            cols["position_mm"].append(kin.position_mm)
            cols["slip_ratio_paper"].append(paper)
            cols["longitudinal_slip_ratio_3d"].append(kin.longitudinal[k])
            cols["transverse_slip_ratio_3d"].append(kin.transverse[k])
            cols["slip_ratio_3d"].append(kin.slip_ratio[k])
    return Table(
        "slip_along_damper",
        "Kinematic slip along the damper (paper Fig. 5)",
        {k: np.concatenate(v) for k, v in cols.items()},
    )


def max_slip_table(design: ConeDesign, step_deg: float = 0.25) -> Table:
    """Largest slip ratio vs cone angle, varying beta, R1 and L one at a time (Fig. 6 a-c).

    ``family`` says which parameter varies; the others keep the design's
    values. Paper eq 6 and the exact 3-D result (transverse and total).
    """
    cases = (
        [
            ("beta", design.replace(beta_deg=b, cone_angle_deg=0.0))
            for b in _with(PAPER_BETAS_DEG, design.beta_deg)
        ]
        + [
            ("r1", design.replace(r1_mm=r, cone_angle_deg=0.0))
            for r in _with(PAPER_R1S_MM, design.r1_mm)
        ]
        + [
            ("length", design.replace(length_mm=L, cone_angle_deg=0.0))
            for L in _with(PAPER_LENGTHS_MM, design.length_mm)
        ]
    )
    cols: dict[str, list] = {
        k: []
        for k in (
            "family",
            "beta_deg",
            "r1_mm",
            "length_mm",
            "cone_angle_deg",
            "max_slip_ratio_paper",
            "max_transverse_slip_ratio_3d",
            "max_slip_ratio_3d",
        )
    }
    for family, d in cases:
        ac = cone_angle_grid(d.beta_deg, step_deg)
        exact = sweep_cone_angle(ac, d.beta_deg, d.r1_mm, d.length_mm)
        cols["family"].append(np.full(ac.shape, family, dtype=object))
        cols["beta_deg"].append(np.full(ac.shape, d.beta_deg))
        cols["r1_mm"].append(np.full(ac.shape, d.r1_mm))
        cols["length_mm"].append(np.full(ac.shape, d.length_mm))
        cols["cone_angle_deg"].append(ac)
        cols["max_slip_ratio_paper"].append(_max_slip(ac, d.beta_deg, d.r1_mm, d.length_mm))
        cols["max_transverse_slip_ratio_3d"].append(exact["max_transverse_slip_ratio"])
        cols["max_slip_ratio_3d"].append(exact["max_slip_ratio"])
    return Table(
        "max_slip_vs_cone_angle",
        "Largest kinematic slip vs cone angle (paper Fig. 6)",
        {k: np.concatenate(v) for k, v in cols.items()},
    )


def comparison_table(design: ConeDesign, step_deg: float = 0.25) -> Table:
    """Paper eq 6 against the exact 3-D kinematics over all cone angles (design's beta, R1, L).

    Ratios are NaN at a cone angle of 0 (both slips vanish for a cylinder).
    """
    ac = cone_angle_grid(design.beta_deg, step_deg)
    paper = _max_slip(ac, design.beta_deg, design.r1_mm, design.length_mm)
    exact = sweep_cone_angle(ac, design.beta_deg, design.r1_mm, design.length_mm)
    with np.errstate(invalid="ignore", divide="ignore"):
        ok = paper > 1e-12
        rt = np.where(ok, exact["max_transverse_slip_ratio"] / np.where(ok, paper, 1.0), np.nan)
        rtot = np.where(ok, exact["max_slip_ratio"] / np.where(ok, paper, 1.0), np.nan)
    return Table(
        "paper_vs_3d",
        "Paper eq 6 vs exact 3-D rigid-body slip",
        {
            "cone_angle_deg": ac,
            "max_slip_ratio_paper": paper,
            "max_transverse_slip_ratio_3d": exact["max_transverse_slip_ratio"],
            "max_longitudinal_slip_ratio_3d": exact["max_longitudinal_slip_ratio"],
            "max_slip_ratio_3d": exact["max_slip_ratio"],
            "transverse_3d_over_paper": rt,
            "total_3d_over_paper": rtot,
            "difference_3d_minus_paper": exact["max_slip_ratio"] - paper,
        },
    )


def contact_slip_table(design: ConeDesign, n_points: int = 23) -> Table:
    """Slip at every contact point of both lines (exact 3-D, unit in-phase motion)."""
    kin = rigid_body_kinematics(design, in_phase_motion(), n_points)
    n = kin.position_mm.size
    pts = kin.points_mm.reshape(-1, 3)
    glob = np.einsum("kij,kni->knj", kin.geometry.frames, kin.slip_ratio_local).reshape(-1, 3)
    return Table(
        "contact_line_slip_3d",
        "Slip at the contact points (exact 3-D)",
        {
            "side": np.repeat([0, 1], n),
            "position_mm": np.tile(kin.position_mm, 2),
            "x_mm": pts[:, 0],
            "y_mm": pts[:, 1],
            "z_mm": pts[:, 2],
            "slip_x_ratio": glob[:, 0],
            "slip_y_ratio": glob[:, 1],
            "slip_z_ratio": glob[:, 2],
            "longitudinal_slip_ratio": kin.longitudinal.ravel(),
            "transverse_slip_ratio": kin.transverse.ravel(),
            "slip_ratio": kin.slip_ratio.ravel(),
            "slip_ratio_paper": np.tile(section_slip_ratio(design, kin.position_mm), 2),
        },
    )


def best_cone_angle(table: Table, column: str) -> tuple[float, float]:
    """(cone angle deg, value) where ``column`` of a :func:`comparison_table` is largest."""
    i = int(np.nanargmax(table[column]))
    return float(table["cone_angle_deg"][i]), float(table[column][i])
