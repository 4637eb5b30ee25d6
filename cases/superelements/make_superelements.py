"""Write the Craig-Bampton superelements of ``cases/two_superelements.yaml``, a coupled loads
example: a steel tube adapter (grid 1 at the launcher interface, grid 2 at the top), a stiffer
variant of it (``adapter_stiff``: a thicker wall, 1.5 times the section, for ``substruct
compare``), and a spacecraft (a mast from grid 100 with a 400 kg payload at grid 101 and an arm
to a 60 kg tip at grid 102).

Each is reduced by substruct's own Craig-Bampton (free, boundary grids kept, fixed-interface
modes, :math:`q = T [\\eta; x_b]`) with Rayleigh damping :math:`C = a M + b K` projected,
:math:`T^T C T`, and written as OP4 (adapters in binary, the spacecraft in text) with CSV DOF
maps.  The spacecraft carries output transformation matrices, built from the same ``T``:

* ``ATM`` (``ATMROWS``: grid, component): the accelerations of grids 101 and 102, the rows of
  ``T`` at them, acting on the accelerations;
* ``LTM`` (mode displacement): the end forces at grid 100 of the mast's first element,
  ``K_e[0:6] T_e``, in global axes;
* ``IFLTM``: the force the adapter applies to the spacecraft at grid 100, the boundary rows of
  the reduced equation, ``[M_b C_b K_b]`` acting on ``[a v x]``.

Deterministic: the same models, the same files (to the rounding of the eigensolver). Run
from the repository root: ``python cases/superelements/make_superelements.py``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from substruct.io.op4 import write_op4
from substruct.models.beam import Material, Section, beam_matrices
from substruct.models.craig_bampton import craig_bampton
from substruct.models.frame import FRAME_COMPONENTS, Beam, frame

HERE = Path(__file__).resolve().parent
STEEL = Material(E=2.1e11, G=8.1e10, rho=7850.0)
ALU = Material(E=7.0e10, G=2.6e10, rho=2700.0)
TUBE = Section(A=1.2e-2, Iy=1.5e-4, Iz=1.5e-4, J=3.0e-4)
TUBE_STIFF = Section(A=1.8e-2, Iy=2.25e-4, Iz=2.25e-4, J=4.5e-4)
MAST = Section(A=8.0e-3, Iy=8.0e-5, Iz=8.0e-5, J=1.6e-4)
MAST_NODES = {100: (0.0, 0.0, 1.2), 101: (0.0, 0.0, 3.2), 102: (1.0, 0.0, 2.6)}
#: Rayleigh damping C = a M + b K: 2 % of critical at 8 Hz and 80 Hz.
RAYLEIGH = (2 * 0.02 * (2 * np.pi * 8) * (2 * np.pi * 80) / (2 * np.pi * 88),
            2 * 0.02 / (2 * np.pi * 88))
#: Fixed-interface modes kept.
MODES = {"adapter": 6, "spacecraft": 12}
#: Interior grids whose accelerations the spacecraft's ATM recovers.
ATM_GRIDS = (101, 102)


def adapter_model(section: Section = TUBE):
    """The adapter: a steel tube from grid 1 (0, 0, 0) to grid 2 (0, 0, 1.2), 8 elements."""
    return frame("adapter", {1: (0, 0, 0), 2: (0, 0, 1.2)},
                 [Beam((1, 2), section, STEEL, (1, 0, 0), divisions=8)])


def spacecraft_model():
    """The spacecraft: an aluminium mast 100-101 (10 elements) with 400 kg at 101 and an arm
    102-101 (6 elements) with 60 kg at 102.  Node 103 is the mast's first division."""
    return frame("spacecraft", MAST_NODES,
                 [Beam((100, 101), MAST, ALU, (1, 0, 0), divisions=10),
                  Beam((102, 101), MAST, ALU, (0, 0, 1), divisions=6)],
                 node_masses={101: 400.0, 102: 60.0})


