r"""The test-lab analyses of a case on the receptances it computed (``analysis.frf``, its
outputs ``x`` inputs ``H``; :mod:`substruct.case.testlab_analysis`):

* ``analysis.tpa``: blocked forces at the interface ``c`` from the operating responses, in
  situ :math:`f^{bl} = (H_{bc})^{+} u_b` (optionally regularised, the moments scaled by the
  regularization's ``length``) or by matrix inverse :math:`f^{bl} = H_{cc}^{-1} u_c`; the
  prediction :math:`\hat u_t = H_{tc} f^{bl}` against the measured responses at the targets,
  and the path contributions :math:`H_{tc_j} f^{bl}_j` (:mod:`substruct.analysis.frf.tpa`);
  with ``method: pseudo_forces`` the ``interface`` points are pseudo-force points ``p`` of the
  source, :math:`F_{ps} = (H_{bp})^{+} u_b` (:mod:`substruct.analysis.frf.tpa_operational`);
  with ``method: operational`` the transmissibility :math:`T = U_t U_i^{+}` from the
  operating responses at the indicators and the targets under every condition but the
  ``validation_condition``, its prediction :math:`\hat u_t = T u_i` of that condition and the
  contributions :math:`T_{:,k} u_{i,k}` of the indicator paths;
* ``analysis.semm``: ``H`` mixed with the measured receptance at the boundary
  (:mod:`substruct.analysis.frf.semm`), standard or extended form; with the extended form and
  two or more measured outputs, the channel coherence criterion too.
"""

from __future__ import annotations

import numpy as np

from substruct.analysis.frf.semm import channel_coherence, semm
from substruct.analysis.frf.tpa import (blocked_forces_in_situ, blocked_forces_matrix_inverse,
                                        on_board_validation, path_contributions)
from substruct.analysis.frf.tpa_operational import (operational_contributions, pseudo_forces,
                                                    transmissibility)
from substruct.analysis.frf.vp_coupling import Regularisation
from substruct.analysis.results import Receptance
from substruct.case.loader import Case
from substruct.run.testlab_results import SemmOutcome, TpaResult

__all__ = ["tpa_result", "semm_result"]

_ROTATIONS = ("rx", "ry", "rz")


def _block(H: Receptance, outs: list[str], ins: list[str]) -> np.ndarray:
    o = [H.outputs.index(p) for p in outs]
    i = [H.inputs.index(p) for p in ins]
    return H.H[:, o][:, :, i]


def tpa_result(case: Case, H: Receptance) -> TpaResult:
    """``analysis.tpa`` on the receptances ``H`` (module docstring).

    Raises:
        CaseError: an interface receptance that is singular (matrix inverse) or receptances
            that are not finite.
    """
    spec = case.analysis.tpa
    if spec is None:
        raise TypeError(f"case {case.name!r} asks for no transfer path analysis")
    if spec.method == "operational":
        return _operational(case)
    c, b, t = list(spec.interface), spec.measured_points(), list(spec.targets)
    u_b = spec.responses_at(b)
    how: str = spec.method
    try:
        if spec.method == "matrix_inverse":
            f = blocked_forces_matrix_inverse(_block(H, c, c), u_b)
        else:
            r = spec.regularization
            reg, scale = Regularisation(), None
            if r is not None:
                reg = Regularisation(r.method, rtol=1e-12 if r.rtol is None else r.rtol,
                                     rank=r.rank, alpha=0.0 if r.alpha is None else r.alpha)
                scale = np.array([r.length if p.rsplit(":", 1)[-1] in _ROTATIONS else 1.0
                                  for p in c])
                how += f" ({r.method})"
            solve = pseudo_forces if spec.method == "pseudo_forces" else blocked_forces_in_situ
            f = solve(_block(H, b, c), u_b, reg, scale)
        Y_tc = _block(H, t, c)
        val = on_board_validation(Y_tc, f, spec.responses_at(t))
        paths = path_contributions(Y_tc, f)
    except ValueError as err:
        raise case.error(("analysis", "tpa"), str(err), spec.method) from None
    return TpaResult(how, c, b, t, f, paths, val.predicted, val.measured, val.error)


def _operational(case: Case) -> TpaResult:
    """``analysis.tpa`` with ``method: operational`` (module docstring)."""
    spec = case.analysis.tpa
    assert spec is not None and spec.validation_condition is not None
    i, t, k = list(spec.indicators), list(spec.targets), spec.validation_condition
    U_i, U_t = spec.responses_at(i), spec.responses_at(t)
    train = [j for j in range(U_i.shape[2]) if j != k]
    try:
        T = transmissibility(U_i[:, :, train], U_t[:, :, train])
        u_i = U_i[:, :, k]
        val = on_board_validation(T, u_i, U_t[:, :, k])
        paths = operational_contributions(T, u_i)
    except ValueError as err:
        raise case.error(("analysis", "tpa"), str(err), spec.method) from None
    return TpaResult("operational", i, i, t, u_i, paths, val.predicted, val.measured,
                     val.error, T, k)


def semm_result(case: Case, H: Receptance) -> SemmOutcome:
    """``analysis.semm`` on the receptances ``H`` (module docstring).

    Raises:
        CaseError: a boundary block of the numerical model that is not finite, shapes that do
            not match.
    """
    spec = case.analysis.semm
    if spec is None:
        raise TypeError(f"case {case.name!r} asks for no model mixing")
    _, outs, ins, E = spec.data()
    bo = outs if spec.boundary is None else list(spec.boundary.outputs)
    bi = ins if spec.boundary is None else list(spec.boundary.inputs)
    try:
        res = semm(H.H, H.outputs, H.inputs, E, outs, ins, bo, bi, form=spec.form)
        chan = channel_coherence(H.H, H.outputs, H.inputs, E, outs, ins) \
            if spec.form == "extended" and len(outs) > 1 else None
    except ValueError as err:
        raise case.error(("analysis", "semm"), str(err), spec.measured) from None
    return SemmOutcome(list(H.outputs), list(H.inputs), res.Y, list(outs), list(ins),
                       list(bo), list(bi), res.coherence, res.validation, res.indicator,
                       spec.form, chan)
