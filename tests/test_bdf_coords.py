"""Coordinate systems of Nastran bulk data (substruct/case/bdf_coords.py): CORD2C, CORD2S,
CORD1R/C/S and RID chains place the grids (GRID CP).

* a ring of CBARs whose grids are given in a cylindrical system (CORD2C, itself in a rotated
  CORD2R) and a spherical one (CORD2S) and a CORD1C on three grids: its positions are those
  computed by hand to 1e-13, and its stiffness and mass equal, to 1e-13, those of the same
  model written in basic coordinates (the hand positions printed to 17 digits, exact);
* a missing RID or grid and systems that refer to each other in a loop are refused, naming
  the card and line.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from substruct.case.bdf import parse_bulk
from substruct.case.bdf_fields import BdfError
from substruct.models.nastran import nastran_matrices

# CORD2R 1: origin (1, 2, 3), z along basic x, x along basic y (so y along basic z).
# CORD2C 2 in 1: origin (0, 0, 1) of 1, z along 1's y, C on 1's x.
# CORD2S 3 in 2 (cylindrical coordinates of A, B, C): origin at R=1, theta=90, z=0 of 2.
SYSTEMS = ["CORD2R,1,,1.,2.,3.,2.,2.,3.,", ",1.,3.,3.",
           "CORD2C,2,1,0.,0.,1.,0.,1.,1.,", ",1.,0.,1.",
           "CORD2S,3,2,1.,90.,0.,1.,90.,1.,", ",2.,90.,0."]
RING = 8  # grids 1-8 on a circle of radius 2 in system 2, 45 degrees apart


def _hand() -> dict[int, np.ndarray]:
    """The basic positions of the grids of :func:`_deck`, by hand."""
    o1, R1 = np.array([1.0, 2.0, 3.0]), np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0],
                                                     [1.0, 0.0, 0.0]])  # rows: x, y, z of 1
    in1 = lambda q: o1 + R1.T @ np.asarray(q, float)  # noqa: E731
    # system 2: origin 1's (0, 0, 1); z along 1's y; x along 1's x (C - A = 1's x)
    o2 = in1([0.0, 0.0, 1.0])
    ez2, ex2 = R1[1], R1[0]
    R2 = np.array([ex2, np.cross(ez2, ex2), ez2])
    in2 = lambda r, t, z: o2 + R2.T @ np.array([r * math.cos(math.radians(t)),  # noqa: E731
                                                r * math.sin(math.radians(t)), z])
    out = {k + 1: in2(2.0, 45.0 * k, 0.5) for k in range(RING)}
    # system 3: origin 2's (1, 90, 0), z along 2's z, x towards 2's (2, 90, 0): radial
    o3 = in2(1.0, 90.0, 0.0)
    ez3 = R2[2]
    ex3 = in2(2.0, 90.0, 0.0) - o3
    R3 = np.array([ex3, np.cross(ez3, ex3), ez3])
    t, p = math.radians(60.0), math.radians(30.0)
    out[11] = o3 + R3.T @ (1.5 * np.array([math.sin(t) * math.cos(p),
                                           math.sin(t) * math.sin(p), math.cos(t)]))
    # CORD1C 4 on grids 1 (origin), 3 (on z), 2 (in x-z); grid 12 at R=0.5, theta=30, z=0.2
    ez4 = (out[3] - out[1]) / np.linalg.norm(out[3] - out[1])
    ey4 = np.cross(ez4, out[2] - out[1])
    ey4 /= np.linalg.norm(ey4)
    R4 = np.array([np.cross(ey4, ez4), ey4, ez4])
    out[12] = out[1] + R4.T @ np.array([0.5 * math.cos(math.radians(30.0)),
                                        0.5 * math.sin(math.radians(30.0)), 0.2])
    return out


def _members() -> list[str]:
    lines = ["MAT1,1,2.1+11,,.3,7850.", "PBAR,1,1,1.-3,1.-7,2.-7,1.5-7", "CONM2,31,11,,2.",
             "CONM2,32,12,,3."]
    for k in range(RING):
        lines.append(f"CBAR,{k + 1},1,{k + 1},{(k + 1) % RING + 1},,,,,")
        lines[-1] = f"CBAR,{k + 1},1,{k + 1},{(k + 1) % RING + 1},11"
    lines += ["CBAR,21,1,1,11,12", "CBAR,22,1,11,12,3", "CBAR,23,1,12,5,1"]
    return lines


def _deck() -> str:
    grids = [f"GRID,{k + 1},2,2.,{45.0 * k:.1f},.5" for k in range(RING)]
    grids += ["GRID,11,3,1.5,60.,30.", "CORD1C,4,1,3,2", "GRID,12,4,.5,30.,.2"]
    return "\n".join(SYSTEMS + grids + _members()) + "\n"


def _basic_deck() -> str:
    grids = [f"GRID,{g},,{x[0]:.16e},{x[1]:.16e},{x[2]:.16e}" for g, x in _hand().items()]
    return "\n".join(grids + _members()) + "\n"


def test_grids_in_cylindrical_and_spherical_systems_are_placed_as_by_hand():
    bulk = parse_bulk(_deck(), "c.bdf")
    hand = _hand()
    assert set(bulk.grids) == set(hand)
    for g, x in hand.items():
        assert np.abs(bulk.grids[g] - x).max() < 1e-13 * 10, (g, bulk.grids[g], x)
    a, b = nastran_matrices(bulk), nastran_matrices(parse_bulk(_basic_deck(), "b.bdf"))
    for X, Y in ((a.K, b.K), (a.M, b.M)):
        assert abs(X - Y).max() <= 1e-13 * abs(Y).max()


@pytest.mark.parametrize("extra, fragment", [
    ("CORD2C,5,9,0.,0.,0.,0.,0.,1.,\n,1.,0.,0.\nGRID,1,5,1.,0.,0.",
     "line 1: CORD2C 5: RID: no such coordinate system, got 9"),
    ("CORD2S,5,6,0.,0.,0.,0.,0.,1.,\n,1.,0.,0.\nCORD2R,6,5,0.,0.,0.,0.,0.,1.,\n,1.,0.,0.\n"
     "GRID,1,5,1.,0.,0.", "coordinate systems refer to each other in a loop, got [5, 6, 5]"),
    ("CORD1R,5,1,2,3\nGRID,1,5,1.,0.,0.\nGRID,2,,0.,0.,1.\nGRID,3,,1.,0.,0.",
     "line 1: CORD1R 5: G1A (GRID 1): coordinate systems refer to each other in a loop"),
    ("CORD1S,5,1,2,4\nGRID,1,,1.,0.,0.\nGRID,2,,0.,0.,1.",
     "line 1: CORD1S 5: G3A: no such GRID, got 4"),
    ("GRID,1,7,1.,0.,0.", "line 1: GRID 1: CP: no such coordinate system, got 7"),
    ("CORD2C,5,,0.,0.,0.,0.,0.,1.,\n,0.,0.,2.\nGRID,1,5,1.,0.,0.",
     "line 1: CORD2C 5: A, B and C do not define axes"),
    ("CORD1C,5,1,2,2\nGRID,1,,1.,0.,0.\nGRID,2,,0.,0.,1.",
     "line 1: CORD1C 5: G1A: the three grids are distinct"),
])
def test_bad_systems_are_refused_with_the_card_and_line(extra, fragment):
    with pytest.raises(BdfError) as err:
        parse_bulk(extra + "\n", "c.bdf")
    assert fragment in str(err.value) and "\n" not in str(err.value), str(err.value)
