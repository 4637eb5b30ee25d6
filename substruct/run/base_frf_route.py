r"""The case door of the base-driven frequency response (``analysis.base_frf``): the grounded
supports of each base input give a column of ``E`` in the nonhomogeneous constraint
:math:`A q = E g` (:func:`~substruct.run.spec_route.base_columns`, as ``analysis.random``'s
bases), :func:`~substruct.analysis.frf.base_drive.base_drive_sweep` gives the output
displacement per base acceleration :math:`H = \hat u / \hat a` (by the paper's ``R`` with
:math:`F = A^T E`, checked against the relative-coordinates form at every frequency), and
:math:`T = (i \omega)^p H` the output's displacement, velocity or acceleration (``p = 0, 1,
2``) per base acceleration; for acceleration the transmissibility proper, which for a mass on
a spring and dashpot is :math:`(1 + 2 i \zeta r) / (1 - r^2 + 2 i \zeta r)`.

Input the sweep cannot take becomes a :class:`~substruct.case.loader.CaseError` naming the
field (exit 2); a check beyond the tolerance stays a
:class:`~substruct.analysis.errors.CheckError` (exit 1).
"""

from __future__ import annotations

import numpy as np

from substruct.analysis.api import SweepOptions
from substruct.analysis.errors import INPUT_ERRORS, CheckError
from substruct.analysis.frf.base_drive import base_drive_sweep
from substruct.builder.model import Model
from substruct.case.loader import Case
from substruct.run.spec_results import BaseFrf
from substruct.run.spec_route import base_columns, loss_parts, sweep_kw
from substruct.vocabulary import DERIVATIVE_ORDER

__all__ = ["base_frf_result"]


def base_frf_result(case: Case, model: Model) -> BaseFrf:
    """The transmissibilities of ``analysis.base_frf`` (module docstring).

    Raises:
        CaseError: a base point no constraint holds alone, a support moved by two inputs, an
            unknown substructure of ``loss_factor``, a mechanism with the supports held.
        CheckError: a check beyond ``analysis.base_frf.tolerance``.
    """
    spec = case.analysis.base_frf
    if spec is None:
        raise TypeError(f"case {case.name!r} asks for no base-driven frequency response")
    loc = ("analysis", "base_frf")
    asm = model.assembly
    w = spec.omegas()
    parts = loss_parts(case, model, spec.loss_factor, (*loc, "loss_factor")) \
        if spec.loss_factor is not None else []
    outputs = asm.rows([model.points[p] for p in spec.outputs])
    names = spec.input_names()
    E = base_columns(case, model, [b.at for b in spec.base_inputs()], loc,
                     spec.base is not None)
    try:
        rec = base_drive_sweep(asm.K, asm.M, asm.C, asm.A, w, E, outputs, per="acceleration",
                               loss=parts,
                               options=SweepOptions(**sweep_kw(spec, names, spec.outputs),
                                                    what="base frf"))
    except INPUT_ERRORS as err:
        raise case.error(loc, " ".join(str(err).split())) from None
    except CheckError as err:
        raise CheckError(f"{err}; to accept it, raise analysis.base_frf.tolerance") from None
    T = np.asarray(rec.H) * ((1j * w) ** DERIVATIVE_ORDER[spec.quantity])[:, None, None]
    return BaseFrf(omega=w, outputs=list(spec.outputs), inputs=names, quantity=spec.quantity,
                   T=T, method=rec.method, agreement=dict(rec.agreement),
                   tolerance=spec.tolerance)
