"""The bad-input corpus (tests/bad_cases/) through the real command line.

Every case file must end ``substruct run`` with exit code 2 and exactly one line on stderr,
``substruct: error: <file>: <field.path>: <problem>, got <value>``, containing the fragment its
``# expect:`` header promises; no traceback; nothing in the output directory.  docs/errors.md is
generated from the corpus and must be in sync with it.
"""

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from substruct import cli

ROOT = Path(__file__).resolve().parent.parent
CASES = ROOT / "cases"
_spec = importlib.util.spec_from_file_location("bad_cases_make_table",
                                               ROOT / "tests" / "bad_cases" / "make_table.py")
make_table = importlib.util.module_from_spec(_spec)
sys.modules.setdefault("bad_cases_make_table", make_table)
_spec.loader.exec_module(make_table)

CORPUS = make_table.corpus()
#: A field path (``substructures.rod.length``, ``connections[0][1]``,
#: ``constraints.c1.terms``, a quoted key ``'a b'``), one given on the command line
#: (``--set analysis.frf.omega``) or a place in the file (``line 3, column 7``).
FIELD = re.compile(r"(--set )?(?:[A-Za-z_][\w.@\[\]-]*|'[^'\s]*')|line \d+, column \d+")


def files_in(directory: Path) -> list[Path]:
    return sorted(p for p in directory.rglob("*") if p.is_file()) if directory.exists() else []


def test_the_corpus_is_large_and_well_formed():
    assert len(CORPUS) >= 40
    names = [c.name for c in CORPUS]
    assert len(set(names)) == len(names)
    # every class of the issue is represented
    for prefix in ("yaml_", "key_", "type_", "missing_", "value_", "matrix_", "point_", "name_",
                   "constraint_", "modes_", "analysis_", "omega_", "expr_", "size_"):
        assert any(n.startswith(prefix) for n in names), prefix


@pytest.mark.parametrize("case", CORPUS, ids=lambda c: c.name)
def test_bad_case_is_one_line_exit_2_and_writes_nothing(case, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(ROOT)
    out = tmp_path / "out"
    code = cli.main(["run", case.path, "--out", str(out), *case.args])
    stdout, stderr = capsys.readouterr()
    assert code == 2, stderr
    assert stdout == ""
    assert stderr.endswith("\n") and stderr.count("\n") == 1, stderr
    line = stderr[:-1]
    assert "Traceback" not in line and "\r" not in line
    head = f"substruct: error: {case.path}: "
    assert line.startswith(head), line
    assert case.expect in line, f"expected {case.expect!r} in\n{line}"
    rest = line[len(head):]
    if case.has_field:
        field, sep, _ = rest.partition(": ")
        assert sep and FIELD.fullmatch(field), f"no field path in {line!r}"
    if case.has_value:
        assert ", got " in rest, f"no value in {line!r}"
    assert files_in(out) == [] and files_in(tmp_path) == []


def test_no_traceback_reaches_the_terminal(tmp_path):
    """One real process: the hostile expression is refused, nothing runs, one line."""
    case = "tests/bad_cases/expr_import.yaml"
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONPATH": str(ROOT)}
    proc = subprocess.run([sys.executable, "-m", "substruct.cli", "run", case, "--out",
                           str(tmp_path / "out")], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 2
    assert proc.stdout == ""  # 'echo owned' never ran
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    assert proc.stderr.startswith(f"substruct: error: {case}: substructures.rod.EA: call of")
    assert files_in(tmp_path) == []


def test_docs_errors_md_is_in_sync_with_the_corpus():
    expected = make_table.render(CORPUS, make_table.messages(CORPUS),
                                 make_table.other_messages())
    actual = (ROOT / "docs" / "errors.md").read_text(encoding="utf-8")
    assert actual == expected, "docs/errors.md is stale: run python tests/bad_cases/make_table.py"


# ------------------------------------------------------------- the output directory


def assert_refused(capsys, args, *fragments):
    code = cli.main([str(a) for a in args])
    stdout, stderr = capsys.readouterr()
    assert code == 2 and stdout == "", stderr
    assert stderr.startswith("substruct: error: ") and stderr.count("\n") == 1, stderr
    for fragment in fragments:
        assert fragment in stderr, stderr


def test_out_below_a_file_is_refused_before_computing(tmp_path, capsys):
    blocker = tmp_path / "somefile"
    blocker.write_text("keep me\n")
    assert_refused(capsys, ["run", CASES / "three_dof_frf.yaml", "--out", blocker / "sub"],
                   f"--out {blocker / 'sub'}: {blocker} is not a directory")
    assert_refused(capsys, ["run", CASES / "three_dof_frf.yaml", "--out", blocker],
                   f"--out {blocker} exists and is not a directory")
    assert files_in(tmp_path) == [blocker] and blocker.read_text() == "keep me\n"


def test_read_only_out_is_refused(tmp_path, capsys):
    out = tmp_path / "ro"
    out.mkdir()
    out.chmod(0o555)
    try:
        if os.access(out, os.W_OK):  # root (or a file system without permissions)
            pytest.skip("chmod does not stop this user from writing")
        assert_refused(capsys, ["run", CASES / "three_dof_frf.yaml", "--out", out],
                       f"--out {out} is not writable")
        assert_refused(capsys, ["run", CASES / "three_dof_frf.yaml", "--out", out / "new"],
                       f"--out {out / 'new'} is not writable")
        assert files_in(out) == []
    finally:
        out.chmod(0o755)


def test_unwritable_out_is_refused_even_as_root(tmp_path, capsys, monkeypatch):
    """The same refusal, with the permission error simulated (root ignores chmod)."""
    import tempfile

    def denied(*args, **kwargs):
        raise PermissionError(13, "Permission denied")
    monkeypatch.setattr(tempfile, "TemporaryFile", denied)
    out = tmp_path / "out"
    assert_refused(capsys, ["run", CASES / "three_dof_frf.yaml", "--out", out],
                   f"substruct: error: --out {out} is not writable (Permission denied)")
    assert files_in(tmp_path) == [] and not out.exists()


def test_an_earlier_picture_is_not_clobbered_without_force(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    old = out / "three_dof_frf_frf.png"
    old.write_bytes(b"an earlier picture")
    assert_refused(capsys, ["run", CASES / "three_dof_frf.yaml", "--out", out],
                   f"substruct: error: {old} exists; use --force to overwrite it")
    assert files_in(tmp_path) == [old] and old.read_bytes() == b"an earlier picture"
