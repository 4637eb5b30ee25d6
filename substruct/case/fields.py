"""Building blocks of the case-file schema: checked field types, points and size limits.

Every model of the schema (:mod:`substruct.case.loader`, :mod:`substruct.case.matrices`) derives from
:class:`StrictModel` (unknown keys are errors, ``nan``/``inf`` are refused) and types its fields
with the annotated types here, so that a number is never a boolean and lies within the range
of :mod:`substruct.case.numbers` (``0`` or ``1e-30 .. 1e30`` in magnitude), a count is an
integer within ``1 .. MAX_COUNT``, and a name is usable in a file name and in a point
``"sub@where"``.
"""

from __future__ import annotations

import re
from typing import Annotated, Any

from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    StringConstraints,
    ValidationInfo,
    model_validator,
)

from substruct.case.expressions import ExpressionError, scalar
from substruct.case.numbers import (
    BigNumber,
    coefficient_problem,
    digits_problem,
    number_problem,
)
from substruct.machine import available_memory, gigabytes

__all__ = [
    "MEMORY_LIMIT", "MAX_ASSUMED_MODES", "MAX_ELEMENTS", "MAX_FREQUENCIES", "MAX_MATRIX_SIZE",
    "MAX_DENSE_ENTRIES", "MAX_COUNT", "MAX_NAME_LENGTH", "DENSE_CHECK", "NAME_PATTERN",
    "Number", "Coefficient", "Positive", "NonNegative", "Count", "Id", "Name", "Point",
    "Distribution",
    "StrictModel", "parse_point", "gigabytes", "memory_limit",
]

#: Estimated memory above which an input is refused up front (bytes), where the machine's
#: available memory is not known or is less (:func:`memory_limit`).
MEMORY_LIMIT = 4e9
#: Hard limits on sizes, whatever the memory.
MAX_ASSUMED_MODES = 20_000
MAX_ELEMENTS = 2_000_000
MAX_FREQUENCIES = 100_000
#: Coordinates of a substructure given by its matrices (a 3D solid of 100k coordinates
#: already needs the 4 GB of MEMORY_LIMIT to be solved).
MAX_MATRIX_SIZE = 1_000_000
#: Entries of a dense matrix (inline, .npy, .npz or a Matrix Market array): 4000 x 4000, 128 MB;
#: larger matrices are sparse and belong in Matrix Market coordinate files.
MAX_DENSE_ENTRIES = 16_000_000
#: Largest count of anything (elements, modes, divisions, frequencies) before its own limit.
MAX_COUNT = 1_000_000_000
#: Longest name of a case, substructure, constraint or variant (it names files).
MAX_NAME_LENGTH = 100
#: Largest matrix whose eigenvalues are checked densely (mass matrices of matrix substructures).
DENSE_CHECK = 2000

#: Names of cases, substructures, constraints and variants.
NAME_PATTERN = r"^[A-Za-z0-9_.-]+$"


def _in_range(value: float) -> float:
    """The one numeric validation (:func:`substruct.case.numbers.number_problem`) of a number
    after pydantic read it (from a number, or from text such as ``"1e-310"``)."""
    problem = number_problem(value)
    if problem is not None:
        raise ValueError(problem)
    return value


def _no_bool(value: Any) -> Any:
    problem = number_problem(value) if isinstance(value, (bool, BigNumber)) else None
    if problem is not None:
        raise ValueError(problem)
    return value


def _literal(text: str, kind: type) -> bool:
    """Whether ``text`` is a number pydantic reads itself (``"1e-310"``, ``" 12 "``, ``"nan"``)."""
    try:
        kind(text)
    except (ValueError, OverflowError):
        return False
    return True


def _parameter_value(value: str, info: ValidationInfo) -> float:
    """The value of an expression of the case parameters (:func:`substruct.case.expressions.
    scalar`: whitelisted syntax, never ``eval``), checked by the one numeric validation."""
    params = dict((info.context or {}).get("parameters", {}))
    if value.strip().isidentifier() and value.strip() not in params:
        raise ValueError("must be a number")  # not a parameter of the case
    try:
        return scalar(value, params)
    except ExpressionError as err:
        raise ValueError(str(err)) from None


def _number(value: Any, info: ValidationInfo) -> Any:
    """A number, or text naming case parameters (``k``, ``2*k0``) evaluated to a float."""
    if isinstance(value, str) and not _literal(value, float):
        return _parameter_value(value, info)
    return _no_bool(value)


def _count(value: Any, info: ValidationInfo) -> Any:
    """An integer, or an expression of the case parameters whose value is a whole number."""
    if isinstance(value, str) and not _literal(value, int):
        x = _parameter_value(value, info)
        if x != round(x):
            raise ValueError(f"must be an integer: {value.strip()!r} = {x:.6g}")
        return int(round(x))
    return _no_bool(value)


