r"""System equivalent model mixing (SEMM; Klaassen, van der Seijs and de Klerk, "System
equivalent model mixing", Mech. Syst. Signal Process. 105 (2018) 90-112): a numerical model
``N`` known at many coordinates (a finite-element receptance) mixed with an experimental model
``E`` measured at a few, the boundary ``b``, into one model ``S`` that has the coordinates of
``N`` and the dynamics of ``E``.

Derivation.  Three models are joined by LM-FBS at the boundary coordinates: the numerical
*overlay* model ``N`` (all coordinates), the experimental model ``E`` (its boundary block
:math:`Y^E_{bb}`) coupled to it, and the numerical *removed* model ``R``, the overlay's own
boundary block :math:`Y^R_{bb} = Y^N_{bb}`, decoupled (entered with a minus sign).  Eliminating
the Lagrange multipliers and the interface coordinates of ``E`` and ``R`` (the paper's
eqs 9-13) leaves the single-line form

.. math::

    Y^S = Y^N - Y^N_{:b}\,(Y^N_{bb})^{+}\,\bigl(Y^N_{bb} - Y^E_{bb}\bigr)\,
          (Y^N_{bb})^{+}\,Y^N_{b:} ,

here for rectangular boundaries too: the boundary outputs :math:`b_o` (rows, sensors) and
inputs :math:`b_i` (columns, impacts) may differ, :math:`Y^N_{bb} = Y^N_{b_o b_i}` and
:math:`(\cdot)^{+}` is the (optionally regularised) pseudo-inverse.  Properties:

* :math:`Y^E_{bb} = Y^N_{bb}` gives :math:`Y^S = Y^N` exactly (the bracket is zero);
* with :math:`Y^N_{bb}` square and invertible, :math:`Y^S_{bb} = Y^E_{bb}`: the mixed model
  reproduces the measurement at the boundary;
* the mix is linear in the measurement: a perturbation :math:`\Delta E` of :math:`Y^E_{bb}`
  moves :math:`Y^S` by :math:`Y^N_{:b} (Y^N_{bb})^+ \Delta E (Y^N_{bb})^+ Y^N_{b:}`, so
  :math:`\lVert \Delta Y^S \rVert_F \le \lVert Y^N_{:b}(Y^N_{bb})^+\rVert_2
  \lVert \Delta E \rVert_F \lVert (Y^N_{bb})^+ Y^N_{b:}\rVert_2` (:func:`noise_gain`).

Extended form (the paper's section 3.3).  The removed model is the numerical model at *all*
its coordinates, not only its boundary block, so that the numerical dynamics are taken out
everywhere before the measured ones are put in; the interface is still the boundary.  The
single-line form becomes

.. math::

    Y^S = Y^N - Y^N\,(Y^N_{b:})^{+}\,\bigl(Y^N_{bb} - Y^E_{bb}\bigr)\,(Y^N_{:b})^{+}\,Y^N ,

with :math:`Y^N_{b:}` the boundary rows (every numerical input) and :math:`Y^N_{:b}` the
boundary columns (every numerical output).  Again :math:`Y^E_{bb} = Y^N_{bb}` gives
:math:`Y^N`; and :math:`Y^S_{bb} = Y^N_{b:} (Y^N_{b:})^+ (\dots) (Y^N_{:b})^+ Y^N_{:b}` takes
the measurement at the boundary whenever :math:`Y^N_{b:}` has full row rank and
:math:`Y^N_{:b}` full column rank (no square boundary block needed), so the boundary may be
every measured channel, however many.

Channel coherence (the SEMM coherence criterion).  Each measured output ``j`` in turn is left
out of the boundary and predicted by the mix of the others; the coherence of its predicted
row with its measured row, averaged over the measured inputs, says per frequency whether the
channel agrees with the rest of the measurement and the model (:func:`channel_coherence`; a
mislabelled or flipped sensor stands out).

Quality indicator.  Measured entries that are not on the boundary (validation entries: a
sensor row or an impact column left out of ``b``) are predicted by the mix, not imposed; their
coherence with the measurement, per entry and frequency,

.. math::  \gamma = \frac{\lvert Y^S + Y^E \rvert^2}{2\,(\lvert Y^S\rvert^2 + \lvert Y^E\rvert^2)},

is 1 where they agree and 0 where they are opposite (the specific consistency of
:mod:`~substruct.analysis.frf.virtual_point`); its mean over the validation entries is the
indicator per frequency.

Arrays are ``(n_omega, rows, cols)``; coordinates are named by labels.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from substruct.analysis.frf.vp_coupling import Regularisation, regularised_inverse

__all__ = ["SemmResult", "semm", "coherence", "noise_gain", "channel_coherence"]


@dataclass(frozen=True)
class SemmResult:
    """A mixed model.

    Attributes:
        Y: ``(k, n_o, n_i)`` the mixed receptance :math:`Y^S` at the numerical model's
            coordinates.
        coherence: ``(k, m_o, m_i)`` :math:`\\gamma` of :math:`Y^S` and :math:`Y^E` at every
            measured entry.
        validation: ``(m_o, m_i)`` bool: the measured entries not on the boundary.
        indicator: ``(k,)`` the mean coherence over the validation entries (``nan`` when every
            measured entry is on the boundary: nothing is left to validate with).
    """

    Y: np.ndarray
    coherence: np.ndarray
    validation: np.ndarray
    indicator: np.ndarray


def coherence(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``|a + b|^2 / (2 (|a|^2 + |b|^2))`` elementwise (1 where both are 0)."""
    num = np.abs(a + b) ** 2
    den = 2 * (np.abs(a) ** 2 + np.abs(b) ** 2)
    out = np.ones(num.shape)
    np.divide(num, den, out=out, where=den > 0)
    return out


