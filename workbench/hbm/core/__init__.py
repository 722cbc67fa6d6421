"""The harmonic balance itself: Fourier layout, AFT, the linear part, the system record,
the residual and Jacobian (:mod:`..balance`) and the solver options."""
