"""Discrete secondary systems (eqs 17-20)."""

import numpy as np
import pytest
import scipy.linalg as sla

from substruct.models.discrete import fixed_free, free_free
from substruct.substructure import PointError


def test_fixed_free_matrices_and_points():
    s = fixed_free("a", mass=2.0, stiffness=3000.0, damping=0.5)
    assert s.M.toarray().tolist() == [[2.0]]
    assert s.K.toarray().tolist() == [[3000.0]]
    assert s.C.toarray().tolist() == [[0.5]]
    assert s.dof_labels == ("mass",)
    assert s.row("mass").toarray().tolist() == [[1.0]]
    assert s.row("boundary").toarray().tolist() == [[1.0]]
    assert not s.massless.any()
    assert np.isclose(np.sqrt(s.K.toarray()[0, 0] / s.M.toarray()[0, 0]), np.sqrt(1500.0))


def test_free_free_matrices_eqs_19_20():
    s = free_free("c", mass=1.0, stiffness=7000.0, damping=3.0)
    assert s.dof_labels == ("mass", "boundary")
    assert np.array_equal(s.M.toarray(), [[1.0, 0.0], [0.0, 0.0]])
    assert np.array_equal(s.K.toarray(), [[7000.0, -7000.0], [-7000.0, 7000.0]])
    assert np.array_equal(s.C.toarray(), [[3.0, -3.0], [-3.0, 3.0]])
    assert s.massless.tolist() == [False, True]
    assert s.row("mass").toarray().tolist() == [[1.0, 0.0]]
    assert s.row("boundary").toarray().tolist() == [[0.0, 1.0]]


def test_free_free_grounded_at_boundary_has_sqrt_k_over_m():
    """Boundary fixed (z_b = 0): one mode at sqrt(k/m) = sqrt(3000/1.5)."""
    s = free_free("d", mass=1.5, stiffness=3000.0)
    keep = ~s.massless
    lam = sla.eigh(s.K.toarray()[np.ix_(keep, keep)], s.M.toarray()[np.ix_(keep, keep)],
                   eigvals_only=True)
    assert np.allclose(np.sqrt(lam), [np.sqrt(2000.0)], rtol=1e-14)
    # unconstrained, K has the rigid-body null vector [1, 1]
    assert np.allclose(s.K @ np.ones(2), 0.0)


@pytest.mark.parametrize("maker", [fixed_free, free_free])
@pytest.mark.parametrize("field, value", [
    ("mass", 0.0), ("mass", -1.0), ("mass", float("nan")), ("stiffness", 0.0),
    ("stiffness", float("inf")), ("damping", -0.1), ("mass", "heavy"),
])
def test_validation_names_substructure_field_value(maker, field, value):
    args = {"mass": 1.0, "stiffness": 10.0, "damping": 0.0} | {field: value}
    with pytest.raises(ValueError) as err:
        maker("absorber_7", **args)
    msg = str(err.value)
    assert "absorber_7" in msg and field in msg and repr(value) in msg


def test_zero_damping_is_allowed_and_unknown_points_rejected():
    s = free_free("c", 1.0, 1.0)
    assert s.C.nnz == 0
    with pytest.raises(PointError, match="c.*'tip'.*boundary"):
        s.row("tip")
    with pytest.raises(PointError):
        fixed_free("a", 1.0, 1.0).row(0.5)


def test_geometry_local_coordinates():
    s = free_free("c", 1.0, 1.0)
    g = s.geometry
    assert np.array_equal(g.points, [[0, 0, 0], [0, -1, 0]])
    disp = g.displacement(np.array([2.0, 0.5]))  # mass moves 2, boundary 0.5, along x
    assert np.array_equal(disp, [[0.5, 0, 0], [2.0, 0, 0]])
    assert g.glyphs == {"boundary": 0, "mass": 1}
    f = fixed_free("a", 1.0, 1.0).geometry
    assert np.array_equal(f.displacement(np.array([3.0])), [[3.0, 0, 0], [0, 0, 0]])
