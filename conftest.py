"""Skip collecting meshlap.distributed's doctests where petsc4py is not installed (the rest of
meshlap never imports it; tests/test_distributed.py states the skip itself)."""

import importlib.util

collect_ignore = []
if importlib.util.find_spec("petsc4py") is None or importlib.util.find_spec("mpi4py") is None:
    collect_ignore.append("meshlap/distributed.py")
