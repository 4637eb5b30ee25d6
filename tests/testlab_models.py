"""Synthetic test-lab data from finite-element frames with known answers.

Two steel frames meet at a joint ``J`` at the origin: ``A`` (the source, free) and ``B``
(the receptor, clamped at its far end); the assembly ``AB`` is one frame with both sets of
members sharing node 1 (``J``), a formulation independent of any coupling.  Each part carries a
rigid adapter at ``J`` with three triaxial sensors (each in its own rotated frame) and nine
impacts on the faces of a 50 mm cube, off the face centres so that they load the rotations;
channels away from the joint read the translations of a node.  A channel at position ``r`` in
direction ``e`` on node ``N`` at ``r_N`` reads (sensor) or loads (impact) the node's six
coordinates with the row ``[e, (r - r_N) x e]``: the rigid-adapter kinematics.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from substruct.analysis.api import receptance_sweep
from substruct.case.channels import ChannelTable, parse_channels
from substruct.models.beam import Material, Section
from substruct.models.frame import Beam, frame
from substruct.substructure import Substructure

STEEL = Material(E=2.1e11, G=8.1e10, rho=7850.0)
TUBE = Section(A=4.44e-4, Iy=1.02e-7, Iz=1.02e-7, J=1.6e-7)
#: stiffness-proportional damping ``C = BETA K``
BETA = 2e-5
#: the frequency grid (rad/s): 40 frequencies from 5 to 600 Hz
OMEGA = 2 * np.pi * np.linspace(5.0, 600.0, 40)

A_NODES = {1: (0.0, 0.0, 0.0), 2: (-0.4, 0.0, 0.0), 3: (-0.4, 0.3, 0.0), 4: (-0.4, 0.3, 0.25)}
A_BEAMS = [((1, 2), (0, 0, 1)), ((2, 3), (0, 0, 1)), ((3, 4), (1, 0, 0))]
B_NODES = {1: (0.0, 0.0, 0.0), 12: (0.5, 0.0, 0.0), 13: (0.5, 0.0, -0.3), 14: (0.5, 0.35, 0.0)}
B_BEAMS = [((1, 12), (0, 0, 1)), ((12, 13), (1, 0, 0)), ((12, 14), (0, 0, 1))]
B_SUPPORTS = {13: None}


def _frame(name: str, nodes: dict, beams: list, supports: dict | None) -> Substructure:
    members = [Beam(ends, TUBE, STEEL, orient, divisions=3) for ends, orient in beams]
    return frame(name, nodes, members, supports=supports)


def part_a() -> Substructure:
    return _frame("A", A_NODES, A_BEAMS, None)


def part_b() -> Substructure:
    return _frame("B", B_NODES, B_BEAMS, B_SUPPORTS)


def assembly() -> Substructure:
    return _frame("AB", {**A_NODES, **B_NODES}, A_BEAMS + B_BEAMS, B_SUPPORTS)


def _rotation(seed: int) -> np.ndarray:
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return q * np.sign(np.diag(r))[None, :]


def adapter_rows(prefix: str, centre: tuple[float, float, float], seed: int) -> list[dict]:
    """Three triaxial sensors and nine impacts on a 50 mm cube around ``centre``."""
    c = np.asarray(centre)
    rows = []
    spots = [(0.025, 0.012, -0.008), (-0.01, 0.025, 0.015), (0.005, -0.014, 0.025)]
    for s, spot in enumerate(spots):
        axes = _rotation(seed + s)
        for a, axis in enumerate("xyz"):
            rows.append(_row(f"{prefix}S{s + 1}{axis}", "1", c + spot, axes[:, a], "sensor"))
    h = 0.025
    hits = [((h, 0.01, 0.012), (-1, 0, 0)), ((h, -0.012, -0.01), (-1, 0, 0)),
            ((-0.011, h, 0.009), (0, -1, 0)), ((0.013, h, -0.012), (0, -1, 0)),
            ((0.01, -0.012, h), (0, 0, -1)), ((-0.013, 0.01, h), (0, 0, -1)),
            ((-h, 0.012, -0.013), (1, 0, 0)), ((0.012, -h, 0.011), (0, 1, 0)),
            ((-0.009, 0.013, -h), (0, 0, 1))]
    for k, (spot, d) in enumerate(hits):
        rows.append(_row(f"{prefix}H{k + 1}", "1", c + spot, d, "impact"))
    return rows


def _row(name: str, node: str, xyz, d, kind: str) -> dict:
    return {"name": name, "node": node, "x": float(xyz[0]), "y": float(xyz[1]),
            "z": float(xyz[2]), "dx": float(d[0]), "dy": float(d[1]), "dz": float(d[2]),
            "kind": kind}


def node_rows(name: str, sub: Substructure, node: int, d, kind: str) -> dict:
    return _row(name, str(node), sub.position(f"{node}:ux"), d, kind)


def channel_matrix(sub: Substructure, table: ChannelTable, names: list[str],
                   node_of: dict[str, int]) -> sp.csr_array:
    """Rows ``[e, (r - r_N) x e]`` on the node's six coordinates, one per channel."""
    rows = []
    for name in names:
        ch = table.get(name)
        node = node_of.get(name, int(ch.node))
        d = np.asarray(ch.position) - sub.position(f"{node}:ux")
        coef = np.concatenate([ch.direction, np.cross(d, ch.direction)])
        row = sp.csr_array((1, sub.K.shape[0]))
        for c, comp in enumerate(("ux", "uy", "uz", "rx", "ry", "rz")):
            if coef[c] != 0.0:
                row = row + coef[c] * sub.locate(f"{node}:{comp}")
        rows.append(row)
    return sp.csr_array(sp.vstack(rows))


def receptance(sub: Substructure, outputs: sp.csr_array, inputs: sp.csr_array,
               omega: np.ndarray = OMEGA) -> np.ndarray:
    """``outputs (K - w^2 M + i w BETA K)^{-1} inputs^T`` on the grid (``kkt``)."""
    return receptance_sweep(sub.K, sub.M, BETA * sub.K, None, omega,
                            sp.csr_array(inputs).T, outputs, method="kkt").H


def node_dofs(sub: Substructure, node: int) -> sp.csr_array:
    """The six rows of a node's coordinates."""
    return sp.csr_array(sp.vstack([sub.locate(f"{node}:{c}")
                                   for c in ("ux", "uy", "uz", "rx", "ry", "rz")]))


@dataclass
class Measured:
    """A part's table and its receptances from ``impacts`` (columns) to ``sensors``."""

    table: ChannelTable
    sensors: list[str]
    impacts: list[str]
    Y: np.ndarray


def measure(sub: Substructure, rows: list[dict], omega: np.ndarray = OMEGA) -> Measured:
    """The "measured" receptances of every channel in ``rows`` (sensors x impacts)."""
    table = parse_channels(rows, sub.name)
    sensors = [c.name for c in table.of_kind("sensor")]
    impacts = [c.name for c in table.of_kind("impact")]
    S = channel_matrix(sub, table, sensors, {})
    F = channel_matrix(sub, table, impacts, {})
    return Measured(table, sensors, impacts, receptance(sub, S, F, omega))
