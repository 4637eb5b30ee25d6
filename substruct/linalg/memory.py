r"""How much memory a sparse factorization will take, and how much the machine has.

The sparse solvers refuse a model only when its factorization does not fit the memory the
machine has available now (``MemAvailable`` of ``/proc/meminfo``), never by a fixed size.

The peak memory of a factorization (and a solve with it) is a measured model per backend and
matrix kind (:mod:`substruct.linalg.backends`), none of the backends reporting its need before
the numeric factorization:

.. math::  \text{peak} \approx b_0 + c\, \operatorname{nnz}(A)\, n^{p},

:math:`p = 1/3` for the nested-dissection orderings (PARDISO, CHOLMOD, SuperLU after METIS: the
:math:`n^{4/3}` fill of 3D meshes), :math:`p = 2/3` for SuperLU's own minimum-degree ordering
(fill measured to grow like :math:`n^{5/3}`), :math:`p = 1` for SuperLU on saddle points
(its threshold pivoting adds fill).  :data:`PEAK` holds :math:`(b_0, c, p)`, fitted by least
squares to the process's high-water mark above its resident memory in
``benchmarks/factorization.py`` on the benchmark box (10k, 30k and, but for plain SuperLU, 100k
coordinates; docs/performance.md), :math:`c` then raised until no measured peak exceeds the
model: the model is 1.0-1.26 times every measured peak.  They are upper bounds for 2D meshes and chains, whose fill grows more slowly.

:func:`factor_entries` keeps the fill models of the factor's entries for CHOLMOD and SuperLU,
:math:`c_C \operatorname{nnz}(A) n^{1/3}` (``c_C`` 0.231 at 9.7k coordinates, 0.204 at 29k) and
:math:`c_S \operatorname{nnz}(A) n^{2/3}` (``c_S`` 0.0205 and 0.0206).
"""

from __future__ import annotations

import scipy.sparse as sp

from substruct.machine import available_memory, gigabytes

__all__ = [
    "CHOLMOD_FILL",
    "PEAK",
    "SUPERLU_FILL",
    "factor_entries",
    "factor_memory",
    "require_memory",
]

#: ``c_C`` of the CHOLMOD fill model (module docstring).
CHOLMOD_FILL = 0.25
#: ``c_S`` of the SuperLU fill model (module docstring).
SUPERLU_FILL = 0.022

#: ``(b_0 bytes, c bytes, p)`` of the peak-memory model per ``(backend, matrix kind)``.
PEAK: dict[tuple[str, str], tuple[float, float, float]] = {
    ("cholmod", "spd"): (24e6, 2.792, 1 / 3),
    ("pardiso", "complex-symmetric"): (64e6, 4.715, 1 / 3),
    ("pardiso", "spd"): (49e6, 2.698, 1 / 3),
    ("pardiso", "symmetric"): (65e6, 3.029, 1 / 3),
    ("superlu", "complex-symmetric"): (32e6, 0.4096, 2 / 3),
    ("superlu", "spd"): (12e6, 0.224, 2 / 3),
    ("superlu", "symmetric"): (2e6, 0.01501, 1.0),
    ("superlu-metis", "complex-symmetric"): (22e6, 8.333, 1 / 3),
    ("superlu-metis", "spd"): (47e6, 4.879, 1 / 3),
    ("superlu-metis", "symmetric"): (38e6, 6.119, 1 / 3),
}


def factor_entries(A: sp.sparray | sp.spmatrix, kind: str) -> float:
    r"""Estimated nonzeros of the factor of the square sparse ``A`` by ``kind``
    (``"cholmod"``: :math:`c_C \operatorname{nnz}(A) n^{1/3}`; anything else, SuperLU:
    :math:`c_S \operatorname{nnz}(A) n^{2/3}`), at least ``nnz(A)``."""
    n = float(max(A.shape[0], 1))
    nnz = float(sp.csr_array(A).nnz)
    fill = CHOLMOD_FILL * n ** (1.0 / 3.0) if kind == "cholmod" else \
        SUPERLU_FILL * n ** (2.0 / 3.0)
    return max(nnz, fill * nnz)


def factor_memory(A: sp.sparray | sp.spmatrix, kind: str, *, complex_factor: bool = False,
                  matrix: str = "spd") -> float:
    r"""Estimated peak bytes of factorizing ``A`` with the backend ``kind`` (``"pardiso"``,
    ``"cholmod"``, ``"superlu-metis"``, ``"superlu"``) as the matrix kind ``matrix``
    (``"spd"``, ``"symmetric"``, ``"complex-symmetric"``; ``complex_factor``: the last):
    :math:`b_0 + c \operatorname{nnz}(A) n^p` of :data:`PEAK` (a pair not measured takes
    SuperLU's figures for the kind)."""
    which = "complex-symmetric" if complex_factor else matrix
    b0, c, p = PEAK.get((kind, which)) or PEAK[("superlu", which)]
    n = float(max(A.shape[0], 1))
    return b0 + c * float(sp.csr_array(A).nnz) * n ** p


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
