"""CBAR and CBEAM computed all at once (:func:`substruct.models.nastran_bars.bar_blocks`)
equal the same elements made one at a time (:func:`bar_element_matrices`) to round-off, with
lumped and coupled mass: PBAR (Euler-Bernoulli) with non-structural mass, PBEAM with blank
shear factors (1), with ``K1 = .6, K2 = .8`` and with one plane without shear flexibility
(``K1 = 0``), offsets, pin flags and a G0 orientation, on randomly placed elements; a
degenerate element is still refused naming its card."""

from __future__ import annotations

import numpy as np
import pytest

from substruct.case.bdf import parse_bulk
from substruct.case.bdf_fields import BdfError
from substruct.models.nastran_bars import bar_blocks, bar_element_matrices

PROPS = ["MAT1,1,2.1+11,8.+10,,7850.",
         "PBAR,1,1,4.-3,2.-6,5.-6,1.-6,2.5",
         "PBEAM,2,1,4.-3,2.-6,5.-6,,1.-6,1.5",
         "PBEAM,3,1,3.-3,1.-6,4.-6,,1.-6", ",,,,,,,,", ",.6,.8",
         "PBEAM,4,1,3.-3,1.-6,4.-6,,1.-6", ",,,,,,,,", ",0.,.5"]


def model(n: int, seed: int = 4, coupled: bool = False) -> str:
    """``n`` elements between random grids, cycling through properties, offsets, pins and a
    G0 orientation."""
    rng = np.random.default_rng(seed)
    pts = rng.uniform(-1, 1, size=(n + 1, 3)).cumsum(axis=0)
    lines = ["BEGIN BULK"] + PROPS + (["PARAM,COUPMASS,1"] if coupled else [])
    lines += [f"GRID,{k + 1},,{p[0]:.9f},{p[1]:.9f},{p[2]:.9f}"
              for k, p in enumerate(pts)]
    lines.append("GRID,999999,,0.3,7.1,-2.2")
    for e in range(n):
        kind = "CBAR" if e % 4 == 0 else "CBEAM"
        pid = 1 if kind == "CBAR" else 2 + e % 3
        v = [f"{x:.6f}" for x in rng.normal(size=3)]
        orient = "999999,," if e % 7 == 3 else ",".join(v)
        lines.append(f"{kind},{e + 1},{pid},{e + 1},{e + 2},{orient}")
        pins = ("4", "") if e % 11 == 5 else ("", "56") if e % 13 == 6 else ("", "")
        if e % 3 == 1 or any(pins):
            w = rng.normal(scale=0.05, size=6)
            lines.append(f",{pins[0]},{pins[1]}," + ",".join(f"{x:.6f}" for x in w))
    return "\n".join(lines + ["ENDDATA", ""])


@pytest.mark.parametrize("coupled", [False, True])
def test_batched_bars_equal_the_scalar_elements(coupled):
    bulk = parse_bulk(model(60, coupled=coupled), "bars.bdf")
    kinds = {(bar.kind, s.shear, s.kshear, bool(bar.pa or bar.pb), bar.g0 is not None,
              any(bar.wa)) for bar, s in bulk.bars}
    assert len(kinds) >= 10  # every combination the docstring names is present
    K, M = bar_blocks(bulk)
    for e, (bar, s) in enumerate(bulk.bars):
        Ke, Me = bar_element_matrices(bulk, bar, s)
        assert np.abs(K[e] - Ke).max() <= 1e-13 * np.abs(Ke).max(), (e, bar)
        assert np.abs(M[e] - Me).max() <= 1e-13 * np.abs(Me).max(), (e, bar)


def test_an_orientation_along_the_axis_is_refused_naming_the_card():
    text = "\n".join(["BEGIN BULK"] + PROPS + ["GRID,1,,0.,0.,0.", "GRID,2,,1.,0.,0.",
                                               "GRID,3,,0.,1.,0.",
                                               "CBEAM,7,2,1,3,0.,1.,0.", "ENDDATA"])
    with pytest.raises(BdfError, match="CBEAM 7.*parallel"):
        bar_blocks(parse_bulk(text, "bad.bdf"))