def _index(labels: Sequence[str], wanted: Sequence[str], what: str,
           model: str = "numerical model") -> list[int]:
    where = {lab: i for i, lab in enumerate(labels)}
    if len(where) != len(labels):
        raise ValueError(f"SEMM: the labels of the {model} repeat a name")
    missing = [w for w in wanted if w not in where]
    if missing:
        raise ValueError(f"SEMM: {what} {missing[0]!r} is not a coordinate of the {model}")
    return [where[w] for w in wanted]


def _finite(name: str, Y: np.ndarray) -> None:
    bad = ~np.isfinite(Y)
    if bad.any():
        at = [int(v) for v in np.argwhere(bad)[0]]
        raise ValueError(f"SEMM: the {name} receptance is not finite at index {at}")


def semm(Y_num: np.ndarray, num_out: Sequence[str], num_in: Sequence[str],
         Y_exp: np.ndarray, exp_out: Sequence[str], exp_in: Sequence[str],
         boundary_out: Sequence[str] | None = None, boundary_in: Sequence[str] | None = None,
         reg: Regularisation = Regularisation(), form: str = "standard") -> SemmResult:
    r"""Mix the numerical receptance ``Y_num`` (rows ``num_out``, columns ``num_in``) with the
    experimental ``Y_exp`` (rows ``exp_out``, columns ``exp_in``, a subset of the numerical
    coordinates) at the boundary (default: every measured row and column), by the single-line
    form of the module docstring, and the coherence indicator at the validation entries.

    ``reg`` chooses the pseudo-inverse of :math:`Y^N_{bb}` (default: singular values below
    ``1e-12`` of the largest dropped).  ``form="extended"`` uses the extended single-line
    form (module docstring): the pseudo-inverses of the boundary rows and columns of the
    whole numerical model instead of its boundary block.

    Raises:
        ValueError: shapes that do not match the labels, a measured or boundary coordinate
            that the numerical model lacks, a boundary coordinate that is not measured, more
            boundary coordinates than the numerical model has, values that are not finite, a
            form that is neither ``standard`` nor ``extended``.
    """
    if form not in ("standard", "extended"):
        raise ValueError(f"SEMM: the form is standard or extended, got {form!r}")
    Y_num, Y_exp = np.asarray(Y_num), np.asarray(Y_exp)
    if Y_num.ndim != 3 or Y_num.shape[1:] != (len(num_out), len(num_in)):
        raise ValueError(f"SEMM: the numerical receptance has shape {list(Y_num.shape)}, "
                         f"expected (frequencies, {len(num_out)}, {len(num_in)})")
    if Y_exp.ndim != 3 or Y_exp.shape != (len(Y_num), len(exp_out), len(exp_in)):
        raise ValueError(f"SEMM: the experimental receptance has shape {list(Y_exp.shape)}, "
                         f"expected ({len(Y_num)}, {len(exp_out)}, {len(exp_in)})")
    _finite("numerical", Y_num)
    _finite("experimental", Y_exp)
    bo = list(exp_out) if boundary_out is None else list(boundary_out)
    bi = list(exp_in) if boundary_in is None else list(boundary_in)
    if not bo or not bi:
        raise ValueError("SEMM: the boundary needs at least one output and one input")
    eo = _index(exp_out, bo, "boundary output", "measurement")
    ei = _index(exp_in, bi, "boundary input", "measurement")
    no, ni = _index(num_out, bo, "boundary output"), _index(num_in, bi, "boundary input")
    mo = _index(num_out, exp_out, "measured output")
    mi = _index(num_in, exp_in, "measured input")
    R = Y_num[:, no][:, :, ni]                          # removed model Y^N_bb
    E = Y_exp[:, eo][:, :, ei]
    if form == "extended":
        left = Y_num @ regularised_inverse(Y_num[:, no, :], reg)     # Y^N (Y^N_{b:})^+
        right = regularised_inverse(Y_num[:, :, ni], reg) @ Y_num    # (Y^N_{:b})^+ Y^N
    else:
        P = regularised_inverse(R, reg)                     # (k, |b_i|, |b_o|)
        left = Y_num[:, :, ni] @ P                          # Y^N_{:b} (Y^N_bb)^+
        right = P @ Y_num[:, no, :]                         # (Y^N_bb)^+ Y^N_{b:}
    Y_s = Y_num - left @ ((R - E) @ right)
    gamma = coherence(Y_s[:, mo][:, :, mi], Y_exp)
    valid = ~(np.isin(np.asarray(exp_out), bo)[:, None]
              & np.isin(np.asarray(exp_in), bi)[None, :])
    ind = gamma[:, valid].mean(axis=1) if valid.any() else np.full(len(Y_num), np.nan)
    return SemmResult(Y_s, gamma, valid, ind)


