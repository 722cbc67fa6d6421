"""The compiled small-system corrector: one call per solve (AFT, residual, Jacobian, Newton).

Plain Python that numba compiles (:mod:`.small` binds ``march``, the law's
compiled contact march, and compiles one copy per law, on demand or ahead
of time). It is the corrector of :mod:`.corrector` for systems of a few
hundred harmonic unknowns or fewer with modal damping, where the work of a
point is small next to the Python and PETSc overhead around it, and it
takes the same steps: the residual and the Jacobian of
:class:`.balance.HarmonicBalance` (modal receptances), and Newton with the
backtracking line search and the convergence test of PETSc SNES as
:class:`.corrector.Corrector` sets them up (``newtonls``, ``bt`` with at
most ``line_search_max_it`` cubic steps, ``alpha`` 1e-4, ``minlambda``
1e-12, ``maxstep`` 1e8, ``stol`` 1e-8), on the natural system at fixed
frequency or the bordered pseudo-arc-length system (plane or sphere). The
results agree with the PETSc path to round-off (tests/test_small.py).

Layout: unknowns ``X`` (nh, n_s) in the Fourier layout of :mod:`.fourier`;
``V`` (n3, n_s) maps them to the contact displacements (a selection in the
condensed space, ``W`` in the physical one); ``Sz`` (n_s, nz) and ``Bz``
(n3, nz) are the unknowns' and the contacts' maps on the modal coordinates.
"""

from __future__ import annotations

import numpy as np

march = None  # bound per law by workbench.hbm.forced.small: the law's compiled contact march

# integer codes of the outcome (workbench.hbm.forced.small turns them into SNES reason names)
ITERATING, CONV_FNORM, CONV_STALL, CONV_SNORM = 0, 1, 2, 3
DIV_MAX_IT, DIV_LOCAL_MIN, DIV_NAN = 4, 5, 6


def coef(hk, kind, wn2, zw, w, deriv):
    """Modal receptance of each Fourier component: real and imaginary parts (nh, nz)."""
    nh = hk.size
    nz = wn2.size
    dr = np.zeros((nh, nz))
    di = np.zeros((nh, nz))
    for c in range(nh):
        k = hk[c]
        for m in range(nz):
            den = complex(wn2[m] - (k * w) ** 2, 2.0 * zw[m] * k * w)
            d = 1.0 / den
            if deriv:
                d = -complex(-2.0 * k * k * w, 2.0 * zw[m] * k) * d * d
                if kind[c] == 0:
                    d = 0.0
            dr[c, m] = d.real
            di[c, m] = d.imag
    return dr, di


def combine(kind, dr, di, T):
    """Apply the receptances to harmonics T (nh, nz) (cos/sin pairs rotate)."""
    nh, nz = T.shape
    Y = np.empty((nh, nz))
    for c in range(nh):
        if kind[c] == 0:
            for m in range(nz):
                Y[c, m] = T[c, m] * dr[c, m]
        elif kind[c] == 1:
            s = c + 1
            for m in range(nz):
                a, b = dr[c, m], di[c, m]
                Y[c, m] = a * T[c, m] + b * T[s, m]
                Y[s, m] = a * T[s, m] - b * T[c, m]
    return Y


