"""Case files: Craig-Bampton solids with ``interface_degree`` tied through their interface
bases, converging from above to the unreduced case as the degree grows; the bad value."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from cli_helpers import run
from substruct.case.loader import parse_case
from substruct.run.runner import build_model, run_case

ROOT = Path(__file__).resolve().parent.parent


def case(reduce: str = "null") -> str:
    return f"""\
name: three_boxes
substructures:
  - name: left
    type: solid
    box: {{lengths: [1.0, 0.3, 0.3], divisions: [6, 3, 3]}}
    E: 2.1e11
    nu: 0.3
    rho: 7850
    fixed: [xmin]
    reduce: {reduce}
  - name: middle
    type: solid
    box: {{lengths: [1.0, 0.3, 0.3], divisions: [6, 3, 3], origin: [1, 0, 0]}}
    E: 2.1e11
    nu: 0.3
    rho: 7850
    reduce: {reduce}
  - name: right
    type: solid
    box: {{lengths: [1.0, 0.3, 0.3], divisions: [6, 3, 3], origin: [2, 0, 0]}}
    E: 2.1e11
    nu: 0.3
    rho: 7850
    reduce: {reduce}
  - {{name: tmd, type: free-free, mass: 5.0, stiffness: 2.0e6}}
interfaces:
  - {{name: a, between: [left, middle], nodes: {{box: [[1, 0, 0], [1, 0.3, 0.3]]}}}}
  - {{name: b, between: [middle, right], nodes: {{box: [[2, 0, 0], [2, 0.3, 0.3]]}}}}
connections:
  - ["right@3,0.1,0.3:z", tmd]
analysis:
  modes: {{count: 8, solver: sparse, check: []}}
output: {{pictures: false}}
"""


def omega(text: str) -> np.ndarray:
    return run_case(parse_case(text, "three.yaml", ROOT)).modes.omega


def test_interface_degree_converges_from_above():
    """Largest relative error of the 8 lowest frequencies falls as the interface degree grows
    (10 fixed-interface modes a part; p = 3 adds only fields odd across the section, which
    these modes hardly use); every frequency above the unreduced one; the reduced
    solids have g + 3 (p+1)(p+2)/2 coordinates per interface (+1 for the absorber's point)."""
    exact = omega(case())
    errors = []
    for p in (0, 1, 2, 4):
        text = case(f"{{method: craig-bampton, modes: 10, interface_degree: {p}}}")
        w = omega(text)
        assert np.all(w >= exact * (1 - 1e-10)), (p, w, exact)
        errors.append(np.max((w - exact) / exact))
        model = build_model(parse_case(text, "three.yaml", ROOT))
        sizes = [s.n_dof for s in model.assembly.substructures[:3]]
        # (p+1)(p+2)/2 fields a component, less s^4 and t^4 at p = 4: on 4 x 4 nodes they
        # equal cubics
        r = 3 * ((p + 1) * (p + 2) // 2 - (2 if p == 4 else 0))
        assert sizes == [10 + r, 10 + 2 * r, 10 + r + 1], sizes
    assert all(a > b for a, b in zip(errors, errors[1:])), errors
    assert errors[0] > 0.1 and errors[-1] < 1e-3, errors


def test_substruct_run_with_interface_degree(tmp_path, capsys):
    path = tmp_path / "three.yaml"
    path.write_text(case("{method: craig-bampton, modes: 10, interface_degree: 2}"))
    code, out, err = run(capsys, "run", path, "--out", tmp_path)
    assert code == 0, err
    assert "8 physical mode(s)" in out


def test_interface_degree_with_modal_truncation_is_a_one_line_error(tmp_path, capsys):
    path = tmp_path / "bad.yaml"
    path.write_text(case("{modes: 10, interface_degree: 2}"))
    code, _, err = run(capsys, "run", path, "--out", tmp_path)
    assert code == 2 and "interface_degree" in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1, err
