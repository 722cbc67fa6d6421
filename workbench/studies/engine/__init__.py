"""The machinery every study kind shares: spec, plan, case cache, resume, lock, MPI
scheduling, model prefetch, outputs (manifest and report)."""