def evaluate(x, w, kind, E, P, Pz, Sz, Bz, V, mu, kt1, kt2, kn, n0, lp, kc, anchor, act, has_dc,
             ns, mtol, mper, ws):  # fmt: skip
    """The state at unknowns x (N,) and w (rad/s) into the workspace tuple ``ws``.

    ``ws`` = (U, G, D, ut, f, F, J, n_slip, n_sep, contact, periods, conv, Yz, r, T):
    the evaluation of :meth:`HarmonicBalance.evaluate` and its AFT.
    """
    U, G, D, ut, f, F, J, n_slip, n_sep, contact, periods, conv, Yz, r, T = ws
    nh, nt = P.shape
    n_s = Sz.shape[0]
    n3 = Bz.shape[0]
    n_el = n3 // 3
    X = x.reshape(nh, n_s)
    U[:, :] = X @ V.T
    for e in range(n_el):
        for j in range(nt):
            for a in range(3):
                acc = 0.0
                for h in range(nh):
                    acc += E[j, h] * U[h, 3 * e + a]
                ut[e, j, a] = acc
    march(ns, ut, E, P, mu, kt1, kt2, kn, n0, lp, act, True, mtol, mper,
          f, F, J, n_slip, n_sep, contact, periods, conv)  # fmt: skip
    for e in range(n_el):
        for a in range(3):
            for h in range(nh):
                G[h, 3 * e + a] = F[e, a, h] - kc[e, a] * U[h, 3 * e + a]
                for b in range(3):
                    for c in range(nh):
                        D[e, a, h, b, c] = J[e, a, h, b * nh + c]
                D[e, a, h, a, h] -= kc[e, a]
    for e in range(n_el):  # inactive directions never move and act on nothing: no entries
        for a in range(3):
            for b in range(3):
                if not (act[e, a] and act[e, b]):
                    for h in range(nh):
                        for c in range(nh):
                            D[e, a, h, b, c] = 0.0
    if has_dc:
        for e in range(n_el):
            for a in range(2):
                if anchor[e, a] != 0.0:
                    G[0, 3 * e + a] += anchor[e, a] * U[0, 3 * e + a]
                    D[e, a, 0, a, 0] += anchor[e, a]
    T[:, :] = Pz - G @ Bz
    return T


def residual(x, w, hk, kind, wn2, zw, E, P, Pz, Sz, Bz, V, mu, kt1, kt2, kn, n0, lp, kc, anchor,
             act, has_dc, ns, mtol, mper, ws):  # fmt: skip
    """r (N,) at (x, w): ``X - S H (P - W^T G)``; the evaluation stays in ``ws``."""
    T = evaluate(x, w, kind, E, P, Pz, Sz, Bz, V, mu, kt1, kt2, kn, n0, lp, kc, anchor, act, has_dc,
                 ns, mtol, mper, ws)  # fmt: skip
    dr, di = coef(hk, kind, wn2, zw, w, False)
    Yz = ws[12]
    Yz[:, :] = combine(kind, dr, di, T)
    r = ws[13]
    nh, n_s = P.shape[0], Sz.shape[0]
    r[:] = x - (Yz @ Sz.T).reshape(nh * n_s)
    return r


def residual_omega(w, hk, kind, wn2, zw, Sz, ws):
    """dr/dw (N,) at the evaluation in ``ws`` (its T = P - W^T G)."""
    T = ws[14]
    dr, di = coef(hk, kind, wn2, zw, w, True)
    dY = combine(kind, dr, di, T)
    return -(dY @ Sz.T).ravel()


def jacobian(w, hk, kind, wn2, zw, Sz, Bz, V, ws):
    """dr/dx (N, N) at the evaluation in ``ws``: ``I + S H W^T D V`` (dense)."""
    D = ws[2]
    n_el = D.shape[0]
    nh = D.shape[2]
    n_s = Sz.shape[0]
    n3 = Bz.shape[0]
    N = nh * n_s
    dr, di = coef(hk, kind, wn2, zw, w, False)
    Jm = np.zeros((N, N))
    dG = np.zeros((nh, n3))
    for c in range(nh):
        for q in range(n_s):
            dG[:, :] = 0.0
            nz_col = False
            for e in range(n_el):
                for b in range(3):
                    v = V[3 * e + b, q]
                    if v != 0.0:
                        nz_col = True
                        for a in range(3):
                            for h in range(nh):
                                dG[h, 3 * e + a] += D[e, a, h, b, c] * v
            col = c * n_s + q
            Jm[col, col] += 1.0
            if not nz_col:
                continue
            Yc = combine(kind, dr, di, dG @ Bz)
            R = Yc @ Sz.T
            for h in range(nh):
                for i in range(n_s):
                    Jm[h * n_s + i, col] += R[h, i]
    return Jm


def _norm(v):
    s = 0.0
    for i in range(v.size):
        s += v[i] * v[i]
    return np.sqrt(s)


