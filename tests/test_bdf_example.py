"""The shipped bulk data example ``cases/solid_bracket.bdf`` (a CHEXA block, a CBAR arm, an
RBE3 joint), run through the command line, against the same bracket written as a case file:
a ``type: solid`` block from substruct's own solid builder, a ``type: frame`` arm and an
``interpolation`` link on the same nine face nodes.  The two share no code on the way in
(bulk data reader and Nastran element matrices on one side, the case loader, the solid and
frame builders on the other), and their six frequencies agree to 1e-8.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from substruct import cli
from substruct.analysis.api import modes
from substruct.builder.model import assemble_case
from substruct.case.loader import load_case
from substruct.io.result_reader import load

BRACKET = Path(__file__).resolve().parents[1] / "cases" / "solid_bracket.bdf"
E, NU, RHO = 2.1e11, 0.3, 7850.0


def bracket_case() -> dict:
    """The bracket as a case file (the comments of ``solid_bracket.bdf`` describe it)."""
    face = [f"block@0.1,{y},{z}" for z in (0.05, 0.1, 0.15) for y in (0.05, 0.1, 0.15)]
    return {"name": "bracket", "substructures": [
        {"name": "block", "type": "solid",
         "box": {"lengths": [0.1, 0.2, 0.2], "divisions": [2, 4, 4]},
         "E": E, "nu": NU, "rho": RHO, "fixed": [{"box": [[-0.01, -1, -1], [0.01, 1, 1]]}]},
        {"name": "arm", "type": "frame", "nodes": {1: [0.1, 0.1, 0.1], 2: [1.1, 0.1, 0.1]},
         "materials": {"steel": {"E": E, "G": E / (2 * (1 + NU)), "rho": RHO}},
         "sections": {"bar": {"A": 1e-2, "Iy": 8.333333e-6, "Iz": 8.333333e-6,
                              "J": 1.406e-5}},
         "members": [{"nodes": [1, 2], "section": "bar", "material": "steel",
                      "orientation": [0, 1, 0], "divisions": 8}]}],
        "links": [{"type": "interpolation", "reference": "arm@1", "nodes": face}],
        "analysis": {"modes": {"count": 6}}}


def test_solid_bracket_runs_from_the_command_line_and_matches_the_case_file(tmp_path):
    out = tmp_path / "out"
    start = time.perf_counter()
    assert cli.main(["run", str(BRACKET), "--out", str(out), "--quiet", "--no-pictures"]) == 0
    took = time.perf_counter() - start
    omega = load(out / "solid_bracket.h5").modes.omega
    assert omega.size == 6
    asm = assemble_case(load_case(bracket_case())).assembly
    ref = modes(asm.M, None, asm.K, asm.A, 6).omega
    assert np.abs(omega / ref - 1).max() < 1e-8, (omega, ref)
    # the arm's two bending pairs first (the square section makes them double)
    assert abs(omega[1] / omega[0] - 1) < 1e-8 and abs(omega[3] / omega[2] - 1) < 1e-8
    assert took < 60  # generous for a shared machine; about 2 s alone


def test_the_default_hexahedron_of_the_bracket_is_softer(tmp_path):
    """With PSOLID's IN and ISOP blank (bubble functions) the block is more flexible, so
    every frequency falls, and by little: the arm, not the block, bends most."""
    text = BRACKET.read_text().replace("PSOLID,1,1,,2,,FULL", "PSOLID,1,1")
    path = tmp_path / "bubble.bdf"
    path.write_text(text)
    out = tmp_path / "out"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet", "--no-pictures"]) == 0
    soft = load(out / "bubble.h5").modes.omega
    full = load_full(tmp_path)
    assert np.all(soft < full)
    assert np.all(soft > 0.9 * full)


def load_full(tmp_path: Path) -> np.ndarray:
    out = tmp_path / "full"
    assert cli.main(["run", str(BRACKET), "--out", str(out), "--quiet", "--no-pictures"]) == 0
    return load(out / "solid_bracket.h5").modes.omega
