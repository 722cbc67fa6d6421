"""Stability of periodic solutions: Hill's method (:mod:`.hill`) and the verdicts along a
branch (:mod:`.along_path`)."""
