"""Every option of every command is documented where a user looks for it.

The options are read from the parser itself (what ``substruct <command> --help`` lists), so
a new option fails here until it is written down: in the command's row of README's command
table, or in a paragraph, table or code block of the command's own docs page that names the
command (``substruct <command>``).  Options with a fixed set of values (``--format``,
``--reference``) must show each value there too.
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

from substruct.cli.arguments import COMMANDS, build_parser

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
#: The docs pages of each command (besides README's command table).
PAGES = {"run": ["case-files.md", "results.md", "transient.md"],
         "converge": ["convergence.md"], "study": ["studies.md"], "info": ["results.md"],
         "export": ["results.md", "frf.md", "transient.md"], "compare": ["results.md"]}


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


def _blocks(text: str) -> list[str]:
    """Paragraphs, tables and fenced code blocks (separated by blank lines outside fences)."""
    out: list[str] = []
    cur: list[str] = []
    fence = False
    for line in text.splitlines():
        if line.startswith("```"):
            fence = not fence
        if line.strip() or fence:
            cur.append(line)
        elif cur:
            out.append("\n".join(cur))
            cur = []
    return out + (["\n".join(cur)] if cur else [])


def _row(command: str) -> list[str]:
    return [line for line in README.splitlines() if line.startswith(f"| `substruct {command} ")]


def _where(command: str) -> list[str]:
    """README's row of the command and the blocks of its pages that name it."""
    blocks = [b for page in PAGES[command]
              for b in _blocks((ROOT / "docs" / page).read_text(encoding="utf-8"))
              if f"substruct {command}" in b]
    return _row(command) + blocks


def _mentioned(word: str, texts: list[str]) -> bool:
    pattern = re.compile(r"(?<![A-Za-z0-9-])" + re.escape(word) + r"(?![A-Za-z0-9-])")
    return any(pattern.search(t) for t in texts)


def _options(command: str) -> list[argparse.Action]:
    return [a for a in _subparsers()[command]._actions
            if a.option_strings and "--help" not in a.option_strings]


def test_every_command_has_a_row_in_readme_and_pages():
    commands = _subparsers()
    assert sorted(commands) == sorted(COMMANDS) == sorted(PAGES)
    for command in commands:
        assert len(_row(command)) == 1, command
        for page in PAGES[command]:
            assert (ROOT / "docs" / page).is_file(), page


def test_the_top_level_usage_names_every_command():
    usage = build_parser().format_help()
    for command in COMMANDS:
        assert _mentioned(command, [usage]), command


@pytest.mark.parametrize("command", sorted(PAGES))
def test_every_option_is_documented(command):
    where = _where(command)
    missing = [a.option_strings[-1] for a in _options(command)
               if not any(_mentioned(o, where) for o in a.option_strings)]
    assert not missing, f"substruct {command}: {missing} in no doc of the command"
    assert _options(command), command  # the parser was read


@pytest.mark.parametrize("command", sorted(PAGES))
def test_every_value_of_a_choice_is_documented(command):
    where = _where(command)
    missing = [(a.option_strings[-1], c) for a in _options(command) if a.choices
               for c in a.choices if not _mentioned(str(c), where)]
    assert not missing, f"substruct {command}: {missing} in no doc of the command"


def test_readme_usage_lines_name_no_option_the_parser_lacks():
    """The other direction: an option written in a README usage line exists."""
    for command in PAGES:
        known = {o for a in _options(command) for o in a.option_strings}
        for word in re.findall(r"(?<![A-Za-z0-9-])--[a-z][a-z0-9-]*", _row(command)[0]):
            assert word in known, (command, word)
