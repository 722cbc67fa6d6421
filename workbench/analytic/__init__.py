"""Design-stage kinematics of a conical under-platform damper, without finite elements.

* :mod:`~workbench.analytic.cone`: the closed-form estimate of "On the
  efficiency of a conical under-platform damper for turbines" (eqs 1-6):
  axis inclination ``gamma``, the section angle ``alpha_1``, and the
  kinematic slip along the damper under in-phase (radial) platform motion.
* :mod:`~workbench.analytic.rigid`: the same kinematics computed exactly in
  3-D (a rigid cone tangent to both platform planes, small rigid motion from
  a constrained least-squares solve), as a cross-check of the estimate.
* :mod:`~workbench.analytic.charts`: the tables behind the charts (CSV).

Angles in degrees, lengths in millimetres; slips are ratios to the relative
radial displacement ``v`` of the platforms.

>>> from workbench.analytic import ConeDesign, paper_kinematics, rigid_body_kinematics
>>> d = ConeDesign(beta_deg=45, cone_angle_deg=10, r1_mm=10, length_mm=40)
>>> round(paper_kinematics(d).max_slip_ratio, 3)
0.352
>>> round(rigid_body_kinematics(d).max_transverse_slip_ratio, 3)
0.181
"""

from .cone import (
    ConeDesign,
    PaperKinematics,
    alpha1_deg,
    check_cone_angle,
    inclination_deg,
    longitudinal_slip_ratio,
    max_slip_ratio,
    paper_kinematics,
    section_slip_ratio,
)
from .rigid import (
    ConeInGroove,
    RigidBodyKinematics,
    groove_geometry,
    in_phase_motion,
    rigid_body_kinematics,
    sweep_cone_angle,
)

__all__ = [
    "ConeDesign",
    "PaperKinematics",
    "alpha1_deg",
    "check_cone_angle",
    "inclination_deg",
    "longitudinal_slip_ratio",
    "max_slip_ratio",
    "paper_kinematics",
    "section_slip_ratio",
    "ConeInGroove",
    "RigidBodyKinematics",
    "groove_geometry",
    "in_phase_motion",
    "rigid_body_kinematics",
    "sweep_cone_angle",
]
