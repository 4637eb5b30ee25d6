r"""Recovered receptances of superelements in cases with FRF substructures (``type: frf``).

Such a case is coupled by LM-FBS (:func:`substruct.run.frf_route.coupled_frf_result`): the
finite-element part, which holds the superelements, enters as its receptances at the points
the coupling needs, :math:`P`.  A recovery row :math:`r` (a row :math:`R_s S` of
:func:`substruct.run.recovery.recovery_rows`, on the finite-element coordinates) is one more
output of that part: with its receptances to the points, :math:`Y[r, P] = r\,H_{FE}\,E_P`,
the coupled receptance of eq (15) with ``A = B``, restricted to the rows asked for
(:func:`substruct.analysis.frf.coupling_selected.couple_selected`), is

.. math::  Y_c[r, i] = Y[r, i] - Y[r, I] B_I^T (B_I Y[I, I] B_I^T)^{-1} B_I Y[I, i]

(:math:`I` the interface coordinates, :math:`i` the inputs): the finite-element part's
response at the row to the input and to the interface forces.  Only the columns :math:`P` of
the rows are read, so the part is given to the coupling with the recovery rows' own columns
zero (never read: they are no interface coordinate and no input).

Decoupling (``decouple: true``) is not taken: ``None`` (no recovered receptances).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from substruct.analysis.errors import AnalysisInputError
from substruct.analysis.frf.coupling_selected import couple_selected
from substruct.builder.frf_part import FrfPart
from substruct.builder.frf_parts import MODEL_PART, split_frf_case
from substruct.builder.model import Model
from substruct.case.loader import Case
from substruct.case.fields import parse_point
from substruct.run.analyses import rows_receptance

__all__ = ["frf_parts_rows_receptance", "ROW_LABEL"]

#: The finite-element part's label of recovery row ``j`` in the coupling (no point name has a
#: blank).
ROW_LABEL = "recovery row {}"


def frf_parts_rows_receptance(case: Case, model: Model, rows: sp.csr_array
                              ) -> tuple[np.ndarray, np.ndarray] | None:
    r"""The coupled receptances of the output rows ``rows`` (``m x n``, on the coordinates of
    the finite-element part ``model``) to the inputs of ``analysis.frf``, in a case with FRF
    substructures (module docstring).

    Returns:
        ``(omega, H)``, ``H`` of ``n_omega x m x n_inputs`` (complex); ``None`` for a case
        that decouples a part, or without finite-element part.

    Raises:
        CaseError: at ``analysis.frf`` for input the solver cannot take, at ``connections``
            for a singular interface receptance.
    """
    spec = case.analysis.frf
    if spec is None:
        raise TypeError(f"case {case.name!r} asks for no receptances")
    split = split_frf_case(case)
    if split.model_case is None or any(p.decouple for p in split.parts):
        return None
    fe = split.model_case.analysis.frf
    assert fe is not None
    asm = model.assembly
    points = list(split.model_points)
    m = rows.shape[0]
    P = asm.rows([model.points[p] for p in points])
    outputs = sp.csr_array(sp.vstack([P, sp.csr_array(rows)]))
    w = np.asarray(fe.omegas(), dtype=float)
    with np.errstate(over="ignore", invalid="ignore"):
        H = rows_receptance(split.model_case, model, outputs, w)  # (p + m) x p: P's columns
    Y = np.zeros((len(w), len(points) + m, len(points) + m), dtype=complex)
    Y[:, :, :len(points)] = H
    labels = points + [ROW_LABEL.format(j) for j in range(m)]
    first = FrfPart(MODEL_PART, w, labels, Y)
    frf_names = {p.name for p in split.parts}

    def stacked(point: str) -> str:
        return point if parse_point(point)[0] in frf_names else f"{MODEL_PART}@{point}"

    pairs = [(stacked(a), stacked(b)) for a, b in split.pairs]
    try:
        got = couple_selected([first, *split.parts], pairs,
                              [f"{MODEL_PART}@{ROW_LABEL.format(j)}" for j in range(m)],
                              [stacked(p) for p in spec.inputs])
    except AnalysisInputError:
        raise case.error(("connections",), "the interface receptance B Y B^T is singular: "
                         "connections that repeat each other, or receptances of zero at the "
                         "interface", [list(p) for p in split.pairs]) from None
    assert got.H is not None
    return got.omega, got.H
