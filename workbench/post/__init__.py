"""Post-processing of study results: peaks, energies, contact status shares, tables.

Plain numpy on :class:`~workbench.post.results.StudyResults`; the pictures
are made in :mod:`workbench.render` from what these functions return.
"""
