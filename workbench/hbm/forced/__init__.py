"""Forced responses: the curve at one excitation level over a band (:mod:`.response`), its
corrector (PETSc, :mod:`..corrector`; compiled for small systems, :mod:`..small`), peaks
and the record (:mod:`..branch`)."""
