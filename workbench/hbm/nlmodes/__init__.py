"""Nonlinear modes: the backbone continued in modal amplitude (:mod:`.backbone`), its
path problem and corrector (:mod:`.problem`), the EPMC equations (:mod:`..epmc`,
:mod:`..epmc_condensed`), the record (:mod:`.record`) and the synthesised forced
response (:mod:`..synthesis`)."""
