"""Case files: the YAML schema, its validation, and ``--set`` overrides.

A case file names the substructures, how they are connected (compatibility, eq 24), the user
constraints (eqs 41, 52) and the analyses to run; ``docs/case-files.md`` documents every key.
:func:`load_case` reads one, applies command-line overrides ``key.path=value`` and validates it
with pydantic (unknown keys are errors everywhere).  Every problem is reported as one
:class:`CaseError` line::

    cases/rod.yaml: substructures.rod.length: must be > 0, got -200

List items are named in paths by their ``name`` when they have a unique one
(``substructures.rod``), otherwise by their 0-based index (``connections[2]``).  Points
(``"sub@where"``) are checked for syntax here and resolved when the model is built
(:mod:`substruct.run`), which reports a point that is off its substructure the same way.
"""

from __future__ import annotations

import difflib
import json
import math
import re
import types
from pathlib import Path
from typing import Annotated, Any, Literal, Mapping, Sequence, Union, get_args, get_origin

import numpy as np
import scipy.sparse as sp
import yaml
from pydantic import (AfterValidator, BaseModel, BeforeValidator, ConfigDict, Field,
                      PrivateAttr, StringConstraints, ValidationError, ValidationInfo,
                      model_validator)

from substruct.expressions import CONSTANTS, FUNCTIONS, ExpressionError, profile, scalar

__all__ = [
    "CaseError",
    "Case",
    "load_case",
    "parse_case",
    "parse_point",
    "apply_overrides",
    "METHODS",
    "MEMORY_LIMIT",
]

#: Formulations that an analysis may name (see :mod:`substruct.coupling`).
METHODS = ("generalized-inverse", "null-space", "kkt")
#: Estimated memory above which a discretization is refused up front (bytes).
MEMORY_LIMIT = 4e9
#: Hard limits on sizes, whatever the memory.
MAX_ASSUMED_MODES = 20_000
MAX_ELEMENTS = 2_000_000
MAX_FREQUENCIES = 100_000
MAX_MATRIX_SIZE = 5_000_000
#: Largest matrix whose eigenvalues are checked densely (mass matrices of matrix substructures).
DENSE_CHECK = 2000

NAME_PATTERN = r"^[A-Za-z0-9_.-]+$"
_MISSING = object()


# ------------------------------------------------------------------------------ errors


def _show(value: Any) -> str:
    """A value in an error message: one line, at most about 80 characters."""
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, bool):
        text = "true" if value else "false"
    elif value is None:
        text = "null"
    elif isinstance(value, float):
        text = repr(value)
    elif isinstance(value, str):
        text = repr(value)
    elif isinstance(value, (list, tuple, dict)):
        try:
            text = json.dumps(value, default=str)
        except (TypeError, ValueError):
            text = repr(value)
    elif isinstance(value, np.ndarray):
        text = f"array of shape {value.shape}"
    else:
        text = repr(value)
    text = text.replace("\n", "\\n")
    return text if len(text) <= 80 else text[:77] + "..."


class CaseError(ValueError):
    """A problem with a case file, as one line ``<file>: <field.path>: <problem>, got <value>``.

    Attributes:
        source: the case file (or ``"<string>"``).
        path: the field path, e.g. ``substructures.rod.length`` (empty for the whole file).
        problem: what is wrong.
        value: the offending value (absent for a missing field).
    """

    def __init__(self, source: str, path: str, problem: str, value: Any = _MISSING):
        self.source, self.path, self.problem = str(source), path, problem
        self.value = None if value is _MISSING else value
        parts = [self.source] + ([path] if path else []) + [problem]
        message = ": ".join(parts)
        if value is not _MISSING:
            message += f", got {_show(value)}"
        super().__init__(" ".join(message.split("\n")))


class FieldError(ValueError):
    """Raised inside validators: a problem at ``loc`` relative to the validated object."""

    def __init__(self, loc: str | int | Sequence[str | int], problem: str,
                 value: Any = _MISSING):
        self.loc = (loc,) if isinstance(loc, (str, int)) else tuple(loc)
        self.problem, self.value = problem, value
        super().__init__(problem)


# ------------------------------------------------------------------------ small checks


def _finite(value: float) -> float:
    if not math.isfinite(value):
        raise ValueError("must be a finite number")
    return value


def _no_bool(value: Any) -> Any:
    if isinstance(value, bool):
        raise ValueError("must be a number, not true/false")
    return value


Number = Annotated[float, BeforeValidator(_no_bool), AfterValidator(_finite)]
Positive = Annotated[Number, Field(gt=0)]
NonNegative = Annotated[Number, Field(ge=0)]
Count = Annotated[int, BeforeValidator(_no_bool), Field(ge=1)]
Name = Annotated[str, StringConstraints(pattern=NAME_PATTERN)]


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
    return value.strip()


Point = Annotated[str, BeforeValidator(_point)]


def _spec(value: Any) -> Any:
    """A distribution: a number, an expression string or ``{poly: [...]}`` (checked later)."""
    if isinstance(value, bool) or not isinstance(value, (int, float, str, dict)):
        raise ValueError("must be a number, an expression of x and L, or {poly: [c0, c1, ...]}")
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError("must be a finite number")
    return value


Distribution = Annotated[Any, AfterValidator(_spec)]


