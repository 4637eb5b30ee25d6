"""Write the malformed Ansys FULL files of the bad-input corpus (``tests/bad_cases/data/
ansys_*.full``) from the first 600 words of ``file.full`` (its standard and FULL headers, DOF
labels, nodal equivalence table and first stiffness columns), each with one defect.  Run by
hand from the repository root: ``python tests/data/ansys/make_bad_files.py``."""

from pathlib import Path

import numpy as np

HERE = Path(__file__).parent
OUT = HERE.parent.parent / "bad_cases" / "data"
FULL = 105                       # the first word of the FULL header's data (its item 1)


def main() -> None:
    words = np.fromfile(HERE / "file.full", "<i4")[:600].copy()
    edits = {"truncated": {},                        # the DOF table lies beyond the end
             "reclen": {206 + 2 + 3: 4},             # DOF labels: 3 words, ends with 4
             "huge": {FULL + 1: 900_000_000},        # neqn
             "lumped": {FULL + 10: 1}}               # lumpm
    for name, edit in edits.items():
        w = words.copy()
        for k, v in edit.items():
            w[k] = v
        w.tofile(OUT / f"ansys_{name}.full")


if __name__ == "__main__":
    main()
