"""A reduced part that no study parameter changes is made once and shared by every sample:
which parts are shared, the same table bit for bit as reducing in every sample (in-process and
on a 2-worker LocalCluster), and the reduction counted: once."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import substruct.builder.factory as factory
import substruct.models.craig_bampton as cb
from substruct.builder.model import assemble_case
from substruct.builder.parts import reduced_part
from substruct.case.loader import load_case
from substruct.io.study_file import load_study, save_study
from substruct.studies.study_run import run_study
from substruct.studies.study_shared import shared_parts, varied_parameters

CASES = Path(__file__).resolve().parent.parent / "cases"
TUNING = CASES / "tapered_rod_tuning.yaml"
BOX = CASES / "box_beam_tmd.yaml"
SMALL = ["study.grid.parameters[0]={parameter: kc, values: [1140.0, 1160.0]}",
         "study.grid.parameters[1]={parameter: cc, values: [3.5, 4.0]}",
         "analysis.frf.omega={start: 30, stop: 39, num: 181, spacing: linear}"]
#: The box beam with absorber tmd1's stiffness a parameter, on a grid of two values.
BOX_STUDY = ["parameters={k1: 2.035e+5}", "substructures[2].stiffness=k1",
             "analysis.frf.omega={start: 300, stop: 4500, num: 20, spacing: log}",
             "study={grid: {parameters: [{parameter: k1, values: [1.9e+5, 2.1e+5]}]}, "
             "collect: {frequencies: 4, damping_ratios: true, frf_peaks: "
             "['right@1,0.05,0.1:z']}}"]


def assert_same(a, b):
    assert np.array_equal(a.table, b.table)
    assert a.errors == b.errors == [""] * len(a.errors)
    assert sorted(a.values) == sorted(b.values)
    for name in a.values:
        assert np.array_equal(a.values[name], b.values[name]), name
    for name in a.reference:
        assert np.array_equal(a.reference[name], b.reference[name]), name


def counting(monkeypatch, module, name):
    calls: list[str] = []
    original = getattr(module, name)

    def count(sub, *args, **kwargs):
        calls.append(sub.name)
        return original(sub, *args, **kwargs)
    monkeypatch.setattr(module, name, count)
    return calls


@pytest.mark.parametrize("overrides, shared", [
    ([], ["rod"]),  # the study varies the absorber only
    (["study.grid.parameters[0]={parameter: EA0, values: [6.0e6, 6.1e6]}"], []),
    # the rod's EA names EA1, an expression of the varied m0
    (["parameters.EA1=6e6*m0", "substructures[0].EA=6/5*EA1*(1 - (x/L)**2/2)",
      "substructures[0].m=1.2*(1 - (x/L)**2/2)",
      "study.grid.parameters[0]={parameter: m0, values: [1.0, 1.1]}"], []),
    # a point used on the rod moves with the varied xc
    (["parameters.xc=150", "connections[2]=[rod@xc, c]", "constraints[0].terms="
      "{rod@50: 2, rod@100: -5, rod@xc: -4, rod@200: 3}",
      "study.grid.parameters[0]={parameter: xc, values: [150, 140]}"], []),
])
def test_a_part_is_shared_only_when_no_study_parameter_reaches_it(overrides, shared):
    case = load_case(TUNING, overrides)
    assert case.study is not None
    assert shared_parts(case, case.study.parameter_names()) == shared


def test_varied_parameters_follow_expressions_in_order():
    raw = {"parameters": {"a": 1, "b": "2*a", "c": 3, "d": "b + c", "e": "c"}}
    assert varied_parameters(raw, ["a"]) == {"a", "b", "d"}
    assert varied_parameters(raw, ["c"]) == {"c", "d", "e"}


def test_a_prebuilt_part_gives_the_same_model():
    case = load_case(BOX)
    parts = {n: reduced_part(case, n) for n in ("left", "right")}
    alone, shared = assemble_case(case), assemble_case(case, prebuilt=parts)
    for name in ("M", "K", "C", "A"):
        a = sp.csr_array(getattr(alone.assembly, name))
        b = sp.csr_array(getattr(shared.assembly, name))
        assert (a != b).nnz == 0, name
    assert shared.assembly.substructures[0] is parts["left"]
    assert alone.assembly.n_dof == shared.assembly.n_dof


def test_shared_rod_reduced_once_and_the_table_unchanged(monkeypatch, tmp_path):
    calls = counting(monkeypatch, factory, "modal_truncation")
    case = load_case(TUNING, SMALL)
    shared = run_study(case)
    assert calls == ["rod"]  # 4 samples and the MAC reference: one reduction
    calls.clear()
    alone = run_study(case, share=False)
    assert calls == ["rod"] * 5
    assert shared.shared == ["rod"] and alone.shared == []
    assert_same(shared, alone)
    back = load_study(save_study(shared, tmp_path / "s.h5"))
    assert back.shared == ["rod"] and back.shared_seconds == shared.shared_seconds > 0


def test_two_craig_bampton_solids_reduced_once_each(monkeypatch):
    calls = counting(monkeypatch, cb, "craig_bampton")
    case = load_case(BOX, BOX_STUDY)
    shared = run_study(case)
    assert sorted(calls) == ["left", "right"]
    calls.clear()
    alone = run_study(case, share=False)
    assert sorted(calls) == ["left", "left", "right", "right"]
    assert shared.shared == ["left", "right"]
    assert_same(shared, alone)
    assert np.all(np.diff(shared.values["frequency"][:, 0]) != 0)  # k1 changed the modes


#: Runs studies in a fresh interpreter (no Dask in the pytest process: see test_study.py).
SCRIPT = """
import sys, json
from substruct.case.loader import load_case
from substruct.io.study_file import save_study
from substruct.studies.study_backend import Backend
from substruct.studies.study_run import run_study
a = json.loads(sys.argv[1])
save_study(run_study(load_case(a["case"], a["overrides"]), Backend(**a["backend"]),
                     share=a["share"]), a["out"])
