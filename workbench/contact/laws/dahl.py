"""Dahl's smooth friction (regularised Jenkins) on each tangential axis.

Between samples the force follows ``dT/du = kt (1 - sgn(du) T / (mu N))``
exactly for the step ``du = u - u_prev`` (constant ``N`` over the step):

    T = s mu N + (T_prev - s mu N) exp(-kt |du| / (mu N)),   s = sgn(du),

so the force approaches the slip limit ``+-mu N`` smoothly instead of
clipping at it (initial stiffness ``kt``, no sharp stick/slip transition);
it tends to the Jenkins element as the loop grows. State
``s = [T1, T2, u1, u2]`` as for the Jenkins laws; separated: ``T = 0``.
The status counts a sample as slipping when ``|T|`` is above 99 % of the
limit. This module is the example of adding a law: nothing else changes.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._common import begin

NAME = "dahl"
N_STATE = 4


@njit(cache=True)
def step(u, s, mu, kt1, kt2, kn, n0, lp, want_jac, f, s_new, Fu, Fs, Su, Ss):
    N = begin(u, kn, n0, want_jac, f, s_new, Fu, Fs, Su, Ss)
    if N <= 0.0:
        return 2
    if mu <= 0.0:  # no friction: no tangential force
        f[0] = 0.0
        f[1] = 0.0
        s_new[0] = 0.0
        s_new[1] = 0.0
        return 0
    L = mu * N
    flag = 0
    for a in range(2):
        kt = kt1 if a == 0 else kt2
        du = u[a] - s[2 + a]
        sg = 1.0 if du >= 0.0 else -1.0
        x = kt * sg * du / L  # >= 0
        ex = np.exp(-x)
        T = sg * L + (s[a] - sg * L) * ex
        if abs(T) > 0.99 * L:
            flag = 1
        f[a] = T
        s_new[a] = T
        if want_jac:
            dT_ddu = (s[a] - sg * L) * ex * (-kt * sg / L)
            dT_dTp = ex
            # through L = mu N (N = n0 - kn un): dT/dL, then dL/dun = -mu kn
            dT_dL = sg - sg * ex + (s[a] - sg * L) * ex * (x / L)
            Fu[a, a] = dT_ddu
            Fu[a, 2] = dT_dL * (-mu * kn)
            Fs[a, a] = dT_dTp
            Fs[a, 2 + a] = -dT_ddu
            for b in range(3):
                Su[a, b] = Fu[a, b]
            for b in range(4):
                Ss[a, b] = Fs[a, b]
    return flag