def _gigabytes(nbytes: float) -> str:
    return f"{nbytes / 1e9:.3g} GB" if nbytes >= 1e8 else f"{nbytes / 1e6:.3g} MB"


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, validate_default=False)


# ---------------------------------------------------------------------- substructures


class AssumedModes(_Model):
    """``{method: assumed-modes, n: 8, mapping: physical | paper-literal}`` (eqs 45-51)."""

    method: Literal["assumed-modes"]
    n: Count
    mapping: Literal["physical", "paper-literal"] = "physical"

    @model_validator(mode="after")
    def _size(self) -> "AssumedModes":
        n = self.n
        # quadrature of n functions and derivatives at about 52 n points, plus the n x n matrices
        need = 3 * 8 * n * 52 * max(n, 16) + 16 * n * n
        if n > MAX_ASSUMED_MODES or need > MEMORY_LIMIT:
            raise FieldError("n", f"{n} assumed modes would need about {_gigabytes(need)} of "
                             f"memory (dense quadrature of n functions), more than the "
                             f"{_gigabytes(MEMORY_LIMIT)} allowed: use fewer modes or "
                             f"method: fe", n)
        return self


class FiniteElements(_Model):
    """``{method: fe, elements: 64, order: 1 | 2}``: Lagrange elements, nodes at the points."""

    method: Literal["fe"]
    elements: Count
    order: Literal[1, 2] = 1

    @model_validator(mode="after")
    def _size(self) -> "FiniteElements":
        need = 1000.0 * self.elements * self.order  # assembly arrays, about 1 kB per element
        if self.elements > MAX_ELEMENTS or need > MEMORY_LIMIT:
            raise FieldError("elements", f"{self.elements} elements would need about "
                             f"{_gigabytes(need)} of memory; at most {MAX_ELEMENTS} elements "
                             f"are accepted", self.elements)
        return self


Discretization = Annotated[Union[AssumedModes, FiniteElements], Field(discriminator="method")]


class ModalDamping(_Model):
    """``{ratio: z}`` or ``{ratio: [z1, ...]}`` (per kept mode) or ``{rayleigh: [alpha, beta]}``."""

    ratio: Any = None
    rayleigh: tuple[NonNegative, NonNegative] | None = None

    @model_validator(mode="after")
    def _one(self) -> "ModalDamping":
        if (self.ratio is None) == (self.rayleigh is None):
            raise ValueError("give exactly one of ratio: z (or [z1, z2, ...]) and "
                             "rayleigh: [alpha, beta]")
        if self.ratio is not None:
            values = self.ratio if isinstance(self.ratio, list) else [self.ratio]
            for k, z in enumerate(values):
                loc = ("ratio", k) if isinstance(self.ratio, list) else "ratio"
                if isinstance(z, bool) or not isinstance(z, (int, float)):
                    raise FieldError(loc, "a damping ratio must be a number", z)
                if not math.isfinite(z) or z < 0:
                    raise FieldError(loc, "a damping ratio must be finite and >= 0", z)
        return self

    def as_argument(self) -> Any:
        """The ``damping`` argument of :func:`substruct.reduction.modal_truncation`."""
        if self.rayleigh is not None:
            return {"rayleigh": tuple(self.rayleigh)}
        return [float(z) for z in self.ratio] if isinstance(self.ratio, list) \
            else float(self.ratio)


class Reduce(_Model):
    """Modal truncation to the lowest ``modes`` undamped modes (eqs 21-22)."""

    modes: Count
    damping: ModalDamping | None = None

    @model_validator(mode="after")
    def _ratios(self) -> "Reduce":
        if self.damping is not None and isinstance(self.damping.ratio, list) and \
                len(self.damping.ratio) != self.modes:
            raise FieldError(("damping", "ratio"), f"one damping ratio per kept mode: "
                             f"{self.modes} needed", self.damping.ratio)
        return self


class RodSpec(_Model):
    """A longitudinally vibrating rod (section 6) of ``length`` with ``EA(x)``, ``m(x)``."""

    name: Name
    type: Literal["rod"]
    length: Positive
    EA: Distribution
    m: Distribution
    support: Literal["fixed-free", "fixed-fixed", "free-free", "free-fixed"] = "fixed-free"
    discretization: Discretization
    reduce: Reduce | None = None
    _EA: Any = PrivateAttr(default=None)
    _m: Any = PrivateAttr(default=None)

    @model_validator(mode="after")
    def _profiles(self, info: ValidationInfo) -> "RodSpec":
        params = dict((info.context or {}).get("parameters", {}))
        L = float(self.length)
        x = np.linspace(0.0, L, 2001)
        for field in ("EA", "m"):
            spec = getattr(self, field)
            try:
                f = profile(spec, L, params)
                values = f(x)
            except ExpressionError as err:
                raise FieldError(field, str(err), spec) from None
            bad = ~(np.isfinite(values) & (values > 0))
            if bad.any():
                k = int(np.argmax(bad))
                raise FieldError(field, f"must be > 0 and finite on [0, L]: {field}({x[k]:g}) "
                                 f"= {values[k]:g}", spec)
            setattr(self, f"_{field}", f)
        if self.reduce is not None and isinstance(self.discretization, AssumedModes) and \
                self.reduce.modes > self.discretization.n:
            raise FieldError(("reduce", "modes"), f"more modes than the rod's "
                             f"{self.discretization.n} assumed modes", self.reduce.modes)
        return self

    @property
    def EA_function(self):
        """``EA(x)`` as a vectorized callable."""
        return self._EA

    @property
    def m_function(self):
        """``m(x)`` as a vectorized callable."""
        return self._m

    def n_dof(self) -> int | None:
        """Number of coordinates after reduction, ``None`` if only known once meshed."""
        if self.reduce is not None:
            return self.reduce.modes
        if isinstance(self.discretization, AssumedModes):
            return self.discretization.n
        return None


