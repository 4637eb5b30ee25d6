r"""The production path of the sparse modes: the numbers from the null-space form, the
Lagrange and generalized-inverse forms as residual checks.

Whatever formulation a case names, on the sparse path the modes come from

.. math::  u = T p, \quad A T = 0: \qquad (T^T K T)\, p = \omega^2 (T^T M T)\, p

(master-slave elimination, :func:`substruct.analysis.modes.sparse.null_space_modes`; with
damping, the first-order pencil of :math:`T^T M T`, :math:`T^T C T`, :math:`T^T K T` by
:func:`substruct.analysis.modes.damped.damped_sparse_modes`, one real LU of twice the reduced
size, where the KKT pencil would need one of ``2n + m``), with the
fastest factorization installed (:func:`substruct.linalg.backends.auto_factorizer`: PARDISO,
CHOLMOD, SuperLU after METIS, SuperLU, with fallback): one symmetric positive definite factorization of the reduced size, where the
sparse generalized-inverse and KKT eigensolves need two indefinite saddle-point factorizations
of ``n + m`` (100k coordinates: 48 s and 1.6 GB against 151 s and 4.7 GB).

The other formulations verify the modes found (:mod:`substruct.analysis.modes.checks`): the
KKT residual always (products and an ``m x m`` solve), the generalized-inverse residual of
eqs 5/10 where :math:`M_d^{-1} A^T` is cheap.  The figures are relative residuals, held to the
tolerance like the eigenvalue differences of the dense checks; the full sparse eigensolves of
the other formulations stay available in :func:`~substruct.analysis.modes.sparse.sparse_coupled_modes`.

Before factorizing, the memory the factorization will need is estimated from its fill
(:func:`substruct.linalg.memory.factor_memory`) and compared with the memory the machine has
available: a model that fits runs, whatever its size.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from substruct.analysis.errors import require_analysis_memory
from substruct.analysis.modes.krylov import check_inputs, eliminate
from substruct.analysis.modes.checks import (
    generalized_inverse_affordable,
    generalized_inverse_residual,
    kkt_residual,
)
from substruct.analysis.results import Modes
from substruct.analysis.modes.damped import damped_sparse_modes
from substruct.analysis.modes.sparse import null_space_modes
from substruct.linalg.backends import BACKENDS, auto_backend
from substruct.linalg.definite import SingularPencil
from substruct.linalg.memory import factor_memory
from substruct.linalg.nullspace import Elimination
from substruct.vocabulary import NULL_SPACE

__all__ = ["KKT_CHECK", "GI_CHECK", "MAIN_METHOD", "production_modes", "sparse_memory"]

#: The formulation that computes the modes on the sparse path.
MAIN_METHOD = NULL_SPACE
#: The names of the residual checks in ``Modes.agreement``.
KKT_CHECK = "kkt-residual"
GI_CHECK = "generalized-inverse-residual"


def sparse_memory(K: sp.sparray, count: int, kind: str) -> float:
    r"""Estimated peak bytes of the null-space eigensolve of an ``n``-coordinate model: the
    factorization (:func:`substruct.linalg.memory.factor_memory`), the reduced and full
    matrices (six copies of ``nnz(K)`` entries at 12 bytes) and the Lanczos basis
    (:math:`3 n \max(2k + 1, 20)` doubles)."""
    n = K.shape[0]
    nnz = sp.csr_array(K).nnz
    return factor_memory(K, kind) + 72.0 * nnz + 24.0 * n * max(2 * count + 1, 20)


def production_modes(M: sp.sparray, K: sp.sparray, A: sp.sparray | None, count: int, *,
                     C: sp.sparray | None = None, elimination: Elimination | None = None
                     ) -> tuple[Modes, dict[str, float], str]:
    r"""The lowest ``count`` modes by the null-space form, with the residual checks.

    ``C`` ``None`` (undamped): :math:`T^T K T p = \omega^2 T^T M T p` by shift-invert Lanczos;
    otherwise the damped roots of the null-space first-order pencil (eqs 23-34 in ``p``).

    Returns:
        ``(modes, agreement, note)``: the modes (``method`` ``"null-space/sparse"``), the
        figures of :data:`KKT_CHECK` and :data:`GI_CHECK` (the latter when affordable,
        :func:`~substruct.analysis.modes.checks.generalized_inverse_affordable`) and a note
        saying which check was skipped and why (empty if none).

    Raises:
        AnalysisInputError: the factorization would not fit the memory available; what
            :func:`~substruct.analysis.modes.sparse.null_space_modes` refuses.
    """
    Ms, Ks, As, k = check_inputs(M, K, A, count)
    el = elimination or eliminate(Ms, As)
    if C is None:
        kind = auto_backend("spd")
        require_analysis_memory(sparse_memory(Ks, k, kind),
                                f"the sparse eigensolve of {Ks.shape[0]} coordinates "
                                f"({BACKENDS[kind].label})")
        main = null_space_modes(Ms, Ks, As, k, factorization="auto", elimination=el)
        roots, Cs = 1j * main.omega, None
    else:
        Cs = sp.csr_array(C, dtype=float)
        main = damped_sparse_modes(Ms, Cs, Ks, As, k, formulation=NULL_SPACE, elimination=el)
        roots = main.eigenvalues
    main.method = f"{MAIN_METHOD}/sparse"
    U = main.shapes
    Ak = sp.csr_array(As[el.kept_rows])
    agreement = {KKT_CHECK: kkt_residual(Ks, Ms, Ak, roots, U, Cs)}
    note = ""
    if generalized_inverse_affordable(Ms, Ak.shape[0]):
        try:
            agreement[GI_CHECK] = generalized_inverse_residual(Ks, Ms, Ak, roots, U, Cs)
        except (SingularPencil, RuntimeError, np.linalg.LinAlgError):   # M_d singular
            note = ("generalized-inverse check skipped: the mass is singular on coordinates "
                    "that have mass (a combination of them carries none), where eqs 5 and 10 "
                    "do not exist")
    else:
        note = (f"generalized-inverse check skipped: {Ak.shape[0]} constraint rows on a "
                f"consistent mass of {Ks.shape[0]} coordinates")
    return main, agreement, note
