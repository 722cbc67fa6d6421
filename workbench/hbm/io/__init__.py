"""Reading and writing hbm's records (the HDF5 layout of a branch or backbone)."""