class DiscreteSpec(_Model):
    """A spring-mass-damper secondary system (eqs 17-20): ``fixed-free`` or ``free-free``."""

    name: Name
    type: Literal["fixed-free", "free-free"]
    mass: Positive
    stiffness: Positive
    damping: NonNegative = 0.0

    def n_dof(self) -> int:
        """1 for fixed-free (the mass is the boundary), 2 for free-free."""
        return 1 if self.type == "fixed-free" else 2


def _matrix_source(value: Any) -> Any:
    if value is None:
        return value
    if isinstance(value, list):
        return value
    if isinstance(value, dict):
        extra = sorted(set(map(str, value)) - {"file", "key"})
        if extra or "file" not in value or not isinstance(value["file"], str):
            raise ValueError("a matrix is a list of rows, or {file: name.npz, key: K} or "
                             "{file: name.mtx}")
        return value
    raise ValueError("a matrix is a list of rows, or {file: name.npz, key: K} or "
                     "{file: name.mtx}")


MatrixSource = Annotated[Any, AfterValidator(_matrix_source)]


def _entries(field: str, rows: list, parameters: Mapping[str, float]) -> list:
    """Inline rows with expression entries (of the case parameters) evaluated."""
    out = []
    for i, row in enumerate(rows):
        if not isinstance(row, list):
            raise FieldError((field, i), "must be a row (a list of numbers)", row)
        new = []
        for j, v in enumerate(row):
            if isinstance(v, str):
                try:
                    v = scalar(v, parameters)
                except ExpressionError as err:
                    raise FieldError((field, i, j), str(err), v) from None
            elif isinstance(v, bool) or not isinstance(v, (int, float)):
                raise FieldError((field, i, j), "must be a number or an expression of the "
                                 "parameters", v)
            new.append(v)
        out.append(new)
    return out


def _load_matrix(field: str, value: Any, base: Path, parameters: Mapping[str, float]
                 ) -> sp.csr_array | np.ndarray:
    """A 2-D float array (inline lists, ``.npy``/``.npz``) or a sparse matrix (``.mtx``)."""
    if isinstance(value, list):
        try:
            arr = np.array(_entries(field, value, parameters), dtype=float)
        except (TypeError, ValueError):
            raise FieldError(field, "must be a list of rows of numbers, all of equal length",
                             value) from None
        if arr.ndim != 2:
            raise FieldError(field, "must be a list of rows (a 2-D matrix)", value)
        return arr
    path = Path(value["file"])
    path = path if path.is_absolute() else base / path
    key = value.get("key")
    suffix = path.suffix.lower()
    if suffix not in (".npz", ".npy", ".mtx"):
        raise FieldError((field, "file"), "matrix files are .npz, .npy or .mtx",
                         value["file"])
    if not path.is_file():
        raise FieldError((field, "file"), f"no such file ({path})", value["file"])
    try:
        if suffix == ".mtx":
            import scipy.io
            if key is not None:
                raise FieldError((field, "key"), "a .mtx file holds one matrix: no key", key)
            mat = scipy.io.mmread(str(path))
            return sp.csr_array(mat, dtype=float) if sp.issparse(mat) else \
                np.asarray(mat, dtype=float)
        if suffix == ".npy":
            if key is not None:
                raise FieldError((field, "key"), "a .npy file holds one matrix: no key", key)
            arr = np.asarray(np.load(path, allow_pickle=False), dtype=float)
        else:
            with np.load(path, allow_pickle=False) as data:
                key = field if key is None else key
                if key not in data.files:
                    raise FieldError((field, "key"), f"no array {key!r} in {path.name} "
                                     f"(it has {', '.join(data.files)})", key)
                arr = np.asarray(data[key], dtype=float)
    except FieldError:
        raise
    except Exception as err:  # unreadable file: a bad input, reported in one line
        raise FieldError((field, "file"), f"cannot read matrix ({type(err).__name__}: "
                         f"{' '.join(str(err).split())})", value["file"]) from None
    if arr.ndim != 2:
        raise FieldError((field, "file"), f"holds a {arr.ndim}-D array, not a matrix",
                         value["file"])
    return arr


