"""Linear algebra shared by every layer, one idea a module; it imports nothing else of substruct.

* :mod:`~substruct.linalg.dense`: dense copies of matrices known to be small;
* :mod:`~substruct.linalg.scaling`: row equilibration of constraints (safe for tiny rows),
  the mass scale of coordinates, massless coordinates, the spectral norm;
* :mod:`~substruct.linalg.constraints`: rank, independent rows, consistency, particular
  solutions and the pseudo-inverse of ``A M^-1 A^T``, decided on equilibrated rows;
* :mod:`~substruct.linalg.nullspace`: bases of ``null(A)``, dense (SVD) and sparse
  (master-slave elimination);
* :mod:`~substruct.linalg.massless`: the massless directions ``null(M) & null(A)``, dense,
  and block by block in a sparse mass, made coordinates for the sparse eigensolvers;
* :mod:`~substruct.linalg.factorize`: the one registry of sparse factorizations by name;
  :mod:`~substruct.linalg.backends` its backends (PARDISO, CHOLMOD, SuperLU after METIS,
  SuperLU) and the automatic choice with fallback.
"""

from substruct.linalg.constraints import (
    ConstraintError,
    IndependentRows,
    check_consistent,
    independent_rows,
    particular_solution,
    pinv_sym,
)
from substruct.linalg.dense import dense
from substruct.linalg.factorize import FACTORIZATIONS, Factorize, Solve, factorizer, has_cholmod
from substruct.linalg.nullspace import Elimination, master_slave, null_space_basis
from substruct.linalg.scaling import (
    Equilibrated,
    RowScale,
    ZeroRowError,
    equilibrate,
    mass_column_scale,
    massless_coordinates,
    row_scale,
    spectral_norm,
)

__all__ = [
    "FACTORIZATIONS",
    "ConstraintError",
    "Elimination",
    "Equilibrated",
    "Factorize",
    "IndependentRows",
    "RowScale",
    "Solve",
    "ZeroRowError",
    "check_consistent",
    "dense",
    "equilibrate",
    "factorizer",
    "has_cholmod",
    "independent_rows",
    "mass_column_scale",
    "massless_coordinates",
    "master_slave",
    "null_space_basis",
    "particular_solution",
    "pinv_sym",
    "row_scale",
    "spectral_norm",
]
