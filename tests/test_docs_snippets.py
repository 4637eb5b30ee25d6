"""Every command and snippet of README.md and docs/*.md runs (issue 14): the docs cannot drift
from the program again.

The fenced code blocks of each page are extracted and, by kind:

* shell blocks: each line starting with ``substruct``, ``.venv/bin/substruct`` (optionally
  after ``$`` and environment assignments) is run through :func:`substruct.cli.main` and must
  exit 0; a line starting with ``python`` runs in a subprocess.  In a ``$`` block (a command
  followed by what it prints) every printed line shown must appear in the output;
* ``python`` blocks: executed in order, one namespace per page (a page is one session);
* ``yaml`` blocks holding a whole case (``name`` and ``substructures`` at the top) are loaded
  with :func:`substruct.load_case` and built; other ``yaml`` blocks are schema fragments and
  must at least be valid YAML.

Each page runs in a fresh directory holding ``cases/`` and ``meshes/`` of the project and the
result files that ``make run`` leaves in ``results/``, so relative paths work and nothing is
written into the project.  ``substruct run`` commands get ``--set output.pictures=false``
(pictures are not what they show), ``substruct converge`` commands ``--levels quick`` (the
default study is run by ``tests/test_converge_cli.py``).  A block preceded by ``<!-- docs-test: skip ... -->`` is
illustrative only (a synopsis, a schema with elided values); such exceptions are few and
counted here.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest
import yaml

from substruct import cli

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
SKIP = "<!-- docs-test: skip"
FENCE = re.compile(r"^```(\w*)\s*$")
COMMAND = re.compile(r"^(?:\$\s+)?(?:[A-Z_]+=\S+\s+)*(\.venv/bin/substruct|substruct|python)\s")
#: Blocks the pages mark as illustrative only; more is a sign of docs that cannot run.
MAX_SKIPPED = 4


@dataclass
class Block:
    """One fenced block of a page."""

    page: str
    line: int
    lang: str
    text: str
    skip: bool


def blocks(page: Path) -> list[Block]:
    """The fenced blocks of a Markdown page, with the language tag and the skip marker."""
    lines = page.read_text().split("\n")
    out, i = [], 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if m:
            j = i + 1
            while not lines[j].startswith("```"):
                j += 1
            skip = i > 0 and any(lines[k].startswith(SKIP) for k in range(max(i - 2, 0), i))
            out.append(Block(page.name, i + 1, m.group(1), "\n".join(lines[i + 1:j]), skip))
            i = j
        i += 1
    return out


def workspace(tmp: Path) -> Path:
    """A directory like a checkout: cases, meshes and an empty results/."""
    for name in ("cases", "meshes"):
        (tmp / name).symlink_to(ROOT / name)
    (tmp / "results").mkdir()
    return tmp


#: The cases ``make run`` runs into ``results/``.
MADE = ("tapered_rod", "tapered_rod_table1", "three_dof_frf")


@pytest.fixture(scope="module")
def made(tmp_path_factory) -> Path:
    """The result files ``make run`` leaves in ``results/`` (computed once)."""
    out = tmp_path_factory.mktemp("made")
    for name in MADE:
        assert cli.main(["run", str(ROOT / "cases" / f"{name}.yaml"), "--out", str(out),
                         "--quiet", "--set", "output.pictures=false"]) == 0
    return out


def run_command(line: str, capsys) -> str:
    """Run one documented command line; return what it printed (stdout)."""
    words = shlex.split(line.lstrip("$ "), comments=True)
    while words and re.match(r"^[A-Z_]+=", words[0]):
        words.pop(0)
    if words[0] == "python":
        done = subprocess.run([sys.executable, *words[1:]], capture_output=True, text=True,
                              env={**os.environ, "MPLBACKEND": "Agg", "PYTHONPATH": str(ROOT)})
        assert done.returncode == 0, (line, done.stderr)
        return done.stdout
    args = words[1:]
    if args and args[0] == "run":
        args += ["--set", "output.pictures=false"]
    if args and args[0] == "converge" and "--levels" not in args:
        args += ["--levels", "quick"]  # the default study itself: tests/test_converge_cli.py
    capsys.readouterr()
    code = cli.main(args)
    out, err = capsys.readouterr()
    assert code == 0, (line, err)
    return out


def normal(line: str) -> str:
    """A printed line with its spacing collapsed and figures below 1e-9 (round-off, which
    differs between machines and BLAS builds) written ``<round-off>``."""
    line = re.sub(r"\b\d\.\de-(?:09|[1-9]\d)\b", "<round-off>", line)
    return " ".join(line.split())


def check_shell(block: Block, capsys) -> int:
    """Run the commands of a shell block; in a ``$`` block, compare the output shown."""
    lines = block.text.split("\n")
    ran = 0
    for k, line in enumerate(lines):
        if not COMMAND.match(line.strip()):
            continue
        out = run_command(line.strip(), capsys)
        ran += 1
        if line.startswith("$"):
            norm = {normal(o) for o in out.split("\n")}
            for shown in lines[k + 1:]:
                if shown.startswith("$"):
                    break
                if shown.strip() and shown.strip() != "...":
                    assert normal(shown) in norm, (block.page, block.line, shown)
    return ran


def check_yaml(block: Block) -> int:
    """Load a whole case with ``load_case`` and build it; a fragment must parse."""
    from substruct.case.loader import load_case
    from substruct.run.runner import build_model

    data = yaml.safe_load(block.text)
    if isinstance(data, dict) and "name" in data and "substructures" in data:
        build_model(load_case(block.text))
        return 1
    return 0


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_every_snippet_of_the_page_runs(page, tmp_path, monkeypatch, capsys, made):
    monkeypatch.chdir(workspace(tmp_path))
    for name in MADE:  # copies: a documented --force may replace them
        (tmp_path / "results" / f"{name}.h5").write_bytes((made / f"{name}.h5").read_bytes())
    monkeypatch.setenv("MPLBACKEND", "Agg")
    namespace: dict = {"__name__": f"docs_{page.stem}"}
    for block in blocks(page):
        if block.skip:
            continue
        where = f"{block.page}:{block.line}"
        if block.lang == "python":
            exec(compile(block.text, where, "exec"), namespace)  # noqa: S102 (our own docs)
        elif block.lang == "yaml":
            check_yaml(block)
        elif block.lang == "":
            check_shell(block, capsys)


def test_the_pages_hold_runnable_snippets_and_few_exceptions():
    """The extraction finds what it should: commands, Python, cases; few skipped blocks."""
    found = [b for p in PAGES for b in blocks(p)]
    skipped = [f"{b.page}:{b.line}" for b in found if b.skip]
    assert len(skipped) <= MAX_SKIPPED, skipped
    commands = [b for b in found if b.lang == "" and not b.skip and
                any(COMMAND.match(line.strip()) for line in b.text.split("\n"))]
    assert {b.page for b in commands} >= {"README.md", "case-files.md", "convergence.md"}
    assert sum(b.lang == "python" and not b.skip for b in found) >= 8
    assert any(b.lang == "yaml" and b.page == "README.md" for b in found)
