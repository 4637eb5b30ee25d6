"""Studies: parameters wherever a number is read, the ``study:`` block, the study on every
backend (in-process, a LocalCluster, a scheduler and a worker in separate processes), failed
samples, the study file and a sample checked against ``substruct run --set``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from substruct.case.loader import CaseError, parse_case
from substruct.run.runner import run_case

CASES = Path(__file__).resolve().parent.parent / "cases"
ROD = CASES / "tapered_rod.yaml"
QUICK = ["analysis.frf.omega={start: 1, stop: 200, num: 40, spacing: linear}"]


def rod_case(overrides=()):
    return parse_case(ROD.read_text(), str(ROD), CASES, list(overrides))


# ----------------------------------------------------------------- step 1: parameters


def test_a_parameter_feeds_stiffness_mass_damping_and_counts():
    literal = run_case(rod_case(QUICK + [
        "substructures.c.stiffness=8000", "substructures.c.mass=1.5",
        "substructures.c.damping=20", "substructures.rod.discretization.n=10"]))
    named = run_case(rod_case(QUICK + [
        "parameters.k=4000", "parameters.n=5", "substructures.c.stiffness=2*k",
        "substructures.c.mass=k/8000*3", "substructures.c.damping=k/200",
        "substructures.rod.discretization.n=2*n"]))
    assert named.modes is not None and literal.modes is not None
    assert np.array_equal(named.modes.omega, literal.modes.omega)
    assert np.array_equal(named.modes.damping_ratio, literal.modes.damping_ratio)
    assert named.modes.damping_ratio.max() > 0  # the damper is there
    # and they differ from the shipped stiffness 7000
    shipped = run_case(rod_case(QUICK))
    assert shipped.modes is not None
    assert not np.allclose(shipped.modes.omega, named.modes.omega)


def test_parameters_may_be_expressions_of_earlier_ones():
    case = rod_case(["parameters.k0=7000", "parameters.kc=1.5*k0",
                     "substructures.c.stiffness=kc", "parameters.z=0.01",
                     "substructures.rod.reduce.damping={ratio: z}"])
    assert case.substructure("c").stiffness == 10500.0
    assert case.substructure("rod").reduce.damping.as_argument() == 0.01


@pytest.mark.parametrize("overrides, fragment", [
    (["substructures.c.stiffness=kk"], "substructures.c.stiffness: must be a number"),
    (["substructures.c.stiffness=2*kk"], "substructures.c.stiffness: unknown name 'kk'"),
    (["substructures.c.stiffness=-EA0"], "substructures.c.stiffness: must be > 0"),
    (["substructures.c.stiffness=EA0*1e30"],
     "substructures.c.stiffness: 'EA0*1e30' = 6e+36: out of range: too large"),
    (["substructures.c.stiffness=__import__('os')"], "substructures.c.stiffness: call of"),
    (["parameters.n=8.5", "substructures.rod.discretization.n=n"],
     "substructures.rod.discretization.n: must be an integer: 'n' = 8.5"),
    (["parameters.n=0", "substructures.rod.discretization.n=n"],
     "substructures.rod.discretization.n: must be >= 1"),
])
def test_bad_parameter_values_are_one_line_naming_the_field(overrides, fragment):
    with pytest.raises(CaseError) as info:
        rod_case(overrides)
    message = str(info.value)
    assert fragment in message and "\n" not in message
