"""The example notebooks of examples/ execute without error (issue 14): one per main use.

Each runs in a fresh kernel (nbclient + ipykernel) with examples/ as its directory; the
notebooks assert their own numbers (eq 40, Table 1's printed digits, the convergence rates,
the absorbers' effect), so a notebook that runs is one whose claims hold.
"""

from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
FAST = ["section5_frf.ipynb", "table1_both_ways.ipynb", "convergence.ipynb"]
SLOW = ["solid_absorbers.ipynb"]


def execute(name: str) -> list:
    """Run the notebook; return its executed cells."""
    book = nbformat.read(EXAMPLES / name, as_version=4)
    client = nbclient.NotebookClient(book, timeout=180, kernel_name="python3",
                                     resources={"metadata": {"path": str(EXAMPLES)}})
    client.execute()
    return book.cells


def test_every_notebook_is_listed():
    assert sorted(p.name for p in EXAMPLES.glob("*.ipynb")) == sorted(FAST + SLOW)


@pytest.mark.parametrize("name", FAST)
def test_notebook_runs(name, monkeypatch):
    monkeypatch.setenv("MPLBACKEND", "Agg")
    cells = execute(name)
    code = [c for c in cells if c.cell_type == "code"]
    assert code and all(c.execution_count for c in code)
    assert not any(o.get("output_type") == "error" for c in code for o in c.outputs)


@pytest.mark.slow
@pytest.mark.parametrize("name", SLOW)
def test_slow_notebook_runs(name, monkeypatch):
    monkeypatch.setenv("MPLBACKEND", "Agg")
    cells = execute(name)
    assert any("times less" in o.get("text", "") for c in cells if c.cell_type == "code"
               for o in c.outputs)