class MatrixSpec(_Model):
    """A substructure given by its matrices (inline or from ``.npz``/``.npy``/``.mtx`` files)."""

    name: Name
    type: Literal["matrices"]
    M: MatrixSource
    K: MatrixSource
    C: MatrixSource = None
    labels: list[Annotated[str, StringConstraints(min_length=1)]] | None = None
    _matrices: dict[str, Any] = PrivateAttr(default_factory=dict)

    @model_validator(mode="after")
    def _load(self, info: ValidationInfo) -> "MatrixSpec":
        base = Path((info.context or {}).get("base_dir", "."))
        params = dict((info.context or {}).get("parameters", {}))
        mats: dict[str, Any] = {}
        for field in ("M", "K", "C"):
            value = getattr(self, field)
            if value is None:
                continue
            mat = _load_matrix(field, value, base, params)
            shown = value if isinstance(value, list) else value.get("file")
            r, c = mat.shape
            if r != c:
                raise FieldError(field, f"must be square, is {r} x {c}", shown)
            if field != "M" and r != mats["M"].shape[0]:
                n = mats["M"].shape[0]
                raise FieldError(field, f"must be {n} x {n} like M, is {r} x {c}", shown)
            if r > MAX_MATRIX_SIZE:
                raise FieldError(field, f"{r} x {r} is more than the {MAX_MATRIX_SIZE} "
                                 f"coordinates accepted", shown)
            data = mat.data if sp.issparse(mat) else mat
            if not np.all(np.isfinite(data)):
                raise FieldError(field, "has entries that are not finite numbers", shown)
            if field in ("M", "K"):
                scale = max(float(abs(mat).max()) if r else 0.0, 1e-300)
                asym = abs(mat - mat.T)
                asym = float(asym.max()) if r else 0.0
                if asym > 1e-10 * scale:
                    raise FieldError(field, f"must be symmetric: max |{field} - {field}^T| = "
                                     f"{asym:.3g}", shown)
            mats[field] = mat
        M = mats["M"]
        n = M.shape[0]
        diag = M.diagonal()
        if np.any(diag < 0):
            raise FieldError("M", f"must be positive semidefinite: diagonal entry "
                             f"{float(diag.min()):g}", self.M if isinstance(self.M, list)
                             else self.M.get("file"))
        if n <= DENSE_CHECK:
            dense = M.toarray() if sp.issparse(M) else M
            eig = np.linalg.eigvalsh((dense + dense.T) / 2)
            if eig.size and eig[0] < -1e-12 * max(abs(eig).max(), 1e-300):
                raise FieldError("M", f"must be positive semidefinite: smallest eigenvalue "
                                 f"{eig[0]:.6g}", self.M if isinstance(self.M, list)
                                 else self.M.get("file"))
        if self.labels is not None:
            if len(self.labels) != n:
                raise FieldError("labels", f"{len(self.labels)} labels for {n} coordinates",
                                 self.labels)
            dupes = sorted({lab for lab in self.labels if self.labels.count(lab) > 1})
            if dupes:
                raise FieldError("labels", f"duplicate label {dupes[0]!r}", self.labels)
        self._matrices = mats
        return self

    def matrix(self, name: str) -> Any:
        """The loaded ``M``, ``K`` or ``C`` (``None`` for an absent ``C``)."""
        return self._matrices.get(name)

    def dof_labels(self) -> list[str]:
        """Labels of the coordinates (``q1 .. qn`` unless given)."""
        n = self._matrices["M"].shape[0]
        return list(self.labels) if self.labels else [f"q{i}" for i in range(1, n + 1)]

    def n_dof(self) -> int:
        """Number of coordinates."""
        return self._matrices["M"].shape[0]


SubstructureSpec = Annotated[Union[RodSpec, DiscreteSpec, MatrixSpec],
                             Field(discriminator="type")]


# ---------------------------------------------------------------- constraints, analyses


class ConstraintSpec(_Model):
    """``sum_k c_k u(p_k) = rhs + sum_j d_j F(p_j)`` (eqs 41, 52)."""

    name: Name | None = None
    terms: dict[Point, Number]
    rhs: Number = 0.0
    rhs_force: dict[Point, Number] = Field(default_factory=dict)
    active: bool = True

    @model_validator(mode="after")
    def _not_empty(self) -> "ConstraintSpec":
        if not self.terms or all(c == 0 for c in self.terms.values()):
            raise FieldError("terms", "a constraint needs at least one term with a nonzero "
                             "coefficient", self.terms)
        return self


class Variant(_Model):
    """The same model with some constraints left out (e.g. Table 1 without eq 52)."""

    name: Name
    drop: Annotated[list[Name], Field(min_length=1)]


Method = Literal["generalized-inverse", "null-space", "kkt"]


class ModesAnalysis(_Model):
    """Coupled modes (eqs 28-34) by ``method``, checked by the ``check`` formulations."""

    count: Count = 6
    method: Method = "generalized-inverse"
    check: list[Method] = Field(default_factory=list)
    variants: list[Variant] = Field(default_factory=list)