def _con_value(kc_, ys, wsc, cx, cw, c0, mx, mw, xc, wc, ds):
    """The constraint's value at scaled (ys, wsc): plane (kc_ 1) or sphere (kc_ 2)."""
    if kc_ == 2:
        d2 = 0.0
        for i in range(ys.size):
            d2 += mx[i] * (ys[i] - xc[i]) ** 2
        d2 += mw * (wsc - wc) ** 2
        return (d2 - ds * ds) / (2.0 * ds)
    acc = 0.0
    for i in range(ys.size):
        acc += cx[i] * ys[i]
    return acc + cw * wsc - c0


def _con_row(kc_, ys, wsc, cx, cw, mx, mw, xc, wc, ds):
    if kc_ == 2:
        return mx * (ys - xc) / ds, mw * (wsc - wc) / ds
    return cx.copy(), cw


def _func(y, kcon, wfix, hk, kind, wn2, zw, E, P, Pz, Sz, Bz, V, mu, kt1, kt2, kn, n0, lp, kc,
          anchor, act, has_dc, ns, mtol, mper, ws, u_ref, w_ref, cx, cw, c0, mx, mw, xc, wc,
          ds):  # fmt: skip
    """The SNES function: scaled residual (and the constraint row), inf where not finite."""
    N = Sz.shape[0] * P.shape[0]
    wsc = y[N] if kcon > 0 else wfix
    r = residual(y[:N] * u_ref, wsc * w_ref, hk, kind, wn2, zw, E, P, Pz, Sz, Bz, V, mu, kt1,
                 kt2, kn, n0, lp, kc, anchor, act, has_dc, ns, mtol, mper, ws)  # fmt: skip
    out = np.empty(y.size)
    out[:N] = r / u_ref
    if kcon > 0:
        out[N] = _con_value(kcon, y[:N], wsc, cx, cw, c0, mx, mw, xc, wc, ds)
    ok = True
    for i in range(out.size):
        if not np.isfinite(out[i]):
            ok = False
    if not ok:
        out[:] = np.inf
    return out


