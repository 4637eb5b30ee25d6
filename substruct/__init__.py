"""substruct: finite-element substructuring for structural dynamics.

Substructures (finite-element models, assumed-modes models, spring-mass-damper attachments) are
coupled through linear constraints by the generalized-inverse method of Eun, Lee, Chung and Park
("Structural and Mechanical Systems Subjected to Constraints"), checked against null-space and
Lagrange-multiplier formulations.

The Python API mirrors the command line::

    import substruct
    case = substruct.load_case("cases/tapered_rod.yaml")    # a path, a dict or YAML text
    result = substruct.run_case(case)
    result.modes.omega, result.frf.at("rod@200", "rod@50")
    substruct.frf_figure(result)                            # a matplotlib figure

The names are imported on first use (``import substruct`` stays light); ``dir(substruct)``
lists them.
"""

from __future__ import annotations

from substruct.lazy import lazy_getattr

__version__ = "0.1.0"

#: Public name -> the module that defines it.
_LAZY = {
    "load_case": "substruct.case.loader",
    "CaseError": "substruct.case.loader",
    "build_model": "substruct.run.runner",
    "run_case": "substruct.run.runner",
    "Result": "substruct.run.result",
    "Modes": "substruct.analysis.results",
    "Receptance": "substruct.analysis.results",
    "CheckError": "substruct.analysis.errors",
    "modes": "substruct.analysis.api",
    "receptance_sweep": "substruct.analysis.api",
    "load_result": "substruct.io.hdf5",
    "save_result": "substruct.io.hdf5",
    "plot_modes": "substruct.viz.plotting",
    "plot_frf": "substruct.viz.plotting",
    "modes_figure": "substruct.viz.plotting",
    "frf_figure": "substruct.viz.plotting",
}
#: Names whose defining attribute is called otherwise.
_ATTRIBUTE = {"load_result": "load", "save_result": "save"}

__all__ = ["__version__", *_LAZY]


__getattr__ = lazy_getattr(__name__, _LAZY, attributes=_ATTRIBUTE)


def __dir__() -> list[str]:
    """The public names, lazy ones included (what tab completion offers)."""
    return sorted(__all__)
