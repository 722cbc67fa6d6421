"""Node-to-node 3-D friction contact: the element record and its time-domain law.

* :class:`ContactElements` (``elements.py``): the sparse map ``W`` from the
  generalised coordinates to each element's local relative displacement
  ``[t1, t2, n]`` (damper minus platform, ``n > 0`` opening), and per-element
  ``mu``, ``kt1``, ``kt2``, ``kn``, ``n0`` (preload, N, compressive positive)
  and the law ("decoupled", the default, "circular" or "dahl").
* ``laws/``: one module per law, each a compiled ``step`` (force, new state
  and their derivatives for one sample); a new law is one new module there.
* ``march.py``: the one march for every law: periods of samples until the
  state repeats, the exact derivative chained through every sample;
  ``law.py``: :func:`aft_march` (force harmonics and their derivative, for
  the harmonic balance) and :func:`classify` (the status of each element
  over a period: 0 stuck, 1 stick-slip, 2 partial separation, 3 full
  separation). The time integration calls the law's ``step`` directly.

Nothing here knows about harmonics beyond the synthesis/analysis matrices
it is handed; :mod:`workbench.hbm` owns the Fourier layout.
"""

from .elements import ContactElements
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
from .laws import LAWS, get_law
from .march import march

__all__ = [
    "LAWS",
    "ContactElements",
    "aft_march",
    "get_law",
    "march",
    "classify",
    "march_samples",
    "STUCK",
    "STICK_SLIP",
    "PARTIAL_SEPARATION",
    "FULL_SEPARATION",
    "STATUS_NAMES",
]
