"""Discrete secondary systems (eqs 17-20)."""

import numpy as np
import pytest
import scipy.linalg as sla

from substruct.models.discrete import fixed_free, free_free, point_mass, spring
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


# ------------------------------------------------------------------- spring, point mass


def test_spring_between_two_points_matrices():
    s = spring("s", stiffness=5.0e6, damping=20.0)
    pattern = np.array([[1.0, -1.0], [-1.0, 1.0]])
    assert s.kind == "spring" and s.dof_labels == ("i", "j")
    assert np.array_equal(s.K.toarray(), 5.0e6 * pattern)
    assert np.array_equal(s.C.toarray(), 20.0 * pattern)
    assert np.array_equal(s.M.toarray(), np.zeros((2, 2))) and s.M.nnz == 0
    assert s.massless.tolist() == [True, True]
    assert s.row("i").toarray().tolist() == [[1.0, 0.0]]
    assert s.row("j").toarray().tolist() == [[0.0, 1.0]]
    # end forces f_i = -f_j = k (z_i - z_j): a stretch of 1e-6 carries 5 N
    assert np.allclose(s.K @ np.array([1e-6, 0.0]), [5.0, -5.0])
    assert s.meta == {"stiffness": 5.0e6, "damping": 20.0, "grounded": False}


def test_grounded_spring_matrices():
    s = spring("g", stiffness=3000.0, damping=0.5, grounded=True)
    assert s.kind == "spring/grounded" and s.dof_labels == ("i",)
    assert s.K.toarray().tolist() == [[3000.0]] and s.C.toarray().tolist() == [[0.5]]
    assert s.M.toarray().tolist() == [[0.0]] and s.massless.tolist() == [True]
    with pytest.raises(PointError, match=r"g.*'j'.*\['i'\]"):
        s.row("j")


def test_point_mass_matrices():
    m = point_mass("m1", mass=0.5)
    assert m.kind == "mass" and m.dof_labels == ("mass",)
    assert m.M.toarray().tolist() == [[0.5]]
    assert m.K.nnz == 0 and m.C.nnz == 0 and m.K.shape == (1, 1)
    assert m.row("mass").toarray().tolist() == [[1.0]]
    with pytest.raises(PointError, match="m1.*'boundary'"):
        m.row("boundary")


@pytest.mark.parametrize("field, value", [
    ("stiffness", 0.0), ("stiffness", -3.0), ("stiffness", float("inf")),
    ("stiffness", float("nan")), ("damping", -0.1), ("damping", float("inf")),
    ("stiffness", "stiff"),
])
@pytest.mark.parametrize("grounded", [False, True])
def test_spring_validation_names_field_and_value(field, value, grounded):
    args = {"stiffness": 10.0, "damping": 0.0} | {field: value}
    with pytest.raises(ValueError) as err:
        spring("joint_3", grounded=grounded, **args)
    msg = str(err.value)
    assert "joint_3" in msg and field in msg and repr(value) in msg


@pytest.mark.parametrize("value", [0.0, -1.0, float("nan"), float("-inf"), True])
def test_point_mass_validation_names_field_and_value(value):
    with pytest.raises(ValueError) as err:
        point_mass("m7", value)
    assert "m7" in str(err.value) and "mass" in str(err.value) and repr(value) in str(err.value)


def test_spring_and_mass_geometry_local_coordinates():
    """Same convention as fixed_free/free_free: first point at the origin, other end below."""
    g = spring("s", 1.0).geometry
    assert np.array_equal(g.points, [[0, 0, 0], [0, -1, 0]])
    assert g.glyphs == {"i": 0, "j": 1}
    assert np.array_equal(g.displacement(np.array([2.0, 0.5])), [[2.0, 0, 0], [0.5, 0, 0]])
    gg = spring("g", 1.0, grounded=True).geometry
    assert gg.glyphs == {"i": 0, "ground": 1}
    assert np.array_equal(gg.displacement(np.array([3.0])), [[3.0, 0, 0], [0, 0, 0]])
    gm = point_mass("m", 1.0).geometry
    assert np.array_equal(gm.points, [[0, 0, 0]]) and gm.glyphs == {"mass": 0}
    assert gm.cells[0][0] == "vertex"
    assert np.array_equal(gm.displacement(np.array([4.0])), [[4.0, 0, 0]])
