"""The bladed-disk study's own options: the disk, the engine orders, the sector reduction.

Declared once here; ``upd study`` (parser and help), the study specification,
the report's input table and docs/STUDIES.md read them through the kind
registry (:mod:`workbench.studies.kinds`). The dampers and forces are the
shared ``dampers`` and ``forces`` options; the rig section is ``geometry``
and the mesh ``mesh-size``.
"""

from __future__ import annotations

from dataclasses import dataclass

from ....geometry.disk import MAX_BLADES
from ....study_options import option


@dataclass(frozen=True)
class BladedDiskOptions:
    """The bladed-disk study's own options, one field each (``spec.bladed_disk.<name>``)."""

    n_blades: int = option(
        "int",
        12,
        "bladed-disk: number of blades N of the disk (one sector is modelled)",
        "bladed-disk",
        lo=2,
        hi=MAX_BLADES,
        role="model",
    )
    eos: list[int] = option(
        "ints",
        [],
        "bladed-disk: engine orders of the excitation (whole numbers >= 0; an EO above "
        "N/2 maps onto its nodal diameter, backward or forward); empty: every EO 0..N/2",
        "bladed-disk",
        lo=0,
        role="case",
    )
    damper_mesh_size: float | None = option(
        "float",
        None,
        "bladed-disk: global element size of the damper, mm (None: the geometry file's)",
        "bladed-disk",
        lo=0.5,
        hi=50.0,
        optional=True,
        unit="mm",
        role="model",
    )
    contact_points: int | None = option(
        "int",
        None,
        "bladed-disk: contact points per line of the cone and cylinder and per full row of "
        "the wedge (2 rows a face); None: the geometry files' (23 per line, 5 rows of 15)",
        "bladed-disk",
        lo=2,
        hi=200,
        optional=True,
        role="model",
    )
    sector_modes: int = option(
        "int",
        6,
        "bladed-disk: fixed-interface modes per nodal diameter of the sector's reduction",
        "bladed-disk",
        lo=1,
        hi=500,
        role="model",
    )
    damper_modes: int = option(
        "int",
        4,
        "bladed-disk: fixed-interface modes of the damper's reduction",
        "bladed-disk",
        lo=0,
        hi=200,
        role="model",
    )
    fan_families: int = option(
        "int",
        3,
        "bladed-disk: mode families in the fan diagram",
        "bladed-disk",
        lo=1,
        hi=50,
    )
