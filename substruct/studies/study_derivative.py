r"""The derivative of each collected natural frequency with respect to the study's parameter,
in one sample (``collect: derivatives``).

The assembled matrices are differentiated by central differences,
:math:`X' \approx (X(p + h) - X(p - h)) / 2h` with :math:`h = 10^{-5} \max(|p|, 1)` (exact
for matrices linear in ``p``, as stiffnesses, masses and dampings written as parameters are; the
rounding error is about :math:`\epsilon |X| / h`), and the roots by
:func:`substruct.analysis.modes.sensitivity.root_derivatives`:

.. math::  \frac{ds}{dp} = -\frac{\phi^T (s^2 M' + s C' + K')\, \phi}
                               {\phi^T (2 s M + C)\, \phi}, \qquad
           \frac{d\omega}{dp} = \frac{\mathrm{Re}(\bar s\, ds/dp)}{|s|}

(undamped: :math:`d\lambda/dp = \phi^T (K' - \lambda M')\, \phi`, :math:`\phi^T M \phi = 1`).
The formula needs the constraints independent of ``p``: a parameter that changes ``A`` or the
number of coordinates is refused (the sample fails with that message).
"""

from __future__ import annotations

from typing import Mapping

import numpy as np
import scipy.sparse as sp

from substruct.analysis.modes.sensitivity import frequency_derivatives, root_derivatives
from substruct.analysis.results import Modes
from substruct.builder import Substructure
from substruct.case.loader import parse_case
from substruct.run.runner import build_model
from substruct.studies.study_plan import overrides_of

__all__ = ["STEP", "frequency_derivative"]

#: The relative step of the central differences of the matrices.
STEP = 1e-5


def _matrices(text: str, source: str, base_dir: str, overrides: list[str],
              shared: Mapping[str, Substructure] | None) -> tuple:
    case = parse_case(text, source, base_dir, overrides)
    asm = build_model(case, prebuilt=shared).assembly
    dense = (lambda X: None if X is None else sp.csr_array(X))
    return dense(asm.M), dense(asm.C), dense(asm.K), dense(asm.A)


def _largest(X: sp.csr_array) -> float:
    """The largest magnitude of a sparse matrix's stored entries (0 if none)."""
    data = sp.csr_array(X).data
    return float(np.abs(data).max()) if data.size else 0.0


def frequency_derivative(modes: Modes, n: int, text: str, source: str, base_dir: str,
                         overrides: list[str], name: str, value: float,
                         shared: Mapping[str, Substructure] | None = None) -> np.ndarray:
    r""":math:`d\omega_j/dp` of the first ``n`` modes (NaN-padded) of the sample whose
    overrides are ``overrides``, ``p`` the parameter ``name`` at ``value`` (module docstring).

    Raises:
        ValueError: the parameter changes the constraints or the number of coordinates.
    """
    h = STEP * max(abs(value), 1.0)
    lo = _matrices(text, source, base_dir, [*overrides, *overrides_of([name],
                                                                       np.array([value - h]))],
                   shared)
    hi = _matrices(text, source, base_dir, [*overrides, *overrides_of([name],
                                                                       np.array([value + h]))],
                   shared)
    if lo[2].shape != hi[2].shape:
        raise ValueError(f"collect.derivatives: {name} changes the number of coordinates")
    if lo[3] is not None and hi[3] is not None and (
            lo[3].shape != hi[3].shape or _largest(lo[3] - hi[3])
            > 1e-12 * _largest(hi[3])):
        raise ValueError(f"collect.derivatives: {name} changes the constraints (the "
                         f"derivative formula needs them fixed)")
    mid = _matrices(text, source, base_dir, overrides, shared)
    diff = [None if a is None or b is None else (b - a) / (2 * h)
            for a, b in zip(lo[:3], hi[:3])]
    k = min(n, modes.eigenvalues.size)
    s = modes.eigenvalues[:k]
    ds = root_derivatives(s, modes.shapes[:, :k], mid[0], mid[1], *diff)
    out = np.full(n, np.nan)
    out[:k] = frequency_derivatives(s, ds)
    return out
