r"""The analyses of a case on its model: coupled modes (eqs 28-34) with the main formulation
and the checks, the receptances (eqs 11-15) at the requested inputs and outputs:

.. math::  H[k, i, j] = o_i \, \hat H(\omega_k)\, e_j, \qquad e_j = r(p_j)^T, \; o_i = r(p_i)

(a unit force at point ``p_j`` is the generalized force ``r(p_j)^T``), with the constraint
residual :math:`\max |A \hat q - R E| / \max |H|` over all frequencies.
"""

from __future__ import annotations

from typing import Any, Callable, Sequence

import numpy as np
import scipy.sparse as sp

from substruct.analysis.coupling import receptance
from substruct.analysis.dense_modes import Modes, coupled_modes, modes_agreement
from substruct.assembly.stack import Assembly
from substruct.builder.model import Model
from substruct.case.fields import gigabytes
from substruct.case.loader import Case, FiniteElements
from substruct.linalg.constraints import ConstraintError
from substruct.run.result import FrfResult, ModelInfo, ModeResult

__all__ = ["Progress", "modes_result", "frf_result", "model_info", "check_dense_sizes",
           "check_dense_modes", "min_size", "modes_solver", "SPARSE_ABOVE"]

#: ``progress(done, total, label)``, called during frequency sweeps.
Progress = Callable[[int, int, str], None]

#: Largest number of stacked coordinates for the dense coupled eigenproblem.
DENSE_MODES_LIMIT = 2500
#: Largest number of coordinates for the dense null-space receptance check.
DENSE_FRF_LIMIT = 4000
#: Frequencies per receptance call in a sweep (progress is reported between calls).
CHUNK = 10

# ------------------------------------------------------------------ the modes solver


#: ``solver: auto`` takes the sparse path above this many coordinates, damped or not: the dense
#: state-space pencil (eqs 28-34) of a 605-coordinate free-free rod took 62 s on two busy
#: cores, the sparse path 1 s with the same frequencies to 1e-13.
SPARSE_ABOVE = 400


def modes_solver(case: Any, n: int) -> str:
    """``"dense"`` or ``"sparse"`` for the coupled modes of a model of ``n`` coordinates.

    ``analysis.modes.solver``: ``dense`` always dense; ``sparse`` always sparse; ``auto``
    dense up to :data:`SPARSE_ABOVE` coordinates and sparse above it, damped or not (damped
    models by :func:`substruct.analysis.sparse_damped.damped_sparse_modes`).
    """
    spec = case.analysis.modes
    solver = getattr(spec, "solver", "auto")
    if solver == "dense" or (solver == "auto" and n <= SPARSE_ABOVE):
        return "dense"
    return "sparse"


def sparse_mode_result(case: Any, asm: Assembly, A: sp.csr_array, loc: tuple) -> ModeResult:
    """Coupled modes by the sparse path, with the main formulation and the checks of
    ``analysis.modes``, as the dense path fills a :class:`ModeResult` (complex shapes;
    undamped: eigenvalues ``i omega``, damping ratios 0; damped: complex roots, one of each
    conjugate pair, over-damped real roots one entry each, as the dense path reports them; no
    spurious root is ever computed).  Damped models: ``null-space`` and
    ``generalized-inverse`` are both the null-space pencil of
    :func:`substruct.analysis.sparse_damped.damped_sparse_modes` (so neither is reported as a check of
    the other), ``kkt`` its Lagrange pencil."""
    from substruct.analysis.dense_modes import modes_agreement
    from substruct.analysis.sparse_modes import has_damping, sparse_coupled_modes

    spec = case.analysis.modes
    checks = [m for k, m in enumerate(spec.check) if m != spec.method and m not in spec.check[:k]]
    if has_damping(asm.C):  # one pencil for both: no check of one by the other
        same = {"null-space", "generalized-inverse"}
        checks = [m for m in checks if not (m in same and spec.method in same)]

    def solve(method: str):
        return sparse_coupled_modes(asm.M, asm.K, A, spec.count, method=method, C=asm.C)

    try:
        main = solve(spec.method)
        agreement = {m: modes_agreement(solve(m), main) for m in checks}
    except (ValueError, RuntimeError) as err:
        text = " ".join(str(err).split()).replace("(use the dense coupled_modes)",
                                                   "(use solver: dense)")
        raise case.error(loc, f"sparse eigensolver: {text}") from None
    return ModeResult(method=main.method, eigenvalues=np.asarray(main.eigenvalues, complex),
                      omega=np.asarray(main.omega, float),
                      damping_ratio=np.asarray(main.damping_ratio, float),
                      shapes=np.asarray(main.shapes, dtype=complex),
                      residual=np.asarray(main.residual, float),
                      spurious=np.zeros(0, dtype=complex), spurious_reason=[],
                      agreement=agreement)

# --------------------------------------------------------------------------- analyses


def _mode_result(modes: Modes, agreement: dict[str, float]) -> ModeResult:
    return ModeResult(method=modes.method, eigenvalues=modes.eigenvalues, omega=modes.omega,
                      damping_ratio=modes.damping_ratio, shapes=modes.shapes,
                      residual=modes.residual, spurious=modes.spurious,
                      spurious_reason=list(modes.spurious_reason), agreement=agreement)


