"""The hostile command lines of ``docs/errors.md`` (:data:`make_table.OTHERS`: output paths,
corrupt results for ``info``, ``export`` and ``compare``, exports the result cannot give,
schedulers and ``study`` options): each is refused with exit code 2 and one line
``substruct: error: ...``, never a traceback, and leaves no output behind."""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "bad_cases"))

import make_table  # noqa: E402


def test_every_hostile_command_line_is_one_line_exit_2():
    rows = make_table.other_messages()
    assert len(rows) == len(make_table.OTHERS) >= 30
    for situation, shown, code, stderr in rows:
        assert code == 2, (situation, stderr)
        assert stderr.startswith("substruct: error: ") and "\n" not in stderr, (situation,
                                                                                stderr)
        assert "Traceback" not in stderr and "internal error" not in stderr, situation
