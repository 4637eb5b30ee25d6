"""The animated GIF of a transient response (substruct/viz/transient_animation.py): drawn by
``substruct run`` with pictures on, after the result is in place, one frame per stored field,
for a solid and for a rod; not drawn without pictures."""

import numpy as np
from PIL import Image, ImageSequence

from cli_helpers import run
from substruct.io import hdf5 as results
from substruct.viz.transient_animation import frame_indices
from test_transient_export import SOLID_AND_ROD

ROD_ONLY = """\
name: rod_pulse
units: "N, m, kg, s"
substructures:
  - name: rod
    type: rod
    length: 1.0
    EA: 2.1e7
    m: 0.785
    support: fixed-free
    discretization: {method: fe, elements: 10, order: 1}
analysis:
  transient:
    t_end: 1.0e-3
    dt: 1.0e-4
    loads:
      - {point: rod@1, amplitude: 500, shape: half-sine, duration: 5.0e-4}
    outputs: [rod@1]
    field_every: 2
"""


def _frames(path):
    with Image.open(path) as im:
        assert im.format == "GIF" and im.is_animated
        return [np.asarray(f.convert("RGB")) for f in ImageSequence.Iterator(im)]


def _check_frames(frames, count):
    assert len(frames) == count
    for f in frames:
        # not blank: a white background with the drawing and the text on it
        assert (f < 250).any(axis=2).mean() > 0.01
        assert len(np.unique(f.reshape(-1, 3), axis=0)) > 8
    # the structure moves: the first frame (at rest) differs from a later one
    assert np.abs(frames[0].astype(int) - frames[-1].astype(int)).sum() > 0


def test_run_draws_the_gif_of_a_solid_and_a_rod(tmp_path, capsys):
    case = tmp_path / "beam_and_rod.yaml"
    case.write_text(SOLID_AND_ROD.replace("output: {pictures: false}", "output: {pictures: true}"))
    out = tmp_path / "out"
    code, text, err = run(capsys, "run", case, "--out", out)
    assert code == 0, err
    gif = out / "beam_and_rod_transient.gif"
    assert str(gif) in text
    tr = results.load(out / "beam_and_rod.h5").transient
    _check_frames(_frames(gif), len(tr.snapshot_t))


def test_run_draws_the_gif_of_a_rod_and_none_without_pictures(tmp_path, capsys):
    case = tmp_path / "rod_pulse.yaml"
    case.write_text(ROD_ONLY)
    code, _, err = run(capsys, "run", case, "--out", tmp_path / "out")
    assert code == 0, err
    _check_frames(_frames(tmp_path / "out" / "rod_pulse_transient.gif"), 6)  # steps 0, 2, .., 10
    code, _, err = run(capsys, "run", case, "--out", tmp_path / "bare", "--no-pictures")
    assert code == 0, err
    assert sorted(p.name for p in (tmp_path / "bare").iterdir()) == ["rod_pulse.h5"]


def test_frame_indices_keep_the_ends_and_the_count():
    assert frame_indices(5, 10) == [0, 1, 2, 3, 4]
    idx = frame_indices(1001, 120)
    assert len(idx) == 120 and idx[0] == 0 and idx[-1] == 1000
    assert np.all(np.diff(idx) >= 8) and np.all(np.diff(idx) <= 9)
