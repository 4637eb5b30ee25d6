"""LM-FBS of FRF parts for the outputs x inputs asked for only (``couple_selected``, what
``substruct run`` computes for ``type: frf`` parts): the numbers of the whole-stack coupling
(``couple``) bit for bit where the arithmetic is the same (every coordinate an output and an
input), to round-off for a selection, against the generalized-inverse form; its checks, its
blocks sent to a sink, and the NPZ reader's single copy."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from substruct.analysis.errors import AnalysisInputError
from substruct.analysis.frf.coupling import (
    FrfPart,
    boolean_rows,
    couple,
    generalized_inverse_fbs,
    stack,
)
from substruct.analysis.frf.coupling_selected import (
    CHECK_FREQUENCIES,
    check_frequencies,
    couple_selected,
)
from substruct.analysis.frf.stream import SweepTap
from substruct.case.npz_files import read_npz

EPS = np.finfo(float).eps


def _modal_part(name, n, modes, w, seed):
    """A measured-style receptance: a modal sum (real shapes, 2 % damping) plus a small
    symmetric residual flexibility, complex symmetric and regular at every frequency."""
    rng = np.random.default_rng(seed)
    wr = np.sort(rng.uniform(0.5, 2.0, modes)) * w.max()
    phi = rng.normal(size=(n, modes))
    G = rng.normal(size=(n, n))
    den = wr**2 - w[:, None] ** 2 + 0.04j * wr * w[:, None]
    Y = np.einsum("ir,kr,jr->kij", phi, 1 / den, phi) + (0.05 * G @ G.T / (n * wr[-1] ** 2))
    return FrfPart(name, w, [f"{k}:x" for k in range(1, n + 1)], Y)


@pytest.fixture(scope="module")
def parts():
    w = np.linspace(10.0, 400.0, 75)
    return [_modal_part("A", 9, 6, w, 1), _modal_part("B", 7, 5, w, 2),
            _modal_part("C", 5, 4, w, 3)]


PAIRS = [("A@1:x", "B@1:x"), ("A@2:x", "B@2:x"), ("B@5:x", "C@1:x"), ("B@6:x", "C@2:x"),
         ("A@9:x", "C@5:x")]


def _labels(parts):
    return [f"{p.name}@{lab}" for p in parts for lab in p.labels]


def test_every_output_and_input_gives_the_whole_coupling_bit_for_bit(parts):
    w, Yc, labels, _ = couple(parts, PAIRS)
    got = couple_selected(parts, PAIRS, labels, labels)
    assert np.array_equal(got.omega, w)
    assert np.array_equal(got.H, Yc)  # the same products of the same numbers
    B = boolean_rows(labels, PAIRS)
    whole = np.abs(B @ Yc).max() / np.abs(Yc).max()
    # every coordinate an input: the compatibility of the whole coupled receptance
    assert got.residual == pytest.approx(whole, rel=1e-6)
    assert got.residual < 100 * EPS * len(labels)


def test_a_selection_equals_the_generalized_inverse_form(parts):
    labels = _labels(parts)
    Y, _ = stack(parts)
    Yg = generalized_inverse_fbs(Y, boolean_rows(labels, PAIRS))
    rng = np.random.default_rng(7)
    o = [*rng.permutation(len(labels))[:8], 3, 3]  # unordered, repeated, across the parts
    i = [*rng.permutation(len(labels))[:5], 20]
    got = couple_selected(parts, PAIRS, [labels[k] for k in o], [labels[k] for k in i])
    want = Yg[:, o][:, :, i]
    # two formulations of eq (15): they differ by the rounding of the interface inverse,
    # kappa(B Y B^T) * m * eps relative to the largest receptance; kappa here is below 1e4
    kappa = max(np.linalg.cond(b) for b in
                boolean_rows(labels, PAIRS) @ Y @ boolean_rows(labels, PAIRS).T)
    assert kappa < 1e4
    assert np.abs(got.H - want).max() <= 100 * kappa * EPS * np.abs(Yg).max()
    # a check that measures: the same bound for the reported generalized-inverse agreement
    assert 0 < got.agreement <= 100 * kappa * EPS * np.abs(Yg).max() / np.abs(got.H).max()


def _lean(parts, pairs, outs, ins):
    """The lean LM-FBS written out a frequency at a time on the stacked receptances,
    ``Y_oi - (Y_oI B_I^T) solve(B_I Y_II B_I^T, B_I Y_Ii)``, and ``kappa(B Y B^T)``."""
    labels = _labels(parts)
    Y, _ = stack(parts)
    B = boolean_rows(labels, pairs)
    nz = np.flatnonzero(np.any(B != 0, axis=0))
    Bn = B[:, nz]
    where = {lab: k for k, lab in enumerate(labels)}
    o, i = [where[x] for x in outs], [where[x] for x in ins]
    H = np.array([y[o][:, i] - (y[o][:, nz] @ Bn.T)
                  @ np.linalg.solve(Bn @ y[nz][:, nz] @ Bn.T, Bn @ y[nz][:, i]) for y in Y])
    return H, max(np.linalg.cond(Bn @ y[nz][:, nz] @ Bn.T) for y in Y)


def test_completed_a_few_frequencies_at_a_time_in_any_layout(parts, monkeypatch):
    """The outputs x inputs completed two frequencies at a time inside blocks of seven (a
    sink), from parts whose arrays are frequency-fastest in memory: the numbers of the
    whole-block evaluation bit for bit (the same operations on the same numbers), equal to the
    lean formula and to the generalized-inverse form to the rounding of eq (15)."""
    import substruct.analysis.frf.coupling_selected as cs

    labels = _labels(parts)
    outs, ins = labels[1::2], labels[::3]
    whole = couple_selected(parts, PAIRS, outs, ins)
    strided = [FrfPart(p.name, p.omega, p.labels,
                       np.moveaxis(np.ascontiguousarray(np.moveaxis(p.Y, 0, -1)), -1, 0))
               for p in parts]
    assert not strided[0].Y.flags.c_contiguous and strided[0].Y.strides[0] == 16
    monkeypatch.setattr(cs, "CACHE_BYTES", 2 * 16 * len(outs) * len(ins))
    sink = _Blocks(7)
    got = couple_selected(strided, PAIRS, outs, ins, sink=sink)
    assert np.array_equal(sink.H, whole.H)
    assert (got.agreement, got.residual) == (whole.agreement, whole.residual)
    H, kappa = _lean(parts, PAIRS, outs, ins)
    assert kappa < 1e4
    scale = np.abs(H).max()
    # the lean formula: the same products, a frequency at a time (its own rounding bound)
    assert np.abs(sink.H - H).max() <= 100 * kappa * EPS * scale
    Y, _ = stack(parts)
    Yg = generalized_inverse_fbs(Y, boolean_rows(labels, PAIRS))
    where = {lab: k for k, lab in enumerate(labels)}
    want = Yg[:, [where[x] for x in outs]][:, :, [where[x] for x in ins]]
    assert np.abs(sink.H - want).max() <= 100 * kappa * EPS * np.abs(Yg).max()
    assert got.residual <= 100 * kappa * EPS * len(labels)


def test_the_checked_frequencies():
    assert list(check_frequencies(5)) == [0, 1, 2, 3, 4]
    assert list(check_frequencies(CHECK_FREQUENCIES)) == list(range(CHECK_FREQUENCIES))
    idx = check_frequencies(1000)
    assert len(idx) == CHECK_FREQUENCIES and idx[0] == 0 and idx[-1] == 999
    assert np.all(np.diff(idx) >= 999 // (CHECK_FREQUENCIES - 1) - 1)  # spread evenly
    assert len(check_frequencies(0)) == 0


def test_a_singular_interface_is_refused(parts):
    labels = _labels(parts)
    with pytest.raises(AnalysisInputError, match="singular"):  # a pair given twice
        couple_selected(parts, [*PAIRS, PAIRS[0]], labels[:3], labels[:3])


class _Blocks:
    """A sink that keeps the blocks it is given, in blocks of ``rows`` frequencies."""

    def __init__(self, rows):
        self.rows, self.H, self.starts = rows, None, []

    def open(self, shape, dtype):
        self.H = np.full(shape, np.nan, dtype=dtype)
        return self.rows

    def write(self, start, block):
        self.starts.append(start)
        self.H[start:start + len(block)] = block

    def read(self, key):
        return self.H[key]


def test_blocks_sent_to_a_sink_are_the_numbers_as_quantity(parts):
    labels = _labels(parts)
    outs, ins = labels[::2], labels[1::3]
    whole = couple_selected(parts, PAIRS, outs, ins)
    sink = _Blocks(7)
    w = parts[0].omega
    tap = SweepTap(sink, lambda s, c: 1j * w[s:s + c])  # mobility, a block at a time
    got = couple_selected(parts, PAIRS, outs, ins, sink=tap)
    assert got.H is None
    assert sink.starts == list(range(0, len(w), 7))
    assert np.array_equal(sink.H, whole.H * (1j * w)[:, None, None])
    assert (got.agreement, got.residual) == (whole.agreement, whole.residual)
    assert tap.array().peak == np.abs(sink.H).max()


def test_read_npz_copies_a_member_of_the_asked_dtype_once(tmp_path):
    H = np.random.default_rng(0).normal(size=(40, 64, 64)) * (1 + 1j)
    np.savez(tmp_path / "p.npz", H=H)
    tracemalloc.start()
    got = read_npz(tmp_path / "p.npz", ["H"], {"H": np.complex128})["H"]
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert np.array_equal(got, H)
    # the array read, plus numpy's read buffers (at most a few MB): not a second copy
    assert peak < H.nbytes + H.nbytes // 2


def test_a_model_and_an_frf_part_through_the_command_as_mobility(tmp_path, capsys):
    """The command streams the coupled blocks into the result file (through the quantity
    conversion); the finite-element coupling of the same models, in memory, gives the same
    mobilities to the tolerance of the two formulations (the coupled KKT solve against LM-FBS
    of the parts' receptances: both direct solves of a 10-coordinate model, 1e-9)."""
    from substruct import cli
    from substruct.case.loader import load_case
    from substruct.io.hdf5 import load
    from substruct.io.uff import uff58_sets, write_uff
    from substruct.run.runner import build_model, run_case
    from test_frf_coupling import B_LABELS, _b_matrices_spec, _b_receptance, _case

    w = 2 * np.pi * np.linspace(0.5, 12, 116)
    write_uff(tmp_path / "b.uff", uff58_sets(w, _b_receptance(w), B_LABELS, B_LABELS))
    mob = "    method: kkt\n    quantity: mobility\n"
    path = tmp_path / "fbs.yaml"
    path.write_text(_case("{name: B, type: frf, file: b.uff}").replace("    method: kkt\n", mob))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet",
                     "--no-pictures"]) == 0, capsys.readouterr().err
    frf = load(tmp_path / "out" / "fbs.h5").frf
    case = load_case(_case(_b_matrices_spec()).replace("    method: kkt\n", mob))
    fe = run_case(case, model=build_model(case)).frf
    assert frf.method.startswith("lm-fbs") and frf.quantity == fe.quantity == "mobility"
    H, He = np.asarray(frf.H), np.asarray(fe.H)
    assert np.abs(H - He).max() / np.abs(He).max() < 1e-9
    assert frf.constraint_residual < 1e-12
