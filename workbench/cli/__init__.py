"""The ``upd`` command line: one sub-command per pipeline stage."""

import os

# One BLAS thread per process unless the user says otherwise: the dense
# solves here are small (threaded OpenBLAS made them ~10x slower on these
# machines), and under mpirun every rank is its own process. Set before
# numpy is first imported.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