class Omega(_Model):
    """A frequency grid: ``values`` or ``start``/``stop``/``num``/``spacing`` (rad/s)."""

    values: Annotated[list[NonNegative], Field(min_length=1)] | None = None
    start: NonNegative | None = None
    stop: Positive | None = None
    num: Count | None = None
    spacing: Literal["linear", "log"] = "linear"

    @model_validator(mode="before")
    @classmethod
    def _list(cls, value: Any) -> Any:
        if isinstance(value, list):
            return {"values": value}
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return {"values": [value]}
        if not isinstance(value, dict):
            raise ValueError("omega is a list of frequencies (rad/s) or "
                             "{start: .., stop: .., num: .., spacing: linear|log}")
        if "values" in value:
            raise FieldError("values", "unknown key: give omega as a list instead", value)
        return value

    @model_validator(mode="after")
    def _grid(self) -> "Omega":
        if self.values is not None:
            if len(self.values) > MAX_FREQUENCIES:
                raise FieldError((), f"at most {MAX_FREQUENCIES} frequencies",
                                 len(self.values))
            return self
        for key in ("start", "stop", "num"):
            if getattr(self, key) is None:
                raise FieldError(key, "a frequency grid needs start, stop and num")
        if self.stop <= self.start:
            raise FieldError("stop", f"must be > start ({self.start:g})", self.stop)
        if self.spacing == "log" and self.start <= 0:
            raise FieldError("start", "must be > 0 for a log grid", self.start)
        if self.num > MAX_FREQUENCIES:
            raise FieldError("num", f"at most {MAX_FREQUENCIES} frequencies", self.num)
        return self

    def grid(self) -> np.ndarray:
        """The circular frequencies (rad/s)."""
        if self.values is not None:
            return np.asarray(self.values, dtype=float)
        if self.spacing == "log":
            return np.geomspace(self.start, self.stop, self.num)
        return np.linspace(self.start, self.stop, self.num)


class FrfAnalysis(_Model):
    """Receptances ``H[k, i, j]`` (eqs 11-15) at ``omega`` for forces at ``inputs``."""

    omega: Omega
    inputs: Annotated[list[Point], Field(min_length=1)]
    outputs: Annotated[list[Point], Field(min_length=1)]
    method: Method = "generalized-inverse"
    check: list[Method] = Field(default_factory=list)

    @model_validator(mode="after")
    def _positive(self) -> "FrfAnalysis":
        w = self.omega.grid()
        if "generalized-inverse" in (self.method, *self.check) and np.any(w <= 0):
            raise FieldError("omega", "the generalized-inverse receptance (eq 15) is singular "
                             "at omega = 0: use frequencies > 0 (or method kkt for statics)",
                             float(w[w <= 0][0]))
        return self


class Analysis(_Model):
    """What to compute: coupled ``modes`` and/or receptances ``frf``."""

    modes: ModesAnalysis | None = None
    frf: FrfAnalysis | None = None

    @model_validator(mode="after")
    def _something(self) -> "Analysis":
        if self.modes is None and self.frf is None:
            raise ValueError("nothing to compute: give modes and/or frf")
        return self


class Output(_Model):
    """What ``substruct run`` writes besides the results file."""

    pictures: bool = True


def _parameter_names(value: dict[str, float]) -> dict[str, float]:
    reserved = {"x", "L", *CONSTANTS, *FUNCTIONS}
    for key in value:
        if not key.isidentifier() or key in reserved or key.startswith("_"):
            raise FieldError(key, f"a parameter name must be an identifier other than "
                             f"{', '.join(sorted(reserved))}", key)
    return value


class Case(_Model):
    """A validated case file; see ``docs/case-files.md``."""

    name: Name
    description: str = ""
    units: str = ""
    parameters: Annotated[dict[str, Number], AfterValidator(_parameter_names)] = \
        Field(default_factory=dict)
    substructures: Annotated[list[SubstructureSpec], Field(min_length=1)]
    connections: list[Annotated[list[Point], Field(min_length=2)]] = Field(default_factory=list)
    constraints: list[ConstraintSpec] = Field(default_factory=list)
    analysis: Analysis
    output: Output = Field(default_factory=Output)

    _source: str = PrivateAttr(default="<string>")
    _text: str = PrivateAttr(default="")
    _raw: dict = PrivateAttr(default_factory=dict)
    _base_dir: Path = PrivateAttr(default=Path("."))
    _overrides: tuple[str, ...] = PrivateAttr(default=())

    @model_validator(mode="after")
    def _cross_checks(self) -> "Case":
        self._unique("substructures", [s.name for s in self.substructures], "substructure")
        for k, c in enumerate(self.constraints):
            if c.name is None:
                c.name = f"constraint{k + 1}"
        self._unique("constraints", [c.name for c in self.constraints], "constraint")
        modes = self.analysis.modes
        if modes is not None:
            self._unique(("analysis", "modes", "variants"), [v.name for v in modes.variants],
                         "variant")
            active = [c.name for c in self.constraints if c.active]
            for i, variant in enumerate(modes.variants):
                for j, name in enumerate(variant.drop):
                    if name not in active:
                        known = ", ".join(active) or "none"
                        raise FieldError(("analysis", "modes", "variants", i, "drop", j),
                                         f"no active constraint of that name (active: "
                                         f"{known})", name)
            sizes = [s.n_dof() for s in self.substructures]
            if None not in sizes and modes.count > sum(sizes):
                raise FieldError(("analysis", "modes", "count"), f"more modes than the "
                                 f"{sum(sizes)} coordinates of the model", modes.count)
        return self

    @staticmethod
    def _unique(where: str | tuple, names: list[str], what: str) -> None:
        seen: set[str] = set()
        for k, name in enumerate(names):
            if name in seen:
                loc = (where,) if isinstance(where, str) else where
                raise FieldError((*loc, k, "name"), f"duplicate {what} name", name)
            seen.add(name)

    # ------------------------------------------------------------------- conveniences

    @property
    def source(self) -> str:
        """The case file the case was read from (``"<string>"`` otherwise)."""
        return self._source

    @property
    def base_dir(self) -> Path:
        """Directory that relative file names are relative to."""
        return self._base_dir

    @property
    def overrides(self) -> tuple[str, ...]:
        """The ``key.path=value`` overrides applied."""
        return self._overrides

    @property
    def text(self) -> str:
        """The case as YAML text: the file verbatim, or the effective data after overrides."""
        if not self._overrides:
            return self._text
        head = "".join(f"# --set {' '.join(o.split())}\n" for o in self._overrides)
        return (f"# {self._source} with command-line overrides:\n{head}"
                + yaml.safe_dump(self._raw, sort_keys=False, default_flow_style=None))

    def substructure(self, name: str) -> RodSpec | DiscreteSpec | MatrixSpec | None:
        """The substructure called ``name`` (or ``None``)."""
        return next((s for s in self.substructures if s.name == name), None)

    def error(self, loc: Sequence[str | int], problem: str, value: Any = _MISSING
              ) -> CaseError:
        """A :class:`CaseError` for the field at ``loc`` (keys and 0-based list indices)."""
        return CaseError(self._source, _path(tuple(loc), self._raw), problem, value)


