"""Model input and records: the TOML model of ``upd frf`` (:mod:`..modelfile`,
:mod:`..modelcheck`), small example models (:mod:`..examples`) and the HDF5 writer of
every branch and backbone (:mod:`.record`)."""