def _checks(main: str, check: Sequence[str]) -> list[str]:
    return [m for k, m in enumerate(check) if m != main and m not in check[:k]]


def modes_result(case: Case, asm: Assembly, A: sp.csr_array, loc: tuple) -> ModeResult:
    spec = case.analysis.modes
    if modes_solver(case, asm.n_dof) == "sparse":
        return sparse_mode_result(case, asm, A, loc)
    try:
        main = coupled_modes(asm.M, asm.C, asm.K, A, spec.method, spec.count)
        agreement = {m: modes_agreement(coupled_modes(asm.M, asm.C, asm.K, A, m, spec.count),
                                        main)
                     for m in _checks(spec.method, spec.check)}
    except ValueError as err:
        raise case.error(loc, str(err)) from None
    return _mode_result(main, agreement)


def min_size(case: Case) -> int:
    """A lower bound of the number of stacked coordinates, known before building."""
    total = 0
    for spec in case.substructures:
        n = spec.n_dof() if hasattr(spec, "n_dof") else None
        disc = getattr(spec, "discretization", None)
        if n is None and isinstance(disc, FiniteElements):
            n = max(disc.elements * disc.order - 1, 1)  # nodes less at most two supports
        total += n or 0
    return total


def check_dense_sizes(case: Case, N: int, at_least: bool = True) -> None:
    """Refuse dense eigenproblems (and dense receptance checks) too large for the memory."""
    size = f"at least {N}" if at_least else f"{N}"
    if case.analysis.modes is not None and N > DENSE_MODES_LIMIT and \
            modes_solver(case, N) == "dense":
        need = 8 * 8 * (2 * N) ** 2  # dense state-space pencil, eigenvectors, workspace
        raise case.error(("analysis", "modes"), f"the coupled eigenproblem is dense and the "
                         f"model has {size} coordinates (about {gigabytes(need)}); at most "
                         f"{DENSE_MODES_LIMIT}: reduce the large substructures "
                         f"(reduce: {{modes: ...}}), or solver: sparse", N)
    frf = case.analysis.frf
    if frf is not None and "null-space" in (frf.method, *frf.check) and N > DENSE_FRF_LIMIT:
        raise case.error(("analysis", "frf", "check"), f"the null-space receptance is dense: "
                         f"{size} coordinates need about {gigabytes(16 * N * N * 3)}; at most "
                         f"{DENSE_FRF_LIMIT}: use kkt", N)


def check_dense_modes(case: Case, asm: Assembly) -> None:
    check_dense_sizes(case, asm.n_dof, at_least=False)


def _sweep(asm: Assembly, omegas: np.ndarray, R, method: str, E, O,
           progress: Progress | None, label: str) -> np.ndarray:
    out = []
    total = len(omegas)
    for start in range(0, total, CHUNK):
        w = omegas[start:start + CHUNK]
        out.append(receptance(asm.K, asm.M, asm.C, asm.A, w, R, method=method, inputs=E,
                              outputs=O, labels=asm.constraint_labels))
        if progress is not None:
            progress(min(start + CHUNK, total), total, label)
    return np.concatenate(out, axis=0)


def frf_result(case: Case, model: Model, progress: Progress | None) -> FrfResult:
    spec = case.analysis.frf
    asm = model.assembly
    omegas = spec.omega.grid()
    E = sp.csc_array(asm.rows([model.points[p] for p in spec.inputs]).T)
    O_out = asm.rows([model.points[p] for p in spec.outputs])
    m = asm.A.shape[0]
    O = sp.csr_array(sp.vstack([O_out, asm.A])) if m else O_out
    R = asm.R if asm.R.nnz else None
    k_out = O_out.shape[0]
    try:
        full = _sweep(asm, omegas, R, spec.method, E, O, progress, spec.method)
        H = full[:, :k_out]
        scale = max(float(np.abs(H).max()), 1e-300)
        residual = 0.0
        if m:
            RE = (R @ E).toarray() if R is not None else np.zeros((m, E.shape[1]))
            residual = float(np.abs(full[:, k_out:] - RE[None]).max() / scale)
        agreement = {}
        for method in _checks(spec.method, spec.check):
            Hc = _sweep(asm, omegas, R, method, E, O_out, progress, method)
            agreement[method] = float(np.abs(Hc - H).max() / scale)
    except (ConstraintError, ValueError) as err:
        raise case.error(("analysis", "frf"), " ".join(str(err).split())) from None
    return FrfResult(method=spec.method, omega=omegas, H=H, inputs=list(spec.inputs),
                     outputs=list(spec.outputs), agreement=agreement,
                     constraint_residual=residual)


def model_info(model: Model) -> ModelInfo:
    asm = model.assembly
    return ModelInfo(dof_labels=list(asm.dof_labels),
                     substructure_names=[s.name for s in asm.substructures],
                     substructure_kinds=[s.kind for s in asm.substructures],
                     offsets=np.asarray(asm.offsets), A=sp.csr_array(asm.A), b=np.asarray(asm.b),
                     R=sp.csr_array(asm.R), constraint_labels=list(asm.constraint_labels),
                     drawings=model.drawings)