# --------------------------------------------------------------- pydantic -> one line


def _unwrap(tp: Any) -> Any:
    while get_origin(tp) is Annotated:
        tp = get_args(tp)[0]
    return tp


def _members(tp: Any) -> list[Any]:
    tp = _unwrap(tp)
    if get_origin(tp) in (Union, types.UnionType):
        return [_unwrap(a) for a in get_args(tp) if a is not type(None)]
    return [tp]


def _is_model(tp: Any) -> bool:
    return isinstance(tp, type) and issubclass(tp, BaseModel)


def _allowed_keys(loc: Sequence[str | int]) -> list[str] | None:
    """Field names of the model at ``loc`` (for "unknown key" messages)."""
    tp: Any = Case
    for el in loc:
        members = _members(tp)
        models = [m for m in members if _is_model(m)]
        nxt = None
        for m in models:
            if isinstance(el, str) and el in m.model_fields:
                nxt = m.model_fields[el].annotation
                break
        if nxt is None and isinstance(el, str):  # a discriminator tag selects a member
            for m in models:
                for f in m.model_fields.values():
                    if get_origin(_unwrap(f.annotation)) is Literal and \
                            el in get_args(_unwrap(f.annotation)):
                        nxt = m
                        break
                if nxt is not None:
                    break
        if nxt is None:
            for m in members:
                origin = get_origin(m)
                if origin is list and isinstance(el, int):
                    nxt = get_args(m)[0]
                elif origin is dict:
                    nxt = get_args(m)[1]
        if nxt is None:
            return None
        tp = nxt
    models = [m for m in _members(tp) if _is_model(m)]
    return list(models[0].model_fields) if len(models) == 1 else None


def _path(loc: Sequence[str | int], raw: Any) -> str:
    """``substructures.rod.length`` / ``connections[2]`` from a pydantic location."""
    out = ""
    node = raw
    for i, el in enumerate(loc):
        last = i == len(loc) - 1
        if isinstance(node, dict) and isinstance(el, str) and el in node:
            out += ("." if out else "") + el
            node = node[el]
        elif isinstance(node, list) and isinstance(el, int) and 0 <= el < len(node):
            item = node[el]
            name = item.get("name") if isinstance(item, dict) else None
            names = [x.get("name") for x in node if isinstance(x, dict)]
            if isinstance(name, str) and names.count(name) == 1 and \
                    re.match(NAME_PATTERN, name):
                out += "." + name
            else:
                out += f"[{el}]"
            node = item
        elif isinstance(el, int):
            out += f"[{el}]"
            node = None
        elif last and el != "[key]" and (isinstance(node, dict) or node is None):
            out += ("." if out else "") + el
            node = None
        # otherwise: a union member or discriminator tag that pydantic puts in the location
    return out


