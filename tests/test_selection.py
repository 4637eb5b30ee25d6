"""One node selector, one component parser, one tolerance: supports, interfaces, points and
case checks pick the same nodes and read components the same way."""

import numpy as np
import pytest

from substruct.assembly.interfaces import interface_nodes, node_dofs, tie_nodes
from substruct.models.selection import (
    NODE_TOL,
    component_index,
    component_indices,
    model_size,
    node_tolerance,
    nodes_in_box,
    parse_box,
)
from substruct.models.solid import BoxGrid, RectangleGrid, solid_box, solid_rectangle
from substruct.substructure import PointError

E, NU, RHO = 2.1e11, 0.3, 7850.0
L = 2.0  # the box is 2 x 0.5 x 0.5: its size is 2, the tolerance 2e-8


def box(**kwargs):
    return solid_box("b", BoxGrid([L, 0.5, 0.5], [4, 1, 1]), E, NU, RHO, **kwargs)


@pytest.mark.parametrize("name, dim, index", [
    ("x", 3, 0), ("Y", 3, 1), (" uz ", 3, 2), ("ux", 2, 0), (0, 2, 0), (np.int64(2), 3, 2)])
def test_components_by_name_or_number(name, dim, index):
    assert component_index(name, dim, "s") == index


@pytest.mark.parametrize("name, dim", [("w", 3), ("z", 2), (2, 2), (-1, 3), (True, 3),
                                       ("", 3), ("u", 3), (1.0, 3)])
def test_components_that_do_not_exist(name, dim):
    with pytest.raises(PointError, match=r"s: no displacement component .* in a \dD solid"):
        component_index(name, dim, "s")


def test_component_lists():
    assert component_indices(None, 2, "s") == [0, 1]
    assert component_indices("z", 3, "s") == [2]
    assert component_indices(["y", "x"], 3, "s") == [1, 0]


def test_tolerance_is_relative_to_the_model_size():
    pts = np.array([[0.0, 0.0, 0.0], [L, 0.5, 0.5]])
    assert model_size(pts) == L
    assert node_tolerance(pts) == pytest.approx(NODE_TOL * L)
    assert node_tolerance(pts, 1e-3) == 1e-3
    assert model_size(np.zeros((0, 3))) == 1.0


def test_boxes():
    lo, hi = parse_box([[0, 0, -1], [1, 1, 1]], 2, "s")  # holds the plane z = 0 of a 2D solid
    np.testing.assert_array_equal(lo, [0, 0])
    np.testing.assert_array_equal(hi, [1, 1])
    with pytest.raises(ValueError, match="misses the plane z = 0"):
        parse_box([[0, 0, 1], [1, 1, 2]], 2, "s")
    with pytest.raises(ValueError, match="min <= max"):
        parse_box([[1, 0, 0], [0, 1, 1]], 3, "s")
    with pytest.raises(ValueError, match="a box is"):
        parse_box("corner", 3, "s")
    pts = np.array([[0.0, 0.0], [1.0, 0.0], [1.0 + 1e-3, 0.0]])
    np.testing.assert_array_equal(nodes_in_box(pts, np.array([1.0, 0]), np.array([1.0, 0]),
                                               1e-6), [1])


@pytest.mark.parametrize("offset, selected", [(0.4, True), (2.5, False)])
def test_supports_and_interfaces_pick_the_same_nodes(offset, selected):
    """A flat box just beside the plane x = L, ``offset`` tolerances away: supports and
    interfaces both take its four corner nodes, or both take none."""
    x = L + offset * NODE_TOL * L
    flat = [[x, 0, 0], [x, 0.5, 0.5]]
    free = box()
    assert len(interface_nodes(free, {"box": flat})) == (4 if selected else 0)
    assert len(node_dofs(free, {"box": flat}, ["x"])) == (4 if selected else 0)
    if selected:
        held = box(fixed=[{"box": flat, "components": ["x"]}])
        assert held.meta["n_fixed"] == 4 and held.n_dof == free.n_dof - 4
    else:
        with pytest.raises(ValueError, match="selects no node"):
            box(fixed=[{"box": flat}])


@pytest.mark.parametrize("offset, unit", [(0.4, True), (2.5, False)])
def test_a_point_is_a_node_within_the_same_tolerance(offset, unit):
    """At a node (within the tolerance) a point's row is a unit row; a little further it is
    the interpolation row, which still gives the node's value to first order."""
    sub = box()
    row = sub.row({"at": [L, 0.5, 0.5 - offset * NODE_TOL * L], "component": "z"})
    assert bool(row.nnz == 1 and row.data[0] == 1.0) == unit
    assert row.sum() == pytest.approx(1.0, abs=1e-6)


def test_ties_match_nodes_within_the_same_tolerance():
    a = box()
    shift = 0.4 * NODE_TOL * L
    b = solid_box("c", BoxGrid([L, 0.5, 0.5], [4, 1, 1], origin=[L + shift, 0, 0]), E, NU, RHO)
    ties = tie_nodes(a, b, {"box": [[L, 0, 0], [L, 0.5, 0.5]]})
    assert len(ties) == 4 * 3  # four corner nodes of the face, three components each
    assert {t.name.rsplit(" ", 1)[1] for t in ties} == {"ux", "uy", "uz"}


def test_components_of_a_2d_solid():
    plate = solid_rectangle("p", RectangleGrid([1.0, 0.2], [4, 2]), E, NU, RHO)
    assert plate.row({"at": [1.0, 0.2], "component": "uy"}).nnz == 1
    with pytest.raises(PointError, match="no displacement component 'z' in a 2D solid"):
        plate.row({"at": [1.0, 0.2], "component": "z"})
    with pytest.raises(ValueError, match="no displacement component 'z' in a 2D solid"):
        node_dofs(plate, None, ["z"])
