"""Studies: a study file (TOML) -> cases -> cached results -> figures and report.

``engine/`` is what every study kind shares: the specification (options from
defaults, a TOML file and the command line), the plan of cases and their cache
keys, the case runner with resume, lock and MPI scheduling, the model prefetch
and the outputs (manifest and report). ``kinds/`` holds one folder per study
kind (comparison, sweep, fidelity, robustness, uncertainty), each registered
by name: its own options, its computing, its figures and its report.
"""
