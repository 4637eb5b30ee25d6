"""The size of a study plan is checked from its declared counts before anything is allocated:
a product grid of 10^9..10^12 samples, a random count, one axis, and what the samples collect
(memory), each refused by ``substruct study`` in one line naming the field, exit 2, nothing
written; the estimate bounds what a study really holds."""

from __future__ import annotations

import math
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from substruct import cli
from substruct.case.loader import CaseError, load_case
from substruct.case.study import MAX_SAMPLES
from substruct.studies.study_run import run_study

ROOT = Path(__file__).resolve().parent.parent
TUNING = ROOT / "cases" / "tapered_rod_tuning.yaml"


def axis(name: str, num: int) -> str:
    return f"{{parameter: {name}, start: 1000, stop: 2000, num: {num}}}"


@pytest.mark.parametrize("counts", [(1000, 1000, 1000), (10000, 10000, 10000),
                                    (1000000, 1000000), (1001, 1000)])
def test_a_product_grid_over_the_limit_is_refused_from_its_counts(counts, tmp_path, capsys):
    names = ["kc", "cc", "kc"][:len(counts)]
    grid = "[" + ", ".join(axis(n, c) for n, c in zip(names, counts)) + "]"
    out = tmp_path / "out"
    tracemalloc.start()
    start = time.monotonic()
    code = cli.main(["study", str(TUNING), "--out", str(out), "--set",
                     f"study.grid.parameters={grid}"])
    seconds = time.monotonic() - start
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert code == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1
    total = math.prod(counts)
    running = list(np.cumprod(np.array(counts, dtype=object)))
    k = next(i for i, r in enumerate(running) if r > MAX_SAMPLES)  # where it passes
    assert (f"study.grid.parameters[{k}].num: the product grid "
            f"{' x '.join(map(str, counts))} is {total:,} samples, at most {MAX_SAMPLES:,}"
            f" (set on the command line), got {counts[k]}") in captured.err
    assert not out.exists() or not any(out.iterdir())
    assert peak < 50e6 and seconds < 30  # nothing of the size of the grid was made


def test_the_limit_itself_is_accepted_and_its_size_is_the_table_s():
    """1000 x 1000 = MAX_SAMPLES is a valid plan (only loaded here); a small grid's declared
    size is the length of the table it makes."""
    case = load_case(TUNING, [f"study.grid.parameters=[{axis('kc', 1000)}, {axis('cc', 1000)}]"])
    assert case.study is not None and case.study.size() == MAX_SAMPLES
    from substruct.studies.study_plan import samples

    small = load_case(TUNING, [f"study.grid.parameters=[{axis('kc', 3)}, {axis('cc', 7)}]"])
    assert small.study is not None
    assert samples(small.study)[1].shape == (small.study.size(), 2) == (21, 2)


@pytest.mark.parametrize("override, fragment", [
    ("study.random={seed: 1, count: 1000000000, parameters: [{parameter: kc, distribution: "
     "uniform, low: 1000, high: 2000}]}", "study.random.count: must be <= 1000000"),
    (f"study.grid={{combine: zip, parameters: [{axis('kc', 2000000)}, {axis('cc', 2000000)}]}}",
     "study.grid.parameters[0].num: at most 1,000,000 values"),
])
def test_random_counts_and_axes_have_the_same_limit(override, fragment, tmp_path, capsys):
    assert cli.main(["study", str(TUNING), "--out", str(tmp_path / "out"), "--set",
                     override]) == 2
    err = capsys.readouterr().err
    assert fragment in err and err.count("\n") == 1
    assert not (tmp_path / "out").exists()


def test_what_the_samples_collect_must_fit_the_memory_limit():
    grid = f"study.grid.parameters=[{axis('kc', 1000)}, {axis('cc', 1000)}]"
    with pytest.raises(CaseError) as info:
        load_case(TUNING, [grid, "study.collect={frf: [rod@200, rod@200]}",
                           "analysis.frf.omega={start: 30, stop: 39, num: 2000}"])
    # 10^6 x (8 x 3 + 512 + 8 x 2000 + 16 x 2 x 2000) bytes
    assert ("study: 1,000,000 samples collecting 2 FRF curves of 2,000 frequencies would "
            "need about 80.5 GB of memory, at most 4 GB") in str(info.value)


def test_the_memory_estimate_bounds_what_a_study_holds():
    """A small study with every kind of collected array: the arrays, the table and the times
    it holds are within the estimate (which adds 512 bytes a sample for tasks and records)."""
    overrides = [f"study.grid.parameters=[{axis('kc', 3)}, {{parameter: cc, values: [3.5, 4]}}]",
                 "study.collect={frequencies: 4, damping_ratios: true, mac: true, "
                 "frf_peaks: [rod@200], frf: [rod@200]}",
                 "analysis.frf.omega={start: 30, stop: 39, num: 31, spacing: linear}"]
    case = load_case(TUNING, overrides)
    result = run_study(case)
    assert case.study is not None
    held = sum(a.nbytes for a in result.values.values()) + result.table.nbytes \
        + result.seconds.nbytes
    estimate = case.study.memory(31)
    assert held <= estimate <= held + 512 * 6
