"""Case errors cross process boundaries (the run's child process, Dask workers): each kind
pickles and comes back with the same message, class and attributes, also from a worker
process."""

from __future__ import annotations

import pickle
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

from substruct.case.bdf_fields import BdfError
from substruct.case.errors import MISSING, CaseError, FieldError
from substruct.case.loader import parse_case

BAD = "name: x\nsubstructures:\n  - {name: r, type: rod, length: -1.0}\n"


def _bad_case() -> CaseError:
    with pytest.raises(CaseError) as info:
        parse_case(BAD, "bad.yaml")
    return info.value


def _same(a: Exception, b: Exception) -> None:
    assert type(b) is type(a) and str(b) == str(a) and b.args == a.args
    for key, value in vars(a).items():
        got = vars(b)[key]
        assert got is value if value is MISSING else np.array_equal(got, value), key


@pytest.mark.parametrize("err", [
    CaseError("case.yaml", "substructures.rod.length", "must be positive", -1.0),
    CaseError("case.yaml", "", "a case file is a mapping"),
    CaseError("case.yaml", "a.b", "a table", np.arange(3.0)),
    BdfError("model.bdf", "a grid id is 1 to 999999999", 0, line=12, card="GRID", ident=7,
             name="ID"),
    FieldError(("dofs", 3, "modes"), "a count of modal coordinates", 0),
    FieldError("K4", "K4 and W4 go together"),
])
def test_round_trip(err: Exception) -> None:
    back = pickle.loads(pickle.dumps(err))
    _same(err, back)


def test_missing_value_stays_missing() -> None:
    back = pickle.loads(pickle.dumps(FieldError("K4", "K4 and W4 go together")))
    assert back.value is MISSING  # type: ignore[attr-defined]


def test_error_of_a_case_from_a_worker_process() -> None:
    """The error ``parse_case`` raises in a worker comes back whole to the parent."""
    here = _bad_case()
    assert "substructures.r.length" in str(here)
    with ProcessPoolExecutor(max_workers=1) as pool:
        with pytest.raises(CaseError) as info:
            pool.submit(_bad_case_raises).result()
    _same(here, info.value)


def _bad_case_raises() -> None:
    parse_case(BAD, "bad.yaml")
