"""The sparse eigensolvers on models whose constraints leave few free coordinates.

A P2 rod of 8 elements fixed at both ends (15 coordinates) with one free-free absorber (a mass
and a massless boundary) joined at x = 150: 17 coordinates, one connection, 16 free.  ARPACK's
default Krylov basis for 6 modes is 20 vectors, more than the 16 the shift-invert operator spans
on ``null(A)``: it failed with "ARPACK error -9999".  The basis is now capped by the free
coordinates (:func:`substruct.analysis.modes.krylov.krylov_size`); the modes equal the dense ones, and
the command records which solver ran.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from cli_helpers import run
from substruct.analysis.modes.dense import coupled_modes
from substruct.analysis.modes.krylov import free_coordinates, krylov_size, eliminate
from substruct.analysis.modes.sparse import FORMULATIONS, sparse_coupled_modes
from substruct.assembly.stack import Connection, PointRef, assemble
from substruct.io import hdf5
from substruct.models.discrete import free_free
from substruct.models.rod import rod_fe


def small_rod(damping: float = 0.0):
    rod = rod_fe("rod", 200.0, 6.0e6, 1.0, 8, order=2, support="fixed-fixed")
    absorber = free_free("c", 1.0, 7000.0, damping)
    return assemble([rod, absorber], [Connection(PointRef("rod", 150.0), PointRef("c", "boundary"))])


def test_the_model_leaves_sixteen_free_coordinates():
    asm = small_rod()
    el = eliminate(asm.M, asm.A)
    assert asm.n_dof == 17 and el.rank == 1
    assert free_coordinates(el, asm.M) == 16
    assert krylov_size(6, 16) == 15  # not ARPACK's 20
    with pytest.raises(ValueError, match="15 modes .* 16 free coordinates"):
        krylov_size(15, 16)


@pytest.mark.parametrize("method", FORMULATIONS)
def test_sparse_modes_of_a_small_model_equal_the_dense_ones(method):
    asm = small_rod()
    dense = coupled_modes(asm.M, None, asm.K, asm.A, "null-space", n_modes=6)
    modes = sparse_coupled_modes(asm.M, asm.K, asm.A, 6, method=method)
    np.testing.assert_allclose(modes.omega, dense.omega, rtol=1e-10)
    assert modes.residual.max() < 1e-12
    assert modes.solver == "sparse"


@pytest.mark.parametrize("method", ["null-space", "kkt"])
def test_damped_sparse_modes_of_a_small_model_equal_the_dense_ones(method):
    asm = small_rod(damping=20.0)
    dense = coupled_modes(asm.M, asm.C, asm.K, asm.A, "kkt", n_modes=5)
    modes = sparse_coupled_modes(asm.M, asm.K, asm.A, 5, method=method, C=asm.C)
    np.testing.assert_allclose(modes.eigenvalues, dense.eigenvalues, rtol=1e-9)
    assert modes.solver == "sparse-damped"


def test_too_many_modes_for_the_free_coordinates_is_a_clear_error():
    asm = small_rod()
    with pytest.raises(ValueError, match="too few for a Krylov basis"):
        sparse_coupled_modes(asm.M, asm.K, asm.A, 15, method="generalized-inverse")


CASE = """\
name: rod_small
units: "N, mm, t, s"
substructures:
  - name: rod
    type: rod
    length: 200
    EA: 6.0e6
    m: 1.0
    support: fixed-fixed
    discretization: {{method: fe, elements: 8, order: 2}}
  - {{name: c, type: free-free, mass: 1, stiffness: 7000}}
connections:
  - [rod@150, c]
analysis:
  modes:
    count: 6
    method: {method}
    check: {checks}
    solver: {solver}
output: {{pictures: false}}
"""


@pytest.mark.parametrize("method", ["generalized-inverse", "kkt"])
def test_cli_sparse_solver_on_a_small_model(capsys, tmp_path, method):
    out = {}
    for solver in ("dense", "sparse"):
        path = tmp_path / f"{solver}.yaml"
        checks = "[null-space]" if method == "kkt" else "[null-space, kkt]"
        path.write_text(CASE.format(method=method, solver=solver, checks=checks))
        code, text, err = run(capsys, "run", path, "--out", tmp_path / solver, "--json",
                              "--quiet")
        assert code == 0, err
        out[solver] = json.loads(text)["modes"]
        assert max(out[solver]["agreement"].values()) < 1e-10
    np.testing.assert_allclose(out["sparse"]["omega"], out["dense"]["omega"], rtol=1e-10)
    ran = hdf5.load(tmp_path / "sparse" / "rod_small.h5").modes.solver
    # the Krylov solver within its room, or the dense one with the reason said
    assert ran == "sparse" or (ran.startswith("dense (") and "Krylov" in ran), ran