def solve(y0, kcon, wfix, hk, kind, wn2, zw, E, P, Pz, Sz, Bz, V, mu, kt1, kt2, kn, n0, lp, kc,
          anchor, act, has_dc, ns, mtol, mper, ws, u_ref, w_ref, cx, cw, c0, mx, mw, xc, wc, ds,
          tol, tol_stall, stag, max_newton, ls_max, lsn, y_out, info):  # fmt: skip
    """Newton with the bt line search and the convergence test of the SNES corrector.

    ``kcon``: 0 natural (unknowns ``xs``, frequency ``wfix`` scaled), 1 plane,
    2 sphere (unknowns ``[xs, ws]``). Writes the last iterate to ``y_out`` and
    ``info`` = [reason code, iterations, own test passed, residual evaluations,
    stalled acceptances]; the workspace holds the evaluation at ``y_out``. ``lsn``
    (2,): the line search's stored (xnorm, ynorm), updated in place.
    """
    alpha, minlambda, maxstep, stol = 1e-4, 1e-12, 1e8, 1e-8
    stall = 4
    N = Sz.shape[0] * P.shape[0]
    n = y0.size
    X = y0.copy()
    hist = np.zeros(max_newton + 4)
    Y = np.zeros(n)
    nfun = 0
    F = _func(X, kcon, wfix, hk, kind, wn2, zw, E, P, Pz, Sz, Bz, V, mu, kt1, kt2, kn, n0, lp, kc,
              anchor, act, has_dc, ns, mtol, mper, ws, u_ref, w_ref, cx, cw, c0, mx, mw, xc, wc,
              ds)  # fmt: skip
    nfun += 1
    at = X.copy()  # where the workspace's evaluation is
    reason = ITERATING
    own = 0
    nstalled = 0
    it = 0
    nh_ = 0
    while True:
        # -- the convergence test (iteration it, F at X) --------------------------
        fin = True
        for i in range(n):
            if not np.isfinite(F[i]):
                fin = False
        if not fin:
            reason = DIV_NAN
            break
        rn = 0.0
        for i in range(N):
            if abs(F[i]) > rn:
                rn = abs(F[i])
        xm = 0.0
        for i in range(N):
            if abs(X[i]) > xm:
                xm = abs(X[i])
        scale = max(xm, 1.0)
        if it == 0:
            nh_ = 0
        hist[nh_] = rn
        nh_ += 1
        c_ok = kcon == 0 or abs(F[N]) <= 1e-9
        if rn <= tol * scale and c_ok:
            reason = CONV_FNORM
            own = 1
            break
        if nh_ > stall and hist[nh_ - 1] > 0.5 * hist[nh_ - 1 - stall] and rn <= 1e-4 * scale:
            if rn <= tol_stall * scale and c_ok:
                nstalled += 1
                own = 1
                reason = CONV_STALL
            else:
                reason = DIV_LOCAL_MIN
            break
        if stag > 0 and nh_ > stag and hist[nh_ - 1] > 0.5 * hist[nh_ - 1 - stag]:
            reason = DIV_LOCAL_MIN
            break
        if it >= max_newton:
            reason = DIV_MAX_IT
            break
        # -- the Newton direction at X ------------------------------------------------
        if not np.array_equal(at, X):
            _func(X, kcon, wfix, hk, kind, wn2, zw, E, P, Pz, Sz, Bz, V, mu, kt1, kt2, kn, n0, lp,
                  kc, anchor, act, has_dc, ns, mtol, mper, ws, u_ref, w_ref, cx, cw, c0, mx, mw, xc,
                  wc, ds)  # fmt: skip
            nfun += 1
            at[:] = X
        wsc = X[N] if kcon > 0 else wfix
        Jm = jacobian(wsc * w_ref, hk, kind, wn2, zw, Sz, Bz, V, ws)
        if kcon > 0:
            jw = residual_omega(wsc * w_ref, hk, kind, wn2, zw, Sz, ws) * (w_ref / u_ref)
            rx, rw = _con_row(kcon, X[:N], wsc, cx, cw, mx, mw, xc, wc, ds)
            rhs = np.empty((N, 2))
            rhs[:, 0] = F[:N]
            rhs[:, 1] = jw
            z = np.linalg.solve(Jm, rhs)
            z1 = z[:, 0]
            z2 = z[:, 1]
            den = rw - np.dot(rx, z2)
            big = 0.0
            for i in range(N):
                if abs(z2[i]) > big:
                    big = abs(z2[i])
            srx = 0.0
            for i in range(N):
                srx += abs(rx[i])
            Y = np.empty(n)
            if abs(den) <= 1e-14 * (abs(rw) + srx * max(big, 1.0)):
                Y[:N] = z1
                Y[N] = 0.0
            else:
                b = (F[N] - np.dot(rx, z1)) / den
                Y[:N] = z1 - b * z2
                Y[N] = b
            JY = np.empty(n)
            JY[:N] = Jm @ Y[:N] + jw * Y[N]
            JY[N] = np.dot(rx, Y[:N]) + rw * Y[N]
        else:
            Y = np.linalg.solve(Jm, F)
            JY = Jm @ Y
        # -- the bt line search: X <- X - lambda Y (PETSc 3.18 SNESLINESEARCHBT) -----------
        # lsn: the line search's stored (xnorm, ynorm); kept across iterations and solves
        # (a failed search leaves them as they were, as PETSc's does)
        ynorm = _norm(Y)
        xnorm = _norm(X)
        W = X.copy()
        Gv = F.copy()
        lam = 1.0
        failed = False
        moved = True
        if ynorm == 0.0:
            lsn[0] = xnorm
            lsn[1] = 0.0
            failed = True
            moved = False
        else:
            if ynorm > maxstep:
                Y = Y * (maxstep / ynorm)
                ynorm = maxstep
            fn = _norm(F)
            f0 = fn * fn
            slope = np.dot(F, JY)
            if slope > 0.0:
                slope = -slope
            if slope == 0.0:
                slope = -1.0
            g = np.inf
            while True:
                W = X - lam * Y
                Gv = _func(W, kcon, wfix, hk, kind, wn2, zw, E, P, Pz, Sz, Bz, V, mu, kt1, kt2,
                           kn, n0, lp, kc, anchor, act, has_dc, ns, mtol, mper, ws, u_ref, w_ref,
                           cx, cw, c0, mx, mw, xc, wc, ds)  # fmt: skip
                nfun += 1
                at[:] = W
                gn = _norm(Gv)
                g = gn * gn
                if np.isfinite(g) or lam <= minlambda:
                    break
                lam = 0.5 * lam
            if not np.isfinite(g):
                reason = DIV_NAN
                break
            if 0.5 * g <= 0.5 * f0 + lam * alpha * slope:
                pass
            elif stol * xnorm > ynorm:  # a tiny step that does not reduce: X stays
                lsn[0] = xnorm
                lsn[1] = ynorm
                moved = False
            else:
                lt = -slope / (g - f0 - 2.0 * lam * slope)
                lprev = lam
                gprev = g
                if lt > 0.5 * lam:
                    lt = 0.5 * lam
                lam = 0.1 * lam if lt <= 0.1 * lam else lt
                W = X - lam * Y
                Gv = _func(W, kcon, wfix, hk, kind, wn2, zw, E, P, Pz, Sz, Bz, V, mu, kt1, kt2,
                           kn, n0, lp, kc, anchor, act, has_dc, ns, mtol, mper, ws, u_ref, w_ref,
                           cx, cw, c0, mx, mw, xc, wc, ds)  # fmt: skip
                nfun += 1
                at[:] = W
                gn = _norm(Gv)
                g = gn * gn
                if not np.isfinite(g):
                    failed = True
                    moved = False
                elif not (0.5 * g < 0.5 * f0 + lam * alpha * slope):
                    for _ in range(ls_max):
                        if lam <= minlambda:
                            failed = True
                            moved = False
                            break
                        t1 = 0.5 * (g - f0) - lam * slope
                        t2 = 0.5 * (gprev - f0) - lprev * slope
                        aa = (t1 / (lam * lam) - t2 / (lprev * lprev)) / (lam - lprev)
                        bb = (-lprev * t1 / (lam * lam) + lam * t2 / (lprev * lprev)) / (
                            lam - lprev
                        )
                        dd = bb * bb - 3.0 * aa * slope
                        if dd < 0.0:
                            dd = 0.0
                        if aa == 0.0:
                            lt = -slope / (2.0 * bb)
                        else:
                            lt = (-bb + np.sqrt(dd)) / (3.0 * aa)
                        lprev = lam
                        gprev = g
                        if lt > 0.5 * lam:
                            lt = 0.5 * lam
                        lam = 0.1 * lam if lt <= 0.1 * lam else lt
                        W = X - lam * Y
                        Gv = _func(W, kcon, wfix, hk, kind, wn2, zw, E, P, Pz, Sz, Bz, V, mu,
                                   kt1, kt2, kn, n0, lp, kc, anchor, act, has_dc, ns, mtol, mper,
                                   ws, u_ref, w_ref, cx, cw, c0, mx, mw, xc, wc, ds)  # fmt: skip
                        nfun += 1
                        at[:] = W
                        gn = _norm(Gv)
                        g = gn * gn
                        if not np.isfinite(g):
                            failed = True
                            moved = False
                            break
                        if 0.5 * g < 0.5 * f0 + lam * alpha * slope:
                            break
            if moved:
                lsn[0] = _norm(W)
                lsn[1] = ynorm
        if moved:
            X = W
            F = Gv
        it += 1
        if failed and stol * lsn[0] > lsn[1]:
            reason = CONV_SNORM
            break
    y_out[:] = X
    if own and not np.array_equal(at, X):  # the workspace holds the evaluation at a solution
        _func(X, kcon, wfix, hk, kind, wn2, zw, E, P, Pz, Sz, Bz, V, mu, kt1, kt2, kn, n0, lp, kc,
              anchor, act, has_dc, ns, mtol, mper, ws, u_ref, w_ref, cx, cw, c0, mx, mw, xc, wc,
              ds)  # fmt: skip
        nfun += 1
    info[0] = reason
    info[1] = it
    info[2] = own
    info[3] = nfun
    info[4] = nstalled
    return reason


