"""Node-to-node 3-D friction contact: the element record and its time-domain law.

* :class:`ContactElements` (``elements.py``): the sparse map ``W`` from the
  generalised coordinates to each element's local relative displacement
  ``[t1, t2, n]`` (damper minus platform, ``n > 0`` opening), and per-element
  ``mu``, ``kt1``, ``kt2``, ``kn``, ``n0`` (preload, N, compressive positive)
  and the law ("decoupled", the default, or "circular").
* ``law.py``: the law compiled with numba, vectorised over elements:
  :func:`aft_march` (two periods of samples -> force harmonics and their
  exact derivative, for the harmonic balance) and :func:`law_step` (one time
  step with its consistent tangent, for the time-integration reference);
  :func:`classify` gives the status of each element over a period:
  0 stuck, 1 stick-slip, 2 partial separation, 3 full separation.

Nothing here knows about harmonics beyond the synthesis/analysis matrices
it is handed; :mod:`workbench.hbm` owns the Fourier layout.
"""

from .elements import LAWS, ContactElements
from .law import (
    FULL_SEPARATION,
    PARTIAL_SEPARATION,
    STATUS_NAMES,
    STICK_SLIP,
    STUCK,
    aft_march,
    classify,
    march_samples,
)

__all__ = [
    "LAWS",
    "ContactElements",
    "aft_march",
    "classify",
    "march_samples",
    "STUCK",
    "STICK_SLIP",
    "PARTIAL_SEPARATION",
    "FULL_SEPARATION",
    "STATUS_NAMES",
]
