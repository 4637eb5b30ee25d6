r"""How much memory a sparse factorization will take, and how much the machine has.

The sparse solvers refuse a model only when its factorization does not fit the memory the
machine has available now (``MemAvailable`` of ``/proc/meminfo``), never by a fixed size.

The factor's size is a measured model (neither SciPy's SuperLU nor scikit-sparse's CHOLMOD
binding reports the symbolic count before the numeric factorization):

.. math::  \operatorname{nnz}(L)_{CHOLMOD} \approx c_C\, \operatorname{nnz}(A)\, n^{1/3},
           \qquad
           \operatorname{nnz}(L + U)_{SuperLU} \approx c_S\, \operatorname{nnz}(A)\, n^{2/3},

measured on the benchmark box (Q1 hexahedra, two tied halves, 3D elasticity): CHOLMOD's
nested-dissection-like ordering gives the :math:`n^{4/3}` fill of 3D meshes (``c_C`` 0.231 at
9.7k coordinates, 0.204 at 29k); SuperLU's ``MMD_AT_PLUS_A`` in symmetric mode grows like
:math:`n^{5/3}` (``c_S`` 0.0205 and 0.0206).  :data:`CHOLMOD_FILL` and :data:`SUPERLU_FILL` round
them up; both are upper bounds for 2D meshes and chains, whose fill grows more slowly.  Each
stored entry is taken as 12 bytes (a float and an index; twice that for complex factors) and
the factorization's working memory as :data:`WORK_FACTOR` times the factor.
"""

from __future__ import annotations

import scipy.sparse as sp

from substruct.machine import available_memory

__all__ = [
    "CHOLMOD_FILL",
    "SUPERLU_FILL",
    "WORK_FACTOR",
    "factor_entries",
    "factor_memory",
    "gigabytes",
    "require_memory",
]

#: ``c_C`` of the CHOLMOD fill model (module docstring).
CHOLMOD_FILL = 0.25
#: ``c_S`` of the SuperLU fill model (module docstring).
SUPERLU_FILL = 0.022
#: Peak memory of a factorization as a multiple of its factor's bytes.
WORK_FACTOR = 1.2


def factor_entries(A: sp.sparray | sp.spmatrix, kind: str) -> float:
    r"""Estimated nonzeros of the factor of the square sparse ``A`` by ``kind``
    (``"cholmod"``: :math:`c_C \operatorname{nnz}(A) n^{1/3}`; anything else, SuperLU:
    :math:`c_S \operatorname{nnz}(A) n^{2/3}`), at least ``nnz(A)``."""
    n = float(max(A.shape[0], 1))
    nnz = float(sp.csr_array(A).nnz)
    fill = CHOLMOD_FILL * n ** (1.0 / 3.0) if kind == "cholmod" else \
        SUPERLU_FILL * n ** (2.0 / 3.0)
    return max(nnz, fill * nnz)


def factor_memory(A: sp.sparray | sp.spmatrix, kind: str, *, complex_factor: bool = False
                  ) -> float:
    """Estimated peak bytes of factorizing ``A`` by ``kind`` (:func:`factor_entries` x 12
    bytes, x 2 for a complex factor, x :data:`WORK_FACTOR`)."""
    per = 24.0 if complex_factor else 12.0
    return WORK_FACTOR * per * factor_entries(A, kind)


def gigabytes(nbytes: float) -> str:
    """``"3.2 GB"`` (one decimal; ``"0.05 GB"`` below 0.1 GB)."""
    g = float(nbytes) / 1e9
    return f"{g:.2f} GB" if g < 0.1 else f"{g:.1f} GB"



def require_memory(need: float, what: str, available: float | None = None) -> None:
    """Refuse work estimated to need ``need`` bytes when the machine has less available
    (:func:`available_memory`; nothing is refused where that is unknown).

    Raises:
        ValueError: one line, e.g. ``the factorization of 300000 coordinates (CHOLMOD) needs
            about 31.0 GB; 22.9 GB are available``.
    """
    have = available_memory() if available is None else available
    if have is not None and need > have:
        raise ValueError(f"{what} needs about {gigabytes(need)}; {gigabytes(have)} are "
                         f"available on this machine")
