"""Two Jenkins elements (decoupled): slip limit ``mu N`` on each tangential axis.

State ``s = [T1, T2, u1, u2]``: the tangential force and displacement at
the previous sample. Predictor ``T* = T1 + kt1 (u1 - s[2])``, corrector
``T = clip(T*, -mu N, mu N)`` per axis; separated (``N = 0``): ``T = 0``
and the slider follows. As in "On the efficiency of a conical
under-platform damper for turbines".
"""

from __future__ import annotations

from numba import njit

from . import SLIP_TOL
from ._common import begin

NAME = "decoupled"
N_STATE = 4


@njit(cache=True)
def step(u, s, mu, kt1, kt2, kn, n0, lp, want_jac, f, s_new, Fu, Fs, Su, Ss):
    N = begin(u, kn, n0, want_jac, f, s_new, Fu, Fs, Su, Ss)
    if N <= 0.0:
        return 2
    lim = mu * N
    flag = 0
    for a in range(2):
        kt = kt1 if a == 0 else kt2
        Tp = s[a] + kt * (u[a] - s[2 + a])
        if abs(Tp) <= lim:
            T = Tp
            if want_jac:
                Fu[a, a] = kt
                Fs[a, a] = 1.0
                Fs[a, 2 + a] = -kt
        else:
            sg = 1.0 if Tp > 0.0 else -1.0
            T = sg * lim
            if abs(Tp) - lim > SLIP_TOL * lim:
                flag = 1
            if want_jac:
                Fu[a, 2] = -sg * mu * kn
        f[a] = T
        s_new[a] = T
        if want_jac:
            for b in range(3):
                Su[a, b] = Fu[a, b]
            for b in range(4):
                Ss[a, b] = Fs[a, b]
    return flag
