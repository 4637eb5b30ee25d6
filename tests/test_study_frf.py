"""``collect: frf``: the whole receptance curve of every sample in the study and its file,
equal to a direct run of the sample, consistent with the peaks; bad entries refused."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from substruct.case.loader import CaseError, load_case
from substruct.io.study_file import load_study, save_study
from substruct.run.runner import run_case
from substruct.studies.study_run import run_study

CASES = Path(__file__).resolve().parent.parent / "cases"
TUNING = CASES / "tapered_rod_tuning.yaml"
STUDY = ["study.grid.parameters[0]={parameter: kc, values: [1140.0, 1160.0]}",
         "study.grid.parameters[1]={parameter: cc, values: [3.5, -1.0]}",  # -1: fails
         "analysis.frf.omega={start: 30, stop: 39, num: 61, spacing: linear}",
         "analysis.frf.outputs=[rod@200, c@mass]",
         "study.collect={frequencies: 2, frf_peaks: [rod@200], frf: [rod@200, c@mass], "
         "mac: true}"]


def test_the_whole_curve_of_each_sample_is_kept(tmp_path):
    result = run_study(load_case(TUNING, STUDY))
    assert result.curves == ["rod@200<-rod@200", "c@mass<-rod@200"]
    H, w = result.values["frf"], result.values["frf_omega"]
    assert H.shape == (4, 61, 2) and H.dtype == complex and w.shape == (4, 61)
    assert result.failed == [1, 3] and np.isnan(H[1]).all() and np.isnan(w[3]).all()
    for k in (0, 2):
        kc, cc = map(float, result.table[k])
        direct = run_case(load_case(TUNING, STUDY[2:4] + [f"parameters.kc={kc!r}",
                                                           f"parameters.cc={cc!r}"]))
        assert direct.frf is not None
        assert np.array_equal(H[k, :, 0], direct.frf.at("rod@200", "rod@200"))
        assert np.array_equal(H[k, :, 1], direct.frf.at("rod@200", "c@mass"))
        assert np.array_equal(w[k], direct.frf.omega)
        assert result.values["frf_peak"][k, 0] == np.abs(H[k, :, 0]).max()
    assert result.reference["frf"].shape == (61, 2)
    back = load_study(save_study(result, tmp_path / "s.h5"))
    assert back.curves == result.curves
    assert np.array_equal(back.values["frf"], H, equal_nan=True)
    assert np.array_equal(back.values["frf_omega"], w, equal_nan=True)


@pytest.mark.parametrize("collect, fragment", [
    ("{frf: [rod@100]}", "study.collect.frf[0]: not an output of analysis.frf"),
    ("{frf: [{output: rod@200, input: c@mass}]}",
     "study.collect.frf[0].input: not an input of analysis.frf"),
])
def test_a_curve_not_in_the_sweep_is_refused(collect, fragment):
    with pytest.raises(CaseError) as err:
        load_case(TUNING, [f"study.collect={collect}"])
    assert fragment in str(err.value)
