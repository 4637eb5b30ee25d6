r"""The three formulations as objects: each owns its receptance, its dense modes and its check.

A :class:`Formulation` answers, for a :class:`~substruct.linalg.system.ConstrainedSystem`
``M q'' + C q' + K q = F``, ``A q = R F``:

* :meth:`~Formulation.receptance`: ``O q(omega_k)`` for the force patterns ``E``, one sweep
  (:mod:`substruct.analysis.formulations.receptance`);
* :meth:`~Formulation.dense_modes`: every root of the constrained free vibration, dense
  (:mod:`substruct.analysis.modes.dense`);
* :meth:`~Formulation.residual`: the figure by which a harmonic response ``q`` to ``F`` at
  ``omega`` is judged in this formulation's own terms.

=========================  ===============================  ======================================
object                     receptance, modes                residual
=========================  ===============================  ======================================
:data:`GENERALIZED_        eq 15 (bordered solve); the      the constraint,
INVERSE_FORM`              pencil of eqs 28-34              ``max |A q - R F| / max |q|``
:data:`NULL_SPACE_FORM`    ``q = N p + q_p``, ``A N = 0``   the reduced equation,
                                                            ``max |N^T (Z q - F)|``
:data:`KKT_FORM`           Lagrange multipliers (bordered)  the KKT system, multipliers fitted
=========================  ===============================  ======================================

(the residuals relative to ``|Z| |q| + |F|``; ``Z = K - omega^2 M + i omega C``, eq 13).  The
three share no code path between their computations, so that each checks the others.
:func:`formulation` is the registry the analyses dispatch through; a new formulation is a new
subclass added to :data:`REGISTRY` (and its name to :data:`substruct.vocabulary.FormulationName`).

Examples
--------
One unit mass on a unit spring and a second coordinate held by ``q_2 = 0``, at ``omega = 1/2``:

>>> import numpy as np
>>> from substruct.analysis.formulations.forms import formulation
>>> from substruct.linalg.system import ConstrainedSystem
>>> s = ConstrainedSystem.of(np.eye(2), None, np.eye(2), [[0.0, 1.0]])
>>> E = np.array([[1.0], [0.0]])
>>> for name in ("generalized-inverse", "null-space", "kkt"):
...     form = formulation(name)
...     q = form.receptance(s, np.array([0.5]), E, np.eye(2))[0]
...     print(form.name, np.round(q.real.ravel(), 6), form.residual(s, 0.5, q, E) < 1e-12)
generalized-inverse [1.333333 0.      ] True
null-space [1.333333 0.      ] True
kkt [1.333333 0.      ] True
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np
import scipy.sparse as sp

from substruct.analysis.formulations.receptance import (
    generalized_inverse_sweep,
    impedance,
    kkt_sweep,
    null_space_sweep,
)
from substruct.linalg.dense import dense
from substruct.linalg.nullspace import null_space_basis
from substruct.linalg.scaling import mass_column_scale
from substruct.linalg.system import ConstrainedSystem
from substruct.vocabulary import GENERALIZED_INVERSE, KKT, NULL_SPACE

if TYPE_CHECKING:
    from substruct.analysis.results import Modes

__all__ = [
    "Formulation",
    "GENERALIZED_INVERSE_FORM",
    "GeneralizedInverse",
    "KKT_FORM",
    "Kkt",
    "NULL_SPACE_FORM",
    "NullSpace",
    "REGISTRY",
    "formulation",
]


def _damping(system: ConstrainedSystem) -> sp.csr_array:
    return system.C if system.C is not None else sp.csr_array((system.n, system.n))


def _scale(Z: np.ndarray, q: np.ndarray, F: np.ndarray) -> float:
    """``max|Z| max|q| + max|F|``, at least 1e-300: the size of the terms of ``Z q = F``."""
    big = float(np.abs(Z).max(initial=0.0)) * float(np.abs(q).max(initial=0.0))
    return max(big + float(np.abs(F).max(initial=0.0)), 1e-300)


def _RF(system: ConstrainedSystem, F: np.ndarray) -> np.ndarray:
    return np.zeros((system.m, F.shape[1])) if system.R is None else system.R @ F


class Formulation:
    """A formulation of a constrained system (the base of the three; see the module).

    Attributes:
        name: its word in :data:`substruct.vocabulary.FORMULATIONS`.
    """

    name: ClassVar[str] = ""

    def receptance(self, system: ConstrainedSystem, omegas: np.ndarray, E: np.ndarray,
                   O: sp.sparray | np.ndarray) -> np.ndarray:
        """``out[k] = O q(omega_k)``, ``q = H(omega_k) E``: complex
        ``(n_omega, n_outputs, n_inputs)``.  The caller has checked that a force-tied ``R``
        is consistent (:func:`substruct.linalg.constraints.check_consistent`)."""
        raise NotImplementedError

    def dense_modes(self, M: np.ndarray, C: np.ndarray, K: np.ndarray,
                    A: np.ndarray) -> Modes:
        """Every physical root of ``M u'' + C u' + K u = 0`` under ``A u = 0`` (dense arrays,
        rows of ``A`` equilibrated), the spurious ones set aside."""
        raise NotImplementedError

    def residual(self, system: ConstrainedSystem, omega: float, q: np.ndarray,
                 F: np.ndarray) -> float:
        """This formulation's figure for a response ``q`` (``n x p``) to forces ``F``
        (``n x p``) at ``omega``: near rounding for its own solution."""
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"formulation({self.name!r})"


class GeneralizedInverse(Formulation):
    r"""The paper's formulation: eq 15 for receptances, the pencil of eqs 28-34 for modes;
    it owns the constraint residual :math:`\max |A q - R F| / \max |q|`."""

    name = GENERALIZED_INVERSE

    def receptance(self, system: ConstrainedSystem, omegas: np.ndarray, E: np.ndarray,
                   O: sp.sparray | np.ndarray) -> np.ndarray:
        return generalized_inverse_sweep(system.K, system.M, _damping(system), system.A,
                                         system.R, omegas, E, O)

    def dense_modes(self, M: np.ndarray, C: np.ndarray, K: np.ndarray,
                    A: np.ndarray) -> Modes:
        # imported here: the dense modes use the projection of this package (no import cycle)
        from substruct.analysis.modes.dense import dense_generalized_inverse_modes
        return dense_generalized_inverse_modes(M, C, K, A)

    def residual(self, system: ConstrainedSystem, omega: float, q: np.ndarray,
                 F: np.ndarray) -> float:
        if not system.m:
            return 0.0
        gap = np.abs(system.A @ q - _RF(system, F)).max(initial=0.0)
        return float(gap / max(float(np.abs(q).max(initial=0.0)), 1e-300))


class NullSpace(Formulation):
    r"""Null-space elimination ``q = N p + q_p``; it owns the reduced equation's residual
    :math:`\max |N^T (Z q - F)|`."""

    name = NULL_SPACE

    def receptance(self, system: ConstrainedSystem, omegas: np.ndarray, E: np.ndarray,
                   O: sp.sparray | np.ndarray) -> np.ndarray:
        return null_space_sweep(system.K, system.M, _damping(system), system.A, system.R,
                                omegas, E, O, system.independent)

    def dense_modes(self, M: np.ndarray, C: np.ndarray, K: np.ndarray,
                    A: np.ndarray) -> Modes:
        from substruct.analysis.modes.dense import dense_null_space_modes
        return dense_null_space_modes(M, C, K, A)

    def residual(self, system: ConstrainedSystem, omega: float, q: np.ndarray,
                 F: np.ndarray) -> float:
        N = null_space_basis(system.A, col_scale=mass_column_scale(system.M)) if system.m \
            else np.eye(system.n)
        Z = dense(impedance(system.K, system.M, _damping(system), omega))
        return float(np.abs(N.T @ (Z @ q - F)).max(initial=0.0) / _scale(Z, q, F))


class Kkt(Formulation):
    r"""Lagrange multipliers, the bordered system ``[[Z, A^T], [A, 0]]``; it owns the KKT
    residual, the multipliers fitted by least squares:
    :math:`\max(|Z q + A_k^T \lambda - F|, |A_k q - R_k F|)`."""

    name = KKT

    def receptance(self, system: ConstrainedSystem, omegas: np.ndarray, E: np.ndarray,
                   O: sp.sparray | np.ndarray) -> np.ndarray:
        return kkt_sweep(system.K, system.M, _damping(system), system.A, system.R, omegas, E,
                         O, system.independent)

    def dense_modes(self, M: np.ndarray, C: np.ndarray, K: np.ndarray,
                    A: np.ndarray) -> Modes:
        from substruct.analysis.modes.dense import kkt_modes
        return kkt_modes(M, C, K, A)

    def residual(self, system: ConstrainedSystem, omega: float, q: np.ndarray,
                 F: np.ndarray) -> float:
        Z = dense(impedance(system.K, system.M, _damping(system), omega))
        r = F - Z @ q
        keep = system.independent.keep
        if not len(keep):
            return float(np.abs(r).max(initial=0.0) / _scale(Z, q, F))
        Ak = dense(system.A)[keep]
        lam = np.linalg.lstsq(Ak.T, r, rcond=None)[0]
        gaps = (np.abs(r - Ak.T @ lam).max(initial=0.0),
                np.abs(Ak @ q - _RF(system, F)[keep]).max(initial=0.0)
                * float(np.abs(Z).max(initial=0.0)))
        return float(max(gaps) / _scale(Z, q, F))


#: The formulation objects.
GENERALIZED_INVERSE_FORM = GeneralizedInverse()
NULL_SPACE_FORM = NullSpace()
KKT_FORM = Kkt()
#: Name -> formulation, in the order of :data:`substruct.vocabulary.FORMULATIONS`.
REGISTRY: dict[str, Formulation] = {f.name: f for f in (GENERALIZED_INVERSE_FORM,
                                                       NULL_SPACE_FORM, KKT_FORM)}


def formulation(name: str) -> Formulation:
    """The formulation called ``name``.

    Raises:
        ValueError: an unknown name (``unknown method ...; expected one of ...``).

    Examples
    --------
    >>> from substruct.analysis.formulations.forms import formulation
    >>> formulation("kkt")
    formulation('kkt')
    >>> formulation("lagrange")
    Traceback (most recent call last):
    ...
    ValueError: unknown method 'lagrange'; expected one of generalized-inverse, null-space, kkt
    """
    try:
        return REGISTRY[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown method {name!r}; expected one of "
                         f"{', '.join(REGISTRY)}") from None
