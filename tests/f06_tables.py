"""Tables read from an MSC Nastran F06 (the printed output): real eigenvalues, real
eigenvectors and element strain energies, for tests against Nastran's own results."""

from __future__ import annotations

import re

import numpy as np

_NUMBER = r"[-+]?\d*\.\d+E[-+]\d+"


def f06_tables(text: str) -> tuple[list[float], dict[int, dict[int, list[float]]],
                                   dict[int, dict[int, float]]]:
    """``(eigenvalues, vectors, energies)``: the EIGENVALUE column of R E A L   E I G E N V A
    L U E S; per mode, grid id -> ``[T1, T2, T3, R1, R2, R3]``; per mode, element id -> its
    STRAIN-ENERGY (E L E M E N T   S T R A I N   E N E R G I E S, every element type)."""
    lines = text.splitlines() + [""]
    eig: list[float] = []
    vecs: dict[int, dict[int, list[float]]] = {}
    ese: dict[int, dict[int, float]] = {}
    for i, ln in enumerate(lines):
        if "R E A L   E I G E N V A L U E S" in ln:
            j = i + 3
            while re.match(rf"^\s+\d+\s+\d+\s+{_NUMBER}", lines[j]):
                eig.append(float(lines[j].split()[2]))
                j += 1
        m = re.search(r"R E A L   E I G E N V E C T O R   N O \.\s+(\d+)", ln)
        if m:
            grids = vecs.setdefault(int(m.group(1)), {})
            j = i + 3
            while re.match(r"^\s+\d+\s+G\s", lines[j]):
                p = lines[j].split()
                grids[int(p[0])] = [float(x) for x in p[2:8]]
                j += 1
        if "E L E M E N T   S T R A I N   E N E R G I E S" in ln:
            energies = ese.setdefault(int(lines[i + 3].split()[1]), {})
            j = i + 4
            while "SUBTOTAL" not in lines[j] and j < len(lines) - 1:
                if re.match(rf"^\s+\d+\s+{_NUMBER}\s+\S+\s+{_NUMBER}", lines[j]):
                    p = lines[j].split()
                    energies[int(p[0])] = float(p[1])
                j += 1
    return eig, vecs, ese


def printed_half_unit(values: np.ndarray, digits: int = 7) -> np.ndarray:
    """Half a unit in the last place of ``values`` printed with ``digits`` significant digits
    (``d.ddddddE+xx``): the largest rounding error of each printed value (0 for a printed 0)."""
    v = np.abs(np.asarray(values, dtype=float))
    out = np.zeros_like(v)
    nz = v > 0
    out[nz] = 0.5 * 10.0 ** (np.floor(np.log10(v[nz])) - (digits - 1))
    return out