def _id(value: Any) -> Any:
    """An id (a node number) as YAML writes it: ``true``/``false`` are not ``1``/``0``."""
    if isinstance(value, bool):
        raise ValueError("an id is an integer, not true/false")
    return value


#: An id (a frame's node number): an integer, a boolean refused.
Id = Annotated[int, BeforeValidator(_id)]


#: A finite number, 0 or within 1e-30 .. 1e30 in magnitude; or an expression of the case
#: parameters (``stiffness: k``, ``mass: 2*m0``) whose value is checked the same way.
Number = Annotated[float, BeforeValidator(_number), AfterValidator(_in_range)]
Positive = Annotated[Number, Field(gt=0)]


def _coefficient_in_range(value: float) -> float:
    problem = coefficient_problem(value)
    if problem is not None:
        raise ValueError(problem)
    return value


#: A constraint coefficient: like :data:`Number` but finite at any magnitude (the rows are
#: equilibrated before any decision, so ``1e-300 q1 = 0`` means ``q1 = 0``).
Coefficient = Annotated[float, BeforeValidator(_number), AfterValidator(_coefficient_in_range)]
NonNegative = Annotated[Number, Field(ge=0)]
#: An integer within 1 .. MAX_COUNT (each count has its own, smaller limit too); or an
#: expression of the case parameters with a whole-number value (``elements: 4*n``).
Count = Annotated[int, BeforeValidator(_count), Field(ge=1, le=MAX_COUNT)]
Name = Annotated[str, StringConstraints(pattern=NAME_PATTERN, max_length=MAX_NAME_LENGTH)]


def parse_point(text: str) -> tuple[str, str | None]:
    """``"sub@where"`` -> ``("sub", "where")``; ``"sub"`` -> ``("sub", None)``."""
    sub, at, where = text.strip().partition("@")
    return sub.strip(), (where.strip() if at else None)


def _point(value: Any) -> str:
    if not isinstance(value, str):
        raise ValueError("a point is written 'substructure@where' or 'substructure'")
    sub, where = parse_point(value)
    if not re.match(NAME_PATTERN, sub) or where == "":
        raise ValueError("a point is written 'substructure@where' (e.g. rod@50, P@q1) or "
                         "'substructure' for the boundary of a discrete attachment")
    problem = digits_problem(where or "", point=True)
    if problem is not None:
        raise ValueError(problem)
    return value.strip()


#: ``"sub@where"`` or ``"sub"``, checked for syntax only (resolved when the model is built).
Point = Annotated[str, BeforeValidator(_point)]


def _spec(value: Any) -> Any:
    """A distribution: a number, an expression string or ``{poly: [...]}`` (checked later)."""
    if isinstance(value, bool) or not isinstance(value, (int, float, str, dict)):
        raise ValueError("must be a number, an expression of x and L, or {poly: [c0, c1, ...]}")
    problem = number_problem(value)
    if problem is not None:
        raise ValueError(problem)
    return value


#: A distribution along a rod; evaluated by :func:`substruct.case.expressions.profile`.
Distribution = Annotated[Any, AfterValidator(_spec)]


class StrictModel(BaseModel):
    """Base of every schema model: unknown keys and non-finite numbers are errors.

    Each model's validator is built when it is first used (``defer_build``), not when its
    class is defined: a case validates through one validator built for :class:`Case` rather
    than one built for each of the schema's 80-odd models at import (0.03-0.05 s of start-up
    saved, the same checks)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, validate_default=False,
                              defer_build=True)

    @model_validator(mode="before")
    @classmethod
    def _yaml_booleans(cls, data: Any) -> Any:
        """A field typed ``bool`` takes ``true`` or ``false`` only: pydantic would also read
        ``"yes"``, ``"off"``, ``0`` or ``1`` as a boolean."""
        if isinstance(data, dict):
            from substruct.case.errors import FieldError  # errors imports this module

            for name in _boolean_fields(cls):
                value = data.get(name, False)
                if not isinstance(value, bool):
                    raise FieldError(name, "must be true or false", value)
        return data


def _boolean_fields(model: type[BaseModel]) -> frozenset[str]:
    """The fields of ``model`` typed ``bool`` (computed once per model class)."""
    found: frozenset[str] | None = model.__dict__.get("_boolean_field_names")
    if found is None:
        found = frozenset(name for name, f in model.model_fields.items() if f.annotation is bool)
        setattr(model, "_boolean_field_names", found)
    return found


def memory_limit() -> float:
    """The estimated memory (bytes) above which a model is refused before it is built: the
    memory the machine has available now, never less than :data:`MEMORY_LIMIT` (a model that
    fits the machine runs)."""
    return max(MEMORY_LIMIT, available_memory() or 0.0)
