"""What an analysis produces: plain arrays, independent of how the model was built.

A :class:`Result` is what ``substruct run`` writes to HDF5 (``results.py``), what the reader
returns, and what the pictures and exports are drawn from.  It holds no callables, so a result
read back from a file is the same object as the one computed.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp

from substruct.builder.drawing import Drawing

__all__ = ["ModelInfo", "ModeResult", "FrfResult", "Result"]


@dataclass
class ModelInfo:
    """The assembled model as data: DOF table, constraints, drawings."""

    dof_labels: list[str]
    substructure_names: list[str]
    substructure_kinds: list[str]
    offsets: np.ndarray
    A: sp.csr_array
    b: np.ndarray
    R: sp.csr_array
    constraint_labels: list[str]
    drawings: list[Drawing] = field(default_factory=list)


@dataclass
class ModeResult:
    """Physical modes (ascending) and the roots set aside, with the cross-check figures.

    ``agreement`` maps a check formulation to the largest relative eigenvalue difference from
    the main formulation (:func:`substruct.analysis.dense_modes.modes_agreement`).
    """

    method: str
    eigenvalues: np.ndarray
    omega: np.ndarray
    damping_ratio: np.ndarray
    shapes: np.ndarray
    residual: np.ndarray
    spurious: np.ndarray
    spurious_reason: list[str]
    agreement: dict[str, float] = field(default_factory=dict)

    @property
    def freq_hz(self) -> np.ndarray:
        """Natural frequencies in Hz."""
        return self.omega / (2 * np.pi)


@dataclass
class FrfResult:
    """Receptances ``H[k, i, j]``: output ``i`` per unit force at input ``j``, at ``omega[k]``."""

    method: str
    omega: np.ndarray
    H: np.ndarray
    inputs: list[str]
    outputs: list[str]
    agreement: dict[str, float] = field(default_factory=dict)
    constraint_residual: float = 0.0


@dataclass
class Result:
    """Everything one run of a case produced.

    ``variants`` holds modes of the same model with some constraints left out (for instance the
    paper's Table 1 "without additional constraint (52)"), by variant name.
    """

    case_name: str
    case_yaml: str
    model: ModelInfo
    modes: ModeResult | None = None
    frf: FrfResult | None = None
    variants: dict[str, ModeResult] = field(default_factory=dict)
    attrs: dict[str, Any] = field(default_factory=dict)
