"""Study runner: a study file (TOML) -> cases -> cached results -> figures and report.

A study file's keys are the ``upd study`` option names (``forces``,
``phases``, ``mesh-size`` ...); the command line overrides the file;
unknown keys are refused with a hint naming the closest valid one. Each
case (one damper, one inter-blade phase, one excitation level, one set of
modelling knobs) is cached under a hash of its canonical parameters, so a
study that was interrupted resumes where it stopped.
"""