def noise_gain(Y_num: np.ndarray, num_out: Sequence[str], num_in: Sequence[str],
               boundary_out: Sequence[str], boundary_in: Sequence[str],
               reg: Regularisation = Regularisation()) -> np.ndarray:
    r"""Per frequency, :math:`g = \lVert Y^N_{:b}(Y^N_{bb})^+\rVert_2\,
    \lVert (Y^N_{bb})^+ Y^N_{b:}\rVert_2`: a perturbation :math:`\Delta E` of the measured
    boundary block moves the mixed model by at most :math:`g \lVert \Delta E \rVert_F`
    (Frobenius norms; module docstring)."""
    no, ni = _index(num_out, boundary_out, "boundary output"), \
        _index(num_in, boundary_in, "boundary input")
    P = regularised_inverse(Y_num[:, no][:, :, ni], reg)
    left = np.linalg.norm(Y_num[:, :, ni] @ P, ord=2, axis=(1, 2))
    right = np.linalg.norm(P @ Y_num[:, no, :], ord=2, axis=(1, 2))
    return np.asarray(left * right)


def channel_coherence(Y_num: np.ndarray, num_out: Sequence[str], num_in: Sequence[str],
                      Y_exp: np.ndarray, exp_out: Sequence[str], exp_in: Sequence[str],
                      reg: Regularisation = Regularisation(), form: str = "extended"
                      ) -> np.ndarray:
    r"""The SEMM coherence criterion per measured output (module docstring): ``(k, m_o)``,
    column ``j`` the mean over the measured inputs of :math:`\gamma` between the row of
    output ``j`` predicted by the mix with ``j`` left out of the boundary (every other
    measured output and every measured input on it) and the measured row.

    Raises:
        ValueError: fewer than two measured outputs; as :func:`semm`.
    """
    outs = list(exp_out)
    if len(outs) < 2:
        raise ValueError("SEMM channel coherence needs at least two measured outputs")
    Y_exp = np.asarray(Y_exp)
    out = np.empty((len(Y_exp), len(outs)))
    for j, name in enumerate(outs):
        others = outs[:j] + outs[j + 1:]
        res = semm(Y_num, num_out, num_in, Y_exp, outs, exp_in, others, list(exp_in), reg,
                   form)
        out[:, j] = res.coherence[:, j, :].mean(axis=1)
    return out
