"""Random hostile mutations of the shipped cases: every one is refused in one line, or runs.

Each example takes a case of ``cases/``, replaces one value anywhere in it (or deletes it) by
something hostile (an integer of 31, 400 or 5000 digits, ``.nan``, ``inf``, ``1e308``, a
subnormal, a negative number, a long string, an expression that reaches for ``__import__``,
lists nested 150 deep, a value of the wrong type) and reads the YAML text back the way
``substruct run`` does.  In-process (:func:`load_case`-like parsing and :func:`build_model`)
the outcome must be a built model or one :class:`CaseError` of one line that starts with the
file; through the command line (a few small cases, ``run`` into ``tmp_path``) exit code 0 with
nothing on stderr, or exit code 2 with exactly one line, never a traceback.

Examples are drawn with ``derandomize=True`` and no example database (the same code gives the
same examples), a few dozen in all, each under a deadline of 20 s.
"""

from __future__ import annotations

import copy
import math
import time
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from substruct import cli
from substruct.case.errors import CaseError
from substruct.case.loader import parse_case
from substruct.case.numbers import is_coefficient
from substruct.case.yaml_io import load_yaml
from substruct.run.runner import build_model

ROOT = Path(__file__).resolve().parent.parent
CASES = ROOT / "cases"
SHIPPED = {p.name: load_yaml(p.read_text(encoding="utf-8"), p.name)
           for p in sorted(CASES.glob("*.yaml"))}
#: Small cases that run end to end in well under a second.
SMALL = ["three_dof_frf.yaml", "three_dof_frf_nonhomogeneous.yaml", "tapered_rod_table1.yaml"]

#: Placeholders put into the data and replaced in the YAML text (values yaml cannot write).
_MARK = "QQHOSTILEQQ"

HOSTILE: list[tuple[str, Any]] = [
    ("digits", 31), ("digits", 400), ("digits", 5000), ("digits_negative", 400),
    ("nested", 150), ("nested", 60),
    ("value", math.nan), ("value", math.inf), ("value", -math.inf), ("value", 1e308),
    ("value", -1e308), ("value", 1e-310), ("value", -1e-310), ("value", 1e31),
    ("value", 0), ("value", -1), ("value", -0.5), ("value", 2.5), ("value", 2 ** 31),
    ("value", ".nan"), ("value", "nan"), ("value", "1e999"), ("value", "9" * 400),
    ("value", "x" * 5000), ("value", "__import__('os').system('echo owned')"),
    ("value", "9**9**9**9"), ("value", ""), ("value", "\x1b]0;owned\x07"),
    ("value", True), ("value", None), ("value", []), ("value", {}), ("value", [[1]]),
    ("value", {"a": {"b": [1, 2]}}), ("delete", None),
]


def _paths(node: Any, here: tuple = ()) -> list[tuple]:
    """Every location in the raw data (mapping keys and list indices), containers too."""
    out = [here] if here else []
    if isinstance(node, dict):
        for key, value in node.items():
            out += _paths(value, here + (key,))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            out += _paths(value, here + (i,))
    return out


PATHS = {name: _paths(data) for name, data in SHIPPED.items()}


def mutated(name: str, where: int, mutation: tuple[str, Any]) -> str:
    """The text of case ``name`` with the value at its ``where``-th location mutated."""
    data = copy.deepcopy(SHIPPED[name])
    loc = PATHS[name][where % len(PATHS[name])]
    parent = data
    for key in loc[:-1]:
        parent = parent[key]
    kind, arg = mutation
    if kind == "delete":
        del parent[loc[-1]]
        return yaml.safe_dump(data, sort_keys=False)
    parent[loc[-1]] = arg if kind == "value" else _MARK
    text = yaml.safe_dump(data, sort_keys=False, width=10 ** 9)
    if kind == "digits":
        return text.replace(_MARK, "9" * arg)
    if kind == "digits_negative":
        return text.replace(_MARK, "-" + "8" * arg)
    if kind == "nested":
        return text.replace(_MARK, "[" * arg + "1" + "]" * arg)
    return text


mutations = st.tuples(st.sampled_from(sorted(SHIPPED)), st.integers(0, 10 ** 6),
                      st.sampled_from(HOSTILE))


def _check_in_process(name: str, text: str) -> str:
    """``"ok"`` or ``"refused"``; anything else fails the test."""
    source = f"cases/{name}"
    start = time.perf_counter()
    try:
        case = parse_case(text, source, CASES)
        build_model(case)
    except CaseError as err:
        message = str(err)
        assert "\n" not in message and "\r" not in message, message
        assert message.startswith(source + ": "), message
        assert message.isprintable(), message
        assert len(message) < 2000, message
        outcome = "refused"
    else:
        outcome = "ok"
    assert time.perf_counter() - start < 20
    return outcome


@settings(max_examples=40, deadline=20_000, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow], print_blob=True)
@given(mutation=mutations)
def test_a_mutated_case_is_refused_in_one_line_or_builds(mutation):
    name, where, hostile = mutation
    _check_in_process(name, mutated(name, where, hostile))


@pytest.mark.parametrize("name", sorted(SHIPPED))
@pytest.mark.parametrize("hostile", [("digits", 400), ("value", math.nan), ("value", 1e308)],
                         ids=["bigint", "nan", "1e308"])
def test_every_number_of_every_case_is_checked(name, hostile):
    """Every numeric leaf of every shipped case, replaced by a hostile number: refused.

    (A number that is a name, a flag or a label position would be refused too: nothing in a
    case accepts these values.)  The one exception is a finite constraint coefficient
    (``terms``, ``rhs_force``): a row means the same at any scale, so ``1e308`` there is a
    legitimate (other) constraint and the case builds."""
    numeric = [i for i, loc in enumerate(PATHS[name]) if isinstance(_at(SHIPPED[name], loc),
                                                                     (int, float))
               and not isinstance(_at(SHIPPED[name], loc), bool)]
    assert numeric
    for where in numeric:
        loc = PATHS[name][where]
        scale_free = (hostile == ("value", 1e308) and is_coefficient(loc)
                      and loc[2] in ("terms", "rhs_force"))
        text = mutated(name, where, hostile)
        assert _check_in_process(name, text) == ("ok" if scale_free else "refused"), loc


def _at(data: Any, loc: tuple) -> Any:
    for key in loc:
        data = data[key]
    return data


@settings(max_examples=8, deadline=20_000, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
          print_blob=True)
@given(mutation=st.tuples(st.sampled_from(SMALL), st.integers(0, 10 ** 6),
                          st.sampled_from(HOSTILE)))
def test_through_the_command_line_exit_0_or_one_line_and_exit_2(mutation, tmp_path_factory,
                                                                capsys):
    name, where, hostile = mutation
    tmp = tmp_path_factory.mktemp("fuzz")
    path = tmp / name
    path.write_text(mutated(name, where, hostile), encoding="utf-8")
    out = tmp / "out"
    code = cli.main(["run", str(path), "--out", str(out), "--quiet",
                     "--set", "output.pictures=false"])
    stdout, stderr = capsys.readouterr()
    assert code in (0, 2), stderr
    if code == 2:
        assert stderr.count("\n") == 1 and stderr.startswith(f"substruct: error: {path}"), \
            stderr
        assert stdout == "" and not out.exists()
    else:
        assert stderr == "", stderr
    assert "Traceback" not in stderr
