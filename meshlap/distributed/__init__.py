"""The same operator over the ranks of an MPI communicator (PETSc matrices, SLEPc spectra).

:func:`laplacian` builds a :class:`DistributedLaplacian`; :mod:`~.solvers` holds its uses.
Requires mpi4py, petsc4py and (for :func:`eigs`) slepc4py; the rest of meshlap never
imports this package.
"""

from .operator import DistributedLaplacian, laplacian
from .solvers import eigs, heat_flow, implicit_heat, mean_curvature_normal

__all__ = ["DistributedLaplacian", "eigs", "heat_flow", "implicit_heat", "laplacian",
           "mean_curvature_normal"]
