"""Warnings on the command line: one ``substruct: warning:`` line each, NumPy's floating-point
notices left out (:mod:`substruct.cli.warning_lines`).

Python shows a warning in two lines (where, and the source line); a factorization backend that
fails and falls back (PARDISO on an impedance singular to working precision: an undamped
model driven exactly at its resonance) warned that way, beside the program's own lines.
"""

from __future__ import annotations

import warnings

from cli_helpers import run
from substruct.cli.warning_lines import install_warning_lines

AT_RESONANCE = """\
name: at_resonance
substructures:
  - name: P
    type: matrices
    M: [[1, 0], [0, 1]]
    K: [[1, -1], [-1, 1]]
analysis:
  frf:
    omega: [1.4142135623730951]
    inputs: [P@1]
    outputs: [P@1, P@2]
output: {pictures: false}
"""


def test_every_stderr_line_is_the_programs_own(tmp_path, capsys):
    case = tmp_path / "r.yaml"
    case.write_text(AT_RESONANCE)
    code, out, err = run(capsys, "run", case, "--out", tmp_path / "out")
    assert code == 0
    for line in err.splitlines():
        assert line.startswith("substruct: warning: "), err


def test_a_warning_is_one_line_and_floating_point_notices_are_silent(capsys):
    with warnings.catch_warnings():
        install_warning_lines()
        warnings.warn("a backend\n fell back", RuntimeWarning)
        warnings.warn("invalid value encountered in divide", RuntimeWarning)
    _, err = capsys.readouterr()
    assert err == "substruct: warning: a backend fell back\n"
