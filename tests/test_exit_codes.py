"""Exit codes of the substruct command: 2 only for bad input, 1 for a failed cross-check or an
internal failure, each with one line that says which; nothing written either way."""

from pathlib import Path

import pytest

import substruct.run.runner
from substruct.analysis.errors import CheckError

from cli_helpers import run

CASES = Path(__file__).resolve().parents[1] / "cases"
NO_PICTURES = ("--set", "output.pictures=false")


def _run(capsys, tmp_path, *extra):
    out = tmp_path / "out"
    code, stdout, stderr = run(capsys, "run", CASES / "three_dof_frf.yaml", "--out", out, *extra)
    return code, stdout, stderr, out


def test_failed_cross_check_is_exit_1_one_line_and_writes_nothing(tmp_path, capsys,
                                                                  monkeypatch):
    message = ("modes: null-space and kkt disagree with generalized-inverse by 8.0e-01 "
               "(tolerance 1e-06; raise analysis.modes.tolerance to accept)")

    def disagree(*args, **kwargs):
        raise CheckError(message)
    monkeypatch.setattr(substruct.run.runner, "run_case", disagree)
    code, stdout, stderr, out = _run(capsys, tmp_path)
    assert code == 1
    assert stderr == f"substruct: error: {message}\n"
    assert stdout == ""
    assert not out.exists() or not any(out.iterdir())


def test_internal_failure_is_exit_1_with_a_closing_one_line_message(tmp_path, capsys,
                                                                   monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("ARPACK error -9999:\n  no convergence")
    monkeypatch.setattr(substruct.run.runner, "run_case", broken)
    code, stdout, stderr, out = _run(capsys, tmp_path, *NO_PICTURES)
    assert code == 1
    last = stderr.splitlines()[-1]
    assert last == ("substruct: internal error: RuntimeError: ARPACK error -9999: no "
                    "convergence (a bug in substruct, not in the input; the traceback above "
                    "says where)")
    assert stdout == ""
    assert not out.exists() or not any(out.iterdir())


@pytest.mark.parametrize("exc", [KeyError("omega"), IndexError("index 7 is out of bounds"),
                                 ZeroDivisionError("float division by zero"),
                                 AssertionError()])
def test_any_unexpected_exception_is_exit_1_never_2(tmp_path, capsys, monkeypatch, exc):
    def broken(*args, **kwargs):
        raise exc
    monkeypatch.setattr(substruct.run.runner, "run_case", broken)
    code, _, stderr, _ = _run(capsys, tmp_path, *NO_PICTURES)
    assert code == 1
    assert stderr.splitlines()[-1].startswith(
        f"substruct: internal error: {type(exc).__name__}")


def test_bad_input_is_still_exit_2(tmp_path, capsys):
    code, stdout, stderr = run(capsys, "run", tmp_path / "missing.yaml", "--out", tmp_path)
    assert code == 2 and stderr.startswith("substruct: error: ") and stderr.count("\n") == 1
    assert stdout == ""
