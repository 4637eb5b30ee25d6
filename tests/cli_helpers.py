"""Running the substruct command in-process, and what a bad-input answer must look like."""

import signal

from substruct import cli


def run(capsys, *args):
    """``(exit code, stdout, stderr)`` of ``substruct ARGS`` run in this process."""
    code = cli.main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_line_error(code, out, err, *fragments):
    """Exit code 2, one line on stderr naming the problem, nothing on stdout, no traceback."""
    assert code == 2, err
    assert err.startswith("substruct: error: ") and err.count("\n") == 1, err
    assert "Traceback" not in err and out == ""
    for fragment in fragments:
        assert fragment in err, err


def default_ctrl_c() -> None:
    """Ctrl-C back to its default in a child process (``preexec_fn``): a test session started
    in the background by a shell without job control (``make test &`` in a script) ignores
    SIGINT, and a child would inherit that."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


#: The ``substructures:`` block of the paper's three-mass model with a dashpot on the first
#: mass (eq 40's matrices), for case texts built in tests.
DAMPED_THREE_MASS = """\
substructures:
  - name: P
    type: matrices
    M: [[1, 0, 0], [0, 2, 0], [0, 0, 4]]
    K: [[20, -10, 0], [-10, 30, -20], [0, -20, 20]]
    C: [[10, 0, 0], [0, 0, 0], [0, 0, 0]]
"""
