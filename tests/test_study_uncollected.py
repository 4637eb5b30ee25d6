"""A study refuses an analysis that no ``collect`` entry reads (random, base_frf, transient,
srs, tpa, semm): each sample would compute it and throw it away, silently.  One line naming
the field, exit 2, nothing written; ``substruct run`` of the same case still runs it."""

import pytest

from cli_helpers import assert_one_line_error, run

CASE = """name: uncollected
parameters: {k: 8.0e+5}
substructures:
  - {name: a, type: free-free, mass: 2.0, stiffness: k, damping: 40.0}
constraints:
  - {name: table, terms: {a@boundary: 1}}
analysis:
  modes: {count: 1}
EXTRA
study:
  grid:
    parameters:
      - {parameter: k, values: [8.0e+5, 9.0e+5]}
  collect: {frequencies: 1}
output: {pictures: false}
"""

EXTRAS = {
    "random": """  random:
    frequencies: {start: 1, stop: 10000, num: 1000, spacing: log}
    base: {at: [a@boundary], psd: [[1, 1.0], [10000, 1.0]]}
    outputs: [a@mass]""",
    "base_frf": """  base_frf:
    omega: {start: 10, stop: 1000, num: 50}
    base: {at: [a@boundary]}
    outputs: [a@mass]""",
    "transient": """  transient:
    t_end: 0.01
    dt: 1.0e-4
    loads:
      - {point: a@mass, amplitude: 1.0}
    outputs: [a@mass]""",
}


@pytest.mark.parametrize("key", sorted(EXTRAS))
def test_study_refuses_an_analysis_it_does_not_collect(capsys, tmp_path, key):
    path = tmp_path / "uncollected.yaml"
    path.write_text(CASE.replace("EXTRA", EXTRAS[key]))
    code, out, err = run(capsys, "study", path, "--out", tmp_path / "out")
    assert_one_line_error(code, out, err, f"analysis.{key}: a study collects nothing of it")
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
    # the study runs once the analysis is left out (on the command line)
    code, out, err = run(capsys, "study", path, "--out", tmp_path / "out",
                         "--set", f"analysis.{key}=null")
    assert code == 0, err
    # and the case itself still runs it
    code, out, err = run(capsys, "run", path, "--out", tmp_path / "run")
    assert code == 0, err