def solve_flat(y0, kcon, wfix, hk, kind, wn2, zw, E, P, Pz, Sz, Bz, V, mu, kt1, kt2, kn, n0, lp,
               kc, anchor, act, has_dc, ns, mtol, mper, U, G, D, ut, f, F, J, n_slip, n_sep,
               contact, periods, conv, Yz, r, T, u_ref, w_ref, cx, cw, c0, mx, mw, xc, wc, ds,
               tol, tol_stall, stag, max_newton, ls_max, lsn, y_out, info):  # fmt: skip
    """:func:`solve` with the workspace as separate arrays (one fixed signature)."""
    ws = (U, G, D, ut, f, F, J, n_slip, n_sep, contact, periods, conv, Yz, r, T)
    return solve(y0, kcon, wfix, hk, kind, wn2, zw, E, P, Pz, Sz, Bz, V, mu, kt1, kt2, kn, n0, lp,
                 kc, anchor, act, has_dc, ns, mtol, mper, ws, u_ref, w_ref, cx, cw, c0, mx, mw,
                 xc, wc, ds, tol, tol_stall, stag, max_newton, ls_max, lsn, y_out,
                 info)  # fmt: skip


def evaluate_flat(x, w, hk, kind, wn2, zw, E, P, Pz, Sz, Bz, V, mu, kt1, kt2, kn, n0, lp, kc,
                  anchor, act, has_dc, ns, mtol, mper, U, G, D, ut, f, F, J, n_slip, n_sep,
                  contact, periods, conv, Yz, r, T):  # fmt: skip
    """:func:`residual` at unknowns ``x`` (m) and ``w`` (rad/s) into the separate workspace."""
    ws = (U, G, D, ut, f, F, J, n_slip, n_sep, contact, periods, conv, Yz, r, T)
    residual(x, w, hk, kind, wn2, zw, E, P, Pz, Sz, Bz, V, mu, kt1, kt2, kn, n0, lp, kc, anchor,
             act, has_dc, ns, mtol, mper, ws)  # fmt: skip
    return 0


