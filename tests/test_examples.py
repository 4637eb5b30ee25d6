"""The example notebooks of examples/ execute without error (issue 14): one per main use.

Each runs in a fresh kernel (nbclient + ipykernel) with examples/ as its directory; the
notebooks assert their own numbers (eq 40, Table 1's printed digits, the convergence rates,
the absorbers' effect), so a notebook that runs is one whose claims hold.
"""

import os
import subprocess
import sys
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
pytest.importorskip("nbclient")

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
FAST = ["section5_frf.ipynb", "table1_both_ways.ipynb", "convergence.ipynb",
        "testlab_vpt.ipynb"]
SLOW = ["solid_absorbers.ipynb"]


#: Executes one notebook and writes it back executed.  It runs in a child process: the kernel
#: client's threads (zmq, its event loop) must not live in the test process, whose later
#: tests fork (``substruct run`` computes in a forked child, which would inherit their locks).
RUNNER = """
import sys, nbclient, nbformat
book = nbformat.read(sys.argv[1], as_version=4)
nbclient.NotebookClient(book, timeout=180, kernel_name="python3",
                        resources={"metadata": {"path": sys.argv[2]}}).execute()
nbformat.write(book, sys.argv[3])
"""


def execute(name: str, tmp_path: Path) -> list:
    """Run the notebook (in a child process); return its executed cells."""
    out = tmp_path / name
    done = subprocess.run([sys.executable, "-c", RUNNER, str(EXAMPLES / name), str(EXAMPLES),
                           str(out)], capture_output=True, text=True,
                          env={**os.environ, "MPLBACKEND": "Agg"})
    assert done.returncode == 0, done.stderr[-3000:]
    return nbformat.read(out, as_version=4).cells


def test_every_notebook_is_listed():
    assert sorted(p.name for p in EXAMPLES.glob("*.ipynb")) == sorted(FAST + SLOW)


@pytest.mark.parametrize("name", FAST)
def test_notebook_runs(name, tmp_path):
    cells = execute(name, tmp_path)
    code = [c for c in cells if c.cell_type == "code"]
    assert code and all(c.execution_count for c in code)
    assert not any(o.get("output_type") == "error" for c in code for o in c.outputs)


@pytest.mark.slow
@pytest.mark.parametrize("name", SLOW)
def test_slow_notebook_runs(name, tmp_path):
    cells = execute(name, tmp_path)
    assert any("times less" in o.get("text", "") for c in cells if c.cell_type == "code"
               for o in c.outputs)
