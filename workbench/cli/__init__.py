"""The ``upd`` command line: one sub-command per pipeline stage."""