def _problem(err: Mapping[str, Any], loc: tuple) -> tuple[str, tuple, Any]:
    """``(problem, loc, value)`` for one pydantic error."""
    typ, msg, ctx = err["type"], err["msg"], err.get("ctx") or {}
    value = err.get("input", _MISSING)
    exc = ctx.get("error")
    if isinstance(exc, FieldError):
        return exc.problem, loc + exc.loc, exc.value
    if typ == "missing":
        return "required field is missing", loc, _MISSING
    if typ == "extra_forbidden":
        allowed = [k for k in _allowed_keys(loc[:-1]) or [] if k != "values"]
        extra = f" (allowed: {', '.join(allowed)})" if allowed else ""
        close = difflib.get_close_matches(str(loc[-1]), allowed, n=1) if loc else []
        hint = f"; did you mean {close[0]!r}?" if close else ""
        return f"unknown key{hint}{extra}", loc, value
    if typ in ("union_tag_invalid", "union_tag_not_found"):
        disc = str(ctx.get("discriminator", "")).strip("'")
        tags = {"type": "rod, fixed-free, free-free, matrices",
                "method": "assumed-modes, fe"}.get(disc, ctx.get("expected_tags", ""))
        if typ == "union_tag_not_found" and isinstance(value, dict):
            return f"needs {disc}: one of {tags}", loc + (disc,), _MISSING
        if typ == "union_tag_not_found":
            return "must be a mapping (key: value)", loc, value
        return f"unknown {disc} (expected one of {tags})", loc + (disc,), ctx.get("tag")
    simple = {
        "greater_than": f"must be > {ctx.get('gt')}",
        "greater_than_equal": f"must be >= {ctx.get('ge')}",
        "less_than_equal": f"must be <= {ctx.get('le')}",
        "finite_number": "must be a finite number",
        "float_parsing": "must be a number", "float_type": "must be a number",
        "int_parsing": "must be an integer", "int_type": "must be an integer",
        "int_from_float": "must be an integer",
        "bool_parsing": "must be true or false", "bool_type": "must be true or false",
        "string_type": "must be a string",
        "string_pattern_mismatch": "must be a name of letters, digits, '_', '.' and '-'",
        "string_too_short": "must not be empty",
        "list_type": "must be a list",
        "dict_type": "must be a mapping (key: value)",
        "model_type": "must be a mapping (key: value)",
        "model_attributes_type": "must be a mapping (key: value)",
        "tuple_type": "must be a list",
        "too_short": f"must have at least {ctx.get('min_length')} item(s)",
        "too_long": f"must have at most {ctx.get('max_length')} item(s)",
        "literal_error": f"must be one of {ctx.get('expected')}",
    }
    if typ in simple:
        return simple[typ], loc, value
    if typ == "value_error":
        return msg.removeprefix("Value error, "), loc, value
    return msg.replace("Input should be", "must be"), loc, value


def _translate(exc: ValidationError, raw: Any, source: str,
               set_paths: Sequence[str] = ()) -> CaseError:
    errors = exc.errors(include_url=False)
    if not errors:
        return CaseError(source, "", str(exc))
    err = errors[0]  # in field order: the first problem a reader meets in the file
    if err["type"] == "missing":  # a misspelt key shows as missing + unknown: name the latter
        parent = tuple(err["loc"][:-1])
        err = next((e for e in errors if e["type"] == "extra_forbidden"
                    and tuple(e["loc"][:-1]) == parent), err)
    problem, loc, value = _problem(err, tuple(err["loc"]))
    path = _path(loc, raw)
    if any(path == p or path.startswith(p + ".") or path.startswith(p + "[")
           for p in set_paths):
        problem += " (set on the command line)"
    return CaseError(source, path, problem, value)


# ----------------------------------------------------------------------- YAML, --set


class _Loader(yaml.SafeLoader):
    """Safe loader that refuses duplicate keys (PyYAML silently keeps the last one)."""


def _mapping(loader: _Loader, node: yaml.MappingNode, deep: bool = False) -> dict:
    loader.flatten_mapping(node)
    out: dict = {}
    for key_node, value_node in node.value:
        key = loader.construct_object(key_node, deep=deep)
        try:
            hash(key)
        except TypeError:
            raise yaml.constructor.ConstructorError(
                None, None, "unhashable key", key_node.start_mark) from None
        if key in out:
            raise yaml.constructor.ConstructorError(
                None, None, f"duplicate key {key!r}", key_node.start_mark)
        out[key] = loader.construct_object(value_node, deep=deep)
    return out


_Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _mapping)
# YAML 1.1 (PyYAML) reads 6e6, 6.0e6 and 2e-3 as strings; read them as numbers, as YAML 1.2 does
_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"))


def _yaml(text: str, source: str) -> Any:
    try:
        return yaml.load(text, Loader=_Loader)  # noqa: S506 - a SafeLoader subclass
    except yaml.MarkedYAMLError as err:
        mark = err.problem_mark or err.context_mark
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark else "YAML"
        what = err.problem or err.context or "syntax error"
        raise CaseError(source, where, f"invalid YAML: {what}") from None
    except yaml.YAMLError as err:
        raise CaseError(source, "", f"invalid YAML: {' '.join(str(err).split())}") from None


def _split_key(key: str) -> list[str | int]:
    """``a.b[2].c`` -> ``["a", "b", 2, "c"]``; bracketed parts are indices or names."""
    parts: list[str | int] = []
    for piece in key.split("."):
        m = re.fullmatch(r"([^\[\]]*)((?:\[[^\[\]]*\])*)", piece)
        if m is None:
            raise ValueError(f"cannot parse key {key!r}")
        if m.group(1):
            parts.append(m.group(1))
        for idx in re.findall(r"\[([^\[\]]*)\]", m.group(2)):
            parts.append(int(idx) if re.fullmatch(r"-?\d+", idx) else idx)
    if not parts or any(p == "" for p in parts):
        raise ValueError(f"cannot parse key {key!r}")
    return parts


