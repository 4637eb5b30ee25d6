"""Write the two Craig-Bampton superelements of ``cases/two_superelements.yaml``: a steel tube
adapter (grids 1 at the launcher interface and 2 at the top) and a spacecraft (a mast from
grid 100 with a 400 kg payload and a 60 kg arm tip), each reduced by substruct's own
Craig-Bampton (free, boundary grids kept, fixed-interface modes), written as OP4 (the adapter
in binary, the spacecraft in text) with CSV DOF maps.  Run from the repository root:
``python cases/superelements/make_superelements.py``."""

from pathlib import Path

from substruct.io.op4 import write_op4
from substruct.models.beam import Material, Section
from substruct.models.craig_bampton import craig_bampton
from substruct.models.frame import FRAME_COMPONENTS, Beam, frame

HERE = Path(__file__).resolve().parent
STEEL = Material(E=2.1e11, G=8.1e10, rho=7850.0)
ALU = Material(E=7.0e10, G=2.6e10, rho=2700.0)
TUBE = Section(A=1.2e-2, Iy=1.5e-4, Iz=1.5e-4, J=3.0e-4)
MAST = Section(A=4.0e-3, Iy=1.2e-5, Iz=1.2e-5, J=2.4e-5)


def write(sub, boundary, modes, stem, **layout):
    b = [k for k, lab in enumerate(sub.dof_labels) if int(lab.split(":")[0]) in boundary]
    red = craig_bampton(sub, b, modes)
    write_op4(HERE / f"{stem}.op4", {"MAA": red.M.toarray(), "KAA": red.K.toarray()},
              **layout)
    rows = ["grid,component"]
    for k, lab in enumerate(red.dof_labels):
        if lab.startswith("eta"):
            rows.append(f"{9000 + k},0")
        else:
            g, c = lab.split(":")
            rows.append(f"{g},{FRAME_COMPONENTS.index(c) + 1}")
    (HERE / f"{stem}.csv").write_text("\n".join(rows) + "\n")


adapter = frame("adapter", {1: (0, 0, 0), 2: (0, 0, 1.2)},
                [Beam((1, 2), TUBE, STEEL, (1, 0, 0), divisions=8)])
write(adapter, (1, 2), 6, "adapter", binary=True)
spacecraft = frame("spacecraft", {100: (0, 0, 1.2), 101: (0, 0, 3.2), 102: (1.0, 0, 2.6)},
                   [Beam((100, 101), MAST, ALU, (1, 0, 0), divisions=10),
                    Beam((102, 101), MAST, ALU, (0, 0, 1), divisions=6)],
                   node_masses={101: 400.0, 102: 60.0})
write(spacecraft, (100,), 12, "spacecraft")
