"""Progress of a study's counted phases: a tqdm bar per phase (count, elapsed, ETA) when
shown, nothing otherwise; the shared reductions and the samples report every task."""

from __future__ import annotations

import io
from pathlib import Path

from substruct.case.loader import load_case
from substruct.cli.progress import CountBar
from substruct.studies.distributed_run import run_distributed
from substruct.studies.study_backend import Backend
from substruct.studies.study_run import run_study

CASES = Path(__file__).resolve().parent.parent / "cases"
SMALL = ["study.grid.parameters[0]={parameter: kc, values: [1140.0, 1160.0, 1170.0]}",
         "study.grid.parameters[1]={parameter: cc, values: [3.5]}",
         "analysis.frf.omega={start: 30, stop: 39, num: 31, spacing: linear}",
         "study.collect={frequencies: 2}"]


def test_a_count_bar_draws_counts_only_when_shown():
    shown, hidden = io.StringIO(), io.StringIO()
    bar, off = CountBar(shown, "study", "sample", True), CountBar(hidden, "study", "sample", False)
    for k in range(1, 4):
        bar(k, 3)
        off(k, 3)
    bar.close()
    off.close()
    assert "study: 100%" in shown.getvalue() and "3/3" in shown.getvalue()
    assert hidden.getvalue() == ""


def test_reductions_and_samples_tick_once_per_task():
    samples, parts = [], []
    run_study(load_case(CASES / "tapered_rod_tuning.yaml", SMALL),
              tick=lambda d, t: samples.append((d, t)),
              parts_tick=lambda d, t: parts.append((d, t)))
    assert samples == [(1, 3), (2, 3), (3, 3)]
    assert parts == [(1, 1)]  # the rod, shared


def test_chunks_tick_after_the_reductions():
    ticks = []
    case = load_case(CASES / "tapered_rod_tuning.yaml", SMALL[2:3] + [
        "analysis.frf.method=kkt"])
    run_distributed(case, Backend(), chunks=3, tick=lambda d, t: ticks.append((d, t)))
    assert ticks == [(1, 1), (1, 3), (2, 3), (3, 3)]  # the rod's reduction, then 3 chunks