# the signatures of solve_flat and evaluate_flat (numba types), for the ahead-of-time build;
# lp, the law's own parameters per element, is the 2-D array after n0 (zero columns when none)
SIGNATURE = (
    "i8(f8[::1], i8, f8, f8[::1], i8[::1], f8[::1], f8[::1], f8[:, ::1], f8[:, ::1], "
    "f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[::1], f8[::1], f8[::1], f8[::1], "
    "f8[::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], b1[:, ::1], b1, i8, f8, i8, f8[:, ::1], "
    "f8[:, ::1], "
    "f8[:, :, :, :, ::1], f8[:, :, ::1], f8[:, :, ::1], f8[:, :, ::1], f8[:, :, :, ::1], "
    "i8[::1], i8[::1], b1[:, ::1], i8[::1], b1[::1], f8[:, ::1], f8[::1], f8[:, ::1], f8, f8, "
    "f8[::1], f8, f8, f8[::1], f8, f8[::1], f8, f8, f8, f8, i8, i8, i8, f8[::1], f8[::1], "
    "i8[::1])"
)
EVAL_SIGNATURE = (
    "i8(f8[::1], f8, f8[::1], i8[::1], f8[::1], f8[::1], f8[:, ::1], f8[:, ::1], "
    "f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[::1], f8[::1], f8[::1], f8[::1], "
    "f8[::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], b1[:, ::1], b1, i8, f8, i8, f8[:, ::1], "
    "f8[:, ::1], "
    "f8[:, :, :, :, ::1], f8[:, :, ::1], f8[:, :, ::1], f8[:, :, ::1], f8[:, :, :, ::1], "
    "i8[::1], i8[::1], b1[:, ::1], i8[::1], b1[::1], f8[:, ::1], f8[::1], f8[:, ::1])"
)
