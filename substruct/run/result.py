"""What an analysis produces: plain arrays, independent of how the model was built.

A :class:`Result` is what ``substruct run`` writes to HDF5 (:mod:`substruct.io.hdf5`), what the
reader returns, and what the pictures and exports are drawn from.  Its modes and receptances are
the analysis layer's own types, :class:`~substruct.analysis.results.Modes` and
:class:`~substruct.analysis.results.Receptance`.  It holds no callables, so a result
read back from a file is the same object as the one computed.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sp

from substruct.analysis.results import Modes, Receptance
from substruct.builder.drawing import Drawing

if TYPE_CHECKING:  # the results of the other analyses (and their layers) only where used
    from substruct.analysis.transient.results import Transient
    from substruct.run.recovered import Recovered
    from substruct.run.spec_results import BaseFrf, RandomResponse, ShockSpectra
    from substruct.analysis.frf.virtual_point import VptResult
    from substruct.case.channel_geometry import PartChannels
    from substruct.analysis.frf.vp_noise import MonteCarloResult
    from substruct.run.testlab_results import SemmOutcome, TpaResult

__all__ = ["ModelInfo", "Result"]


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
    #: the assembly's ``"M"``, ``"K"``, ``"C"`` (stacked coordinates, eq 23) when the case
    #: asks for them (``output: {matrices: true}``), else empty
    matrices: dict[str, sp.csr_array] = field(default_factory=dict)


@dataclass
class Result:
    """Everything one run of a case produced: the model as data, the coupled modes, the
    receptances.

    ``variants`` holds modes of the same model with some constraints left out (for instance the
    paper's Table 1 "without additional constraint (52)"), by variant name.
    """

    case_name: str
    case_yaml: str
    model: ModelInfo
    modes: Modes | None = None
    frf: Receptance | None = None
    transient: Transient | None = None
    variants: dict[str, Modes] = field(default_factory=dict)
    #: responses recovered inside superelements (:mod:`substruct.run.recovered`)
    recovery: list[Recovered] = field(default_factory=list)
    attrs: dict[str, Any] = field(default_factory=dict)
    #: response PSDs and RMS of analysis.random; shock response spectra of analysis.srs
    random: RandomResponse | None = None
    srs: ShockSpectra | None = None
    #: transmissibilities per base acceleration of analysis.base_frf
    base_frf: BaseFrf | None = None
    #: consistency indicators of the parts transformed to virtual points, by part
    virtual_points: dict[str, VptResult] = field(default_factory=dict)
    #: the coupled result's sensitivity to noise (``virtual_points.monte_carlo``)
    monte_carlo: MonteCarloResult | None = None
    #: blocked forces, their validation and path contributions of analysis.tpa
    tpa: TpaResult | None = None
    #: the mixed model of analysis.semm
    semm: SemmOutcome | None = None
    #: the channel tables and virtual points of a virtual-point case, by part
    #: (:mod:`substruct.case.channel_geometry`)
    channels: dict[str, PartChannels] = field(default_factory=dict)