def _set_one(data: dict, key: str, value: Any, source: str) -> str:
    """Apply one override; return its canonical path (as error messages write it)."""
    where = f"--set {key}"
    try:
        parts = _split_key(key)
    except ValueError as err:
        raise CaseError(source, where, str(err)) from None
    node: Any = data
    path = ""
    i = 0
    while True:
        if isinstance(node, dict):
            # the longest run of parts that is a key (names may contain dots)
            for j in range(len(parts), i, -1):
                cand = ".".join(str(p) for p in parts[i:j])
                if cand in node:
                    break
            else:
                j = i + 1
                cand = str(parts[i])
            path += ("." if path else "") + cand
            if j == len(parts):
                node[cand] = value
                return path
            if cand not in node or node[cand] is None:
                node[cand] = {}
            node, i = node[cand], j
        elif isinstance(node, list):
            p = parts[i]
            if isinstance(p, int) or (isinstance(p, str) and re.fullmatch(r"-?\d+", p)):
                k = int(p)
                j = i + 1
                if k == len(node) and j == len(parts):  # one past the end: append
                    node.append(value)
                    return f"{path}[{k}]"
                if not -len(node) <= k < len(node):
                    raise CaseError(source, where, f"no item {k} in {path} "
                                    f"({len(node)} items; {len(node)} appends one)")
                k %= len(node)
                item = node[k]
                name = item.get("name") if isinstance(item, dict) else None
                path += f".{name}" if isinstance(name, str) else f"[{k}]"
            else:
                names = [x.get("name") if isinstance(x, dict) else None for x in node]
                for j in range(len(parts), i, -1):
                    cand = ".".join(str(q) for q in parts[i:j])
                    if cand in names:
                        break
                else:
                    known = ", ".join(str(n) for n in names if n is not None) or "none"
                    raise CaseError(source, where, f"no item named {parts[i]!r} in {path} "
                                    f"(names: {known})")
                k = names.index(cand)
                path += "." + cand
            if j == len(parts):
                node[k] = value
                return path
            node, i = node[k], j
        else:
            raise CaseError(source, where, f"{path} is a value, not a mapping or list",
                            node)


def apply_overrides(data: dict, overrides: Sequence[str], source: str = "<string>"
                    ) -> list[str]:
    """Apply ``key.path=value`` overrides to the raw case ``data`` in place.

    List items are addressed by 0-based index (``connections.0`` or ``connections[0]``) or by
    their ``name`` (``substructures.c.stiffness``); the index one past the end appends an item
    (``constraints[1]={...}``); values are parsed as YAML
    (``--set analysis.frf.omega=[1,2,3]`` gives a list).  Missing mapping keys are created
    (validation then rejects unknown ones).

    Returns:
        The canonical paths set, as validation errors write them.
    """
    paths = []
    for item in overrides:
        key, eq, text = str(item).partition("=")
        if not eq or not key.strip():
            raise CaseError(source, f"--set {item}", "expected key.path=value")
        try:
            value = yaml.load(text, Loader=_Loader) if text.strip() else None  # noqa: S506
        except yaml.YAMLError as err:
            what = getattr(err, "problem", None) or " ".join(str(err).split())[:80]
            raise CaseError(source, f"--set {key.strip()}", f"value is not valid YAML "
                            f"({what})", text) from None
        paths.append(_set_one(data, key.strip(), value, source))
    return paths


# ---------------------------------------------------------------------------- loading


def _parameters(raw: Any) -> dict[str, float]:
    """The parameters that are plain finite numbers (others are reported by validation)."""
    out: dict[str, float] = {}
    if isinstance(raw, dict):
        for k, v in raw.items():
            if isinstance(v, bool) or not isinstance(v, (int, float, str)):
                continue
            try:
                f = float(v)
            except ValueError:
                continue
            if isinstance(k, str) and math.isfinite(f):
                out[k] = f
    return out


def parse_case(text: str, source: str = "<string>", base_dir: str | Path = ".",
               overrides: Sequence[str] = ()) -> Case:
    """Validate case-file text (see :func:`load_case`)."""
    data = _yaml(text, source)
    if not isinstance(data, dict):
        kind = "empty file" if data is None else type(data).__name__
        raise CaseError(source, "", "a case file is a mapping of keys (name, substructures, "
                        f"analysis, ...), got {kind}")
    set_paths = apply_overrides(data, overrides, source)
    context = {"parameters": _parameters(data.get("parameters")), "base_dir": Path(base_dir)}
    try:
        case = Case.model_validate(data, context=context)
    except ValidationError as exc:
        raise _translate(exc, data, source, set_paths) from None
    case._source, case._text, case._raw = source, text, data
    case._base_dir, case._overrides = Path(base_dir), tuple(overrides)
    return case


def load_case(path: str | Path, overrides: Sequence[str] = ()) -> Case:
    """Read, override and validate a case file.

    Args:
        path: the YAML file; matrix files named in it are relative to its directory.
        overrides: ``key.path=value`` strings (``substruct run --set``), applied before
            validation.

    Raises:
        CaseError: one line, ``<file>: <field.path>: <what is wrong>, got <value>``.
    """
    p = Path(path)
    source = str(path)
    try:
        if p.stat().st_size > 20_000_000:
            raise CaseError(source, "", "case file larger than 20 MB (put matrices in "
                            ".npz/.mtx files)")
        text = p.read_text(encoding="utf-8")
    except CaseError:
        raise
    except FileNotFoundError:
        raise CaseError(source, "", "no such case file") from None
    except IsADirectoryError:
        raise CaseError(source, "", "is a directory, not a case file") from None
    except (OSError, UnicodeDecodeError) as err:
        raise CaseError(source, "", f"cannot read case file ({type(err).__name__}: "
                        f"{' '.join(str(err).split())})") from None
    return parse_case(text, source, p.parent, overrides)
