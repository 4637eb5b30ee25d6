"""The reference of the base-drive tests: the transmissibility of a case's base tables by a
dense KKT solve per frequency, independent of substruct's sweep and formulations."""

from __future__ import annotations

import numpy as np

from substruct.run.runner import build_model


def dense_transmissibility(case, spec, f: np.ndarray) -> np.ndarray:
    """``T`` ``(n_f, outputs, bases)``, the outputs' acceleration per base acceleration of each
    of ``spec.bases`` (``analysis.random`` or ``analysis.base_frf`` of ``case``) at the
    frequencies ``f`` (Hz): ``[Z A^T; A 0] [q; l] = [0; E]`` with ``Z = K + i w C - w^2 M`` and
    each table's own constraint row moved by 1 (the output acceleration per table
    acceleration is the output displacement per table displacement)."""
    model = build_model(case)
    asm = model.assembly
    K, M, C, A = (x.toarray() for x in (asm.K, asm.M, asm.C, asm.A))
    n, m = K.shape[0], A.shape[0]
    E = np.zeros((m, len(spec.bases)))
    for j, b in enumerate(spec.bases):
        col = int(np.flatnonzero(asm.row(model.points[b.at[0]]).toarray().ravel())[0])
        for k in range(m):
            if np.flatnonzero(A[k]).tolist() == [col]:
                E[k, j] = A[k, col]
    assert np.count_nonzero(E) == len(spec.bases)  # each table moves its own row
    O = asm.rows([model.points[p] for p in spec.outputs]).toarray()
    T = np.empty((len(f), O.shape[0], E.shape[1]), dtype=complex)
    for k, w in enumerate(2 * np.pi * np.asarray(f)):
        kkt = np.block([[K + 1j * w * C - w ** 2 * M, A.T], [A, np.zeros((m, m))]])
        T[k] = O @ np.linalg.solve(kkt, np.vstack([np.zeros((n, E.shape[1])), E]))[:n]
    return T