def mast_root_stiffness() -> np.ndarray:
    """12 x 12 global stiffness of the mast's first element, grid 100 to node 103."""
    a, b = np.array(MAST_NODES[100]), np.array(MAST_NODES[101])
    K, _ = beam_matrices(a, a + (b - a) / 10, (1, 0, 0), MAST, ALU)
    return K


def damping(sub) -> np.ndarray:
    """Rayleigh damping of a model, dense."""
    return RAYLEIGH[0] * sub.M.toarray() + RAYLEIGH[1] * sub.K.toarray()


def reduce(sub, boundary: tuple[int, ...], modes: int):
    """Craig-Bampton of ``sub`` at the grids ``boundary``: the reduced model and ``T`` (full
    coordinates x reduced ones, ``row_full @ T = row_reduced``)."""
    b = [k for k, lab in enumerate(sub.dof_labels) if int(lab.split(":")[0]) in boundary]
    red = craig_bampton(sub, b, modes)
    T = np.vstack([red.row(lab).toarray().ravel() for lab in sub.dof_labels])
    return red, T


def dof_rows(labels) -> np.ndarray:
    """``grid, component`` per coordinate label (``eta<k>``: ``0, 0``)."""
    rows = []
    for lab in labels:
        if lab.startswith("eta"):
            rows.append((0, 0))
        else:
            g, c = lab.split(":")
            rows.append((int(g), FRAME_COMPONENTS.index(c) + 1))
    return np.array(rows, dtype=float)


def _write_csv(path: Path, table: np.ndarray) -> None:
    lines = ["grid,component"] + [f"{9000 + k if c == 0 else int(g)},{int(c)}"
                                  for k, (g, c) in enumerate(table)]
    path.write_text("\n".join(lines) + "\n")


def spacecraft_matrices(sub, red, T) -> dict[str, np.ndarray]:
    """MAA, KAA, BAA of the reduced spacecraft and its recovery matrices (module docstring)."""
    labels = list(sub.dof_labels)
    M, K = red.M.toarray(), red.K.toarray()
    C = T.T @ damping(sub) @ T
    rows = [labels.index(f"{g}:{c}") for g in ATM_GRIDS for c in FRAME_COMPONENTS[:3]]
    elem = [labels.index(f"{g}:{c}") for g in (100, 103) for c in FRAME_COMPONENTS]
    bnd = [list(red.dof_labels).index(f"100:{c}") for c in FRAME_COMPONENTS]
    return {"MAA": M, "KAA": K, "BAA": C, "ATM": T[rows],
            "ATMROWS": np.array([(g, c) for g in ATM_GRIDS for c in (1, 2, 3)], float),
            "LTM": mast_root_stiffness()[:6] @ T[elem],
            "IFLTM": np.hstack([M[bnd], C[bnd], K[bnd]])}


def write_all(out: Path = HERE) -> None:
    """Write adapter.op4, adapter_stiff.op4, spacecraft.op4 and their CSV maps in ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    for stem, section in (("adapter", TUBE), ("adapter_stiff", TUBE_STIFF)):
        sub = adapter_model(section)
        red, T = reduce(sub, (1, 2), MODES["adapter"])
        write_op4(out / f"{stem}.op4", {"MAA": red.M.toarray(), "KAA": red.K.toarray(),
                                         "BAA": T.T @ damping(sub) @ T}, binary=True)
        _write_csv(out / f"{stem}.csv", dof_rows(red.dof_labels))
    sub = spacecraft_model()
    red, T = reduce(sub, (100,), MODES["spacecraft"])
    write_op4(out / "spacecraft.op4", spacecraft_matrices(sub, red, T))
    _write_csv(out / "spacecraft.csv", dof_rows(red.dof_labels))


if __name__ == "__main__":
    write_all(Path(sys.argv[1]) if len(sys.argv) > 1 else HERE)