"""


def in_subprocess(tmp_path, case, overrides, share, **backend):
    out = tmp_path / f"study_{len(list(tmp_path.iterdir()))}.h5"
    done = subprocess.run([sys.executable, "-c", SCRIPT, json.dumps(
        {"case": str(case), "overrides": overrides, "backend": backend, "share": share,
         "out": str(out)})], capture_output=True, text=True,
        env={**os.environ, "OMP_NUM_THREADS": "1"}, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    return load_study(out)


def test_shared_parts_on_a_two_worker_local_cluster_give_the_same_table(tmp_path):
    """The parts built once and shared to two worker processes give the serial study's
    figures to round-off: the same arithmetic in other processes, whose arrays may sit at
    other alignments (SIMD reductions then round differently: measured 3e-14 on a damping
    ratio of 0.08, 3e-14 relative on the frequencies); 1e-10 of each figure's largest value
    bounds that, orders below the study's check tolerance (1e-6)."""
    serial = in_subprocess(tmp_path, BOX, BOX_STUDY, False)
    dask = in_subprocess(tmp_path, BOX, BOX_STUDY, True, workers=2)
    assert dask.backend == "LocalCluster (2 workers)" and dask.shared == ["left", "right"]
    assert serial.shared == []
    assert np.array_equal(serial.table, dask.table)  # the samples' parameters
    assert serial.errors == dask.errors == [""] * len(serial.errors)
    assert sorted(serial.values) == sorted(dask.values)
    for name in serial.values:
        a, b = np.asarray(serial.values[name]), np.asarray(dask.values[name])
        assert np.abs(a - b).max() <= 1e-10 * np.abs(a).max(), name
    for name in serial.reference:
        a, b = np.asarray(serial.reference[name]), np.asarray(dask.reference[name])
        assert np.abs(a - b).max() <= 1e-10 * np.abs(a).max(), name
