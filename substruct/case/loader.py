"""Case files: the validated schema of a whole case, and reading one.

A case file names the substructures, how they are connected (compatibility, eq 24), the user
constraints (eqs 41, 52) and the analyses to run; ``docs/case-files.md`` documents every key.
:func:`load_case` reads one, applies command-line overrides ``key.path=value`` and validates it
with pydantic (unknown keys are errors everywhere).  Every problem is reported as one
:class:`CaseError` line::

    cases/rod.yaml: substructures.rod.length: must be > 0, got -200

List items are named in paths by their ``name`` when they have a unique one
(``substructures.rod``), otherwise by their 0-based index (``connections[2]``).  Points
(``"sub@where"``) are checked for syntax here and resolved when the model is built
(:mod:`substruct.run.runner`), which reports a point that is off its substructure the same way.

The schema is split by subject, and every public name is importable from here:

* :mod:`substruct.case.fields`: checked field types, points, size limits;
* :mod:`substruct.case.substructures`: rods (assumed modes, finite elements, reduction) and
  spring-mass-damper attachments;
* :mod:`substruct.case.matrices`: substructures given by their matrices (inline or files);
* :mod:`substruct.case.analysis`: user constraints, modes, variants, receptances;
* :mod:`substruct.case.errors`: :class:`CaseError` and pydantic errors as one line;
* :mod:`substruct.case.yaml_io`: the strict YAML loader and ``--set`` overrides.
"""

from __future__ import annotations

import math
import os
import re
import stat
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Sequence, TypeAlias, Union

import yaml
from pydantic import (
    AfterValidator,
    Field,
    PrivateAttr,
    ValidationError,
    model_validator,
)

from substruct.case.analysis import (
    Analysis,
    ConstraintSpec,
    FrfAnalysis,
    ModesAnalysis,
    Omega,
    Output,
    Variant,
)
from substruct.case.errors import MISSING, CaseError, FieldError, field_path, translate
from substruct.case.expressions import CONSTANTS, FUNCTIONS, ExpressionError, scalar
from substruct.case.fields import (
    DENSE_CHECK,
    MAX_ASSUMED_MODES,
    MAX_ELEMENTS,
    MAX_FREQUENCIES,
    MAX_MATRIX_SIZE,
    MEMORY_LIMIT,
    Name,
    Number,
    Point,
    StrictModel,
    parse_point,
)
from substruct.case.kinds import SUBSTRUCTURE_KINDS
from substruct.case.lazy_models import LazyType, LazyUnion
from substruct.case.numbers import find_problem
from substruct.case.nastran import BDF_SUFFIXES, bdf_case
from substruct.case.substructures import (
    AssumedModes,
    DiscreteSpec,
    FiniteElements,
    MassSpec,
    ModalDamping,
    Reduce,
    RodSpec,
    SpringSpec,
)
from substruct.case.yaml_io import apply_overrides, load_yaml
from substruct.lazy import lazy_getattr

if TYPE_CHECKING:
    from substruct.case.frames import FrameSpec
    from substruct.case.frf_substructure import FrfSpec
    from substruct.case.links import LinkSpec
    from substruct.case.matrices import MatrixSpec
    from substruct.case.nastran import NastranSpec
    from substruct.case.solids import InterfaceSpec, SolidSpec
    from substruct.case.study import StudySpec
    from substruct.case.superelements import SuperelementSpec

__all__ = [
    "CaseError",
    "Case",
    "load_case",
    "parse_case",
    "parse_point",
    "apply_overrides",
    "read_case_text",
    "MAX_CASE_FILE",
    "MEMORY_LIMIT",
    "MAX_ASSUMED_MODES",
    "MAX_ELEMENTS",
    "MAX_FREQUENCIES",
    "MAX_MATRIX_SIZE",
    "DENSE_CHECK",
    "SubstructureSpec",
    "RodSpec",
    "AssumedModes",
    "FiniteElements",
    "ModalDamping",
    "Reduce",
    "DiscreteSpec",
    "MatrixSpec",
    "FrfSpec",
    "ConstraintSpec",
    "Variant",
    "ModesAnalysis",
    "Omega",
    "FrfAnalysis",
    "Analysis",
    "Output",
]

#: Largest case file read, in bytes: its YAML takes up to about 6 s to parse on a busy core
#: (matrices belong in ``.npz``/``.mtx`` files).
MAX_CASE_FILE = 200_000

if TYPE_CHECKING:
    SubstructureSpec: TypeAlias = Annotated[
        Union[RodSpec, DiscreteSpec, SpringSpec, MassSpec, MatrixSpec, SolidSpec, FrfSpec,
              FrameSpec, SuperelementSpec, NastranSpec], Field(discriminator="type")]
    Interface: TypeAlias = InterfaceSpec
    Link: TypeAlias = LinkSpec
    Study: TypeAlias = StudySpec | None
else:  # each kind's model, the interfaces', the links' and the study's imported when used
    SubstructureSpec = Annotated[Any, LazyUnion("type", SUBSTRUCTURE_KINDS)]
    # list items: a null item is refused by the model, as any item that is not a mapping
    Interface = Annotated[Any, LazyType("substruct.case.solids", "InterfaceSpec",
                                        optional=False)]
    Link = Annotated[Any, LazyType("substruct.case.links", "LinkSpec", optional=False)]
    Study = Annotated[Any, LazyType("substruct.case.study", "StudySpec")]

#: The models of the kinds of substructure, importable from here as before (on first use).
__getattr__ = lazy_getattr(__name__, {"MatrixSpec": "substruct.case.matrices",
                                      "FrfSpec": "substruct.case.frf_substructure"})


def _parameter_names(value: dict[str, float]) -> dict[str, float]:
    reserved = {"x", "L", *CONSTANTS, *FUNCTIONS}
    for key in value:
        if not key.isidentifier() or key in reserved or key.startswith("_"):
            raise FieldError(key, f"a parameter name must be an identifier that does not "
                             f"start with '_', other than {', '.join(sorted(reserved))}", key)
    return value


class Case(StrictModel):
    """A validated case file; see ``docs/case-files.md``."""

    name: Name
    description: str = ""
    units: str = ""
    parameters: Annotated[dict[str, Number], AfterValidator(_parameter_names)] = \
        Field(default_factory=dict)
    substructures: Annotated[list[SubstructureSpec], Field(min_length=1)]
    connections: list[Annotated[list[Point], Field(min_length=2)]] = Field(default_factory=list)
    constraints: list[ConstraintSpec] = Field(default_factory=list)
    interfaces: list[Interface] = Field(default_factory=list)
    links: list[Link] = Field(default_factory=list)
    analysis: Analysis
    output: Output = Field(default_factory=Output)
    study: Study = None

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
        self._unique("constraints", [str(c.name) for c in self.constraints], "constraint")
        self._unique("links", [ln.name or f"link{k + 1}" for k, ln in enumerate(self.links)],
                     "link")
        modes = self.analysis.modes
        if modes is not None:
            self._unique(("analysis", "modes", "variants"), [v.name for v in modes.variants],
                         "variant")
            active = [str(c.name) for c in self.constraints if c.active]
            for i, variant in enumerate(modes.variants):
                for j, name in enumerate(variant.drop):
                    if name not in active:
                        known = ", ".join(active) or "none"
                        raise FieldError(("analysis", "modes", "variants", i, "drop", j),
                                         f"no active constraint of that name (active: "
                                         f"{known})", name)
            sizes = [s.n_dof() for s in self.substructures]
            counted = [n for n in sizes if n is not None]
            if len(counted) == len(sizes) and modes.band is None and \
                    modes.count > sum(counted):
                raise FieldError(("analysis", "modes", "count"), f"more modes than the "
                                 f"{sum(counted)} coordinates of the model", modes.count)
        if self.analysis.transient is not None:
            self.analysis.transient.refuse_frf_parts(self.substructures)
        if self.study is not None:
            self.study.check(self)
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

    def substructure(self, name: str) -> SubstructureSpec | None:
        """The substructure called ``name`` (or ``None``)."""
        return next((s for s in self.substructures if s.name == name), None)

    def error(self, loc: Sequence[str | int], problem: str, value: Any = MISSING
              ) -> CaseError:
        """A :class:`CaseError` for the field at ``loc`` (keys and 0-based list indices)."""
        return CaseError(self._source, field_path(tuple(loc), self._raw), problem, value)


# ---------------------------------------------------------------------------- loading


def _parameters(raw: Any) -> dict[str, float]:
    """The parameters that are finite numbers, or expressions of the parameters before them
    (others are reported by validation)."""
    out: dict[str, float] = {}
    if isinstance(raw, dict):
        for k, v in raw.items():
            if isinstance(v, bool) or not isinstance(v, (int, float, str)):
                continue
            try:
                f = float(v)
            except (ValueError, OverflowError):
                try:
                    f = scalar(v, out)
                except ExpressionError:
                    continue
            if isinstance(k, str) and math.isfinite(f):
                out[k] = f
    return out


_NAME = re.compile(r"[A-Za-z_][A-Za-z_0-9]*")


def _names_in(node: Any, out: set[str], depth: int = 0) -> None:
    """Every identifier written in a string (value or key) of ``node``: a generous reading of
    what the expressions, point references and study axes may use."""
    if depth > 100:
        return
    if isinstance(node, str):
        out.update(_NAME.findall(node))
    elif isinstance(node, dict):
        for k, v in node.items():
            _names_in(k, out, depth + 1)
            _names_in(v, out, depth + 1)
    elif isinstance(node, list):
        for v in node:
            _names_in(v, out, depth + 1)


def _refuse_unused_parameters(data: dict, source: str, set_paths: Sequence[str]) -> None:
    """Every key is used or refused: a parameter that no expression, point, other parameter or
    study names is refused (a misspelt name, or one set with ``--set`` that does nothing); a
    parameter of the file that ``--set`` overrides of other fields leave unused is not (the
    file as written uses it)."""
    params = data.get("parameters")
    if not isinstance(params, dict) or not params:
        return
    used: set[str] = set()
    _names_in({k: v for k, v in data.items() if k != "parameters"}, used)
    _names_in(list(params.values()), used)
    for name in params:
        if isinstance(name, str) and name not in used:
            path = field_path(("parameters", name), data)
            problem = "a parameter that nothing uses (no expression, point or study names it)"
            if path in set_paths:
                problem += " (set on the command line)"
            elif set_paths:  # the file's own parameter, left unused by what --set rewired
                continue
            raise CaseError(source, path, problem, params[name])


def _check_numbers(data: dict, source: str, set_paths: Sequence[str]) -> None:
    """Refuse the first number of the raw data out of range (:mod:`substruct.case.numbers`),
    before anything converts it."""
    found = find_problem(data)
    if found is None:
        return
    loc, value, problem, is_key = found
    path = field_path(loc, data)
    if is_key:
        problem = f"a key {problem}"
    if any(path == p or path.startswith(p + ".") or path.startswith(p + "[")
           for p in set_paths):
        problem += " (set on the command line)"
    raise CaseError(source, path, problem, value)


def parse_case(text: str, source: str = "<string>", base_dir: str | Path = ".",
               overrides: Sequence[str] = ()) -> Case:
    """Validate case-file text (see :func:`load_case`)."""
    data = load_yaml(text, source)
    if not isinstance(data, dict):
        problem = "a case file is a mapping of keys (name, substructures, analysis, ...)"
        if data is None:
            raise CaseError(source, "", f"{problem}, got empty file")
        raise CaseError(source, "", f"{problem}, not a {type(data).__name__}", data)
    set_paths = apply_overrides(data, overrides, source)
    _check_numbers(data, source, set_paths)
    context = {"parameters": _parameters(data.get("parameters")), "base_dir": Path(base_dir),
               "source": source, "units": data.get("units")}
    try:
        case = Case.model_validate(data, context=context)
    except ValidationError as exc:
        raise translate(exc, data, source, Case, set_paths) from None
    _refuse_unused_parameters(data, source, set_paths)
    case._source, case._text, case._raw = source, text, data
    case._base_dir, case._overrides = Path(base_dir), tuple(overrides)
    return case


def load_case(path: str | Path | dict, overrides: Sequence[str] = ()) -> Case:
    """Read, override and validate a case: a file, a mapping, or YAML text.

    Args:
        path: the YAML file (matrix and mesh files named in it are relative to its
            directory); or the case as a ``dict`` (as ``yaml.safe_load`` gives it) or as YAML
            text (a ``str`` holding a line break), both with files relative to the current
            directory and named ``<dict>`` / ``<string>`` in messages.
        overrides: ``key.path=value`` strings (``substruct run --set``), applied before
            validation.

    Raises:
        CaseError: one line, ``<file>: <field.path>: <what is wrong>, got <value>``.
    """
    if isinstance(path, dict):
        text = yaml.safe_dump(path, sort_keys=False)
        return parse_case(text, "<dict>", Path.cwd(), overrides)
    if isinstance(path, str) and "\n" in path:
        return parse_case(path, "<string>", Path.cwd(), overrides)
    p = Path(path)
    source = str(path)
    if p.suffix.lower() in BDF_SUFFIXES:  # Nastran bulk data: its normal modes
        return parse_case(bdf_case(p, source), source, p.parent, overrides)
    text = read_case_text(p, source)
    return parse_case(text, source, p.parent, overrides)


def read_case_text(path: Path, source: str) -> str:
    """The text of a case file: a regular file of at most :data:`MAX_CASE_FILE` bytes of UTF-8.

    The file is opened without blocking and checked before anything is read: a FIFO, a
    device (``/dev/zero``, a terminal), a socket or a directory is refused, and so is a file
    larger than the limit; at most ``MAX_CASE_FILE + 1`` bytes are ever read (a file growing
    while it is read is refused too).  Line ends are read as ``\\n``.

    Raises:
        CaseError: ``<source>: <problem>``.
    """
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise CaseError(source, "", "no such case file") from None
    except IsADirectoryError:
        raise CaseError(source, "", "is a directory, not a case file") from None
    except (OSError, ValueError) as err:
        detail = getattr(err, "strerror", None) or " ".join(str(err).split())
        raise CaseError(source, "", f"cannot read case file ({type(err).__name__}: "
                        f"{detail})") from None
    try:
        info = os.fstat(fd)
        if stat.S_ISDIR(info.st_mode):
            raise CaseError(source, "", "is a directory, not a case file")
        if not stat.S_ISREG(info.st_mode):
            kind = ("a FIFO (named pipe)" if stat.S_ISFIFO(info.st_mode) else
                    "a device" if stat.S_ISCHR(info.st_mode) or stat.S_ISBLK(info.st_mode)
                    else "a socket" if stat.S_ISSOCK(info.st_mode) else "not a regular file")
            raise CaseError(source, "", f"is {kind}, not a case file: a case is read from a "
                            f"regular file")
        limit = f"more than the {MAX_CASE_FILE} bytes read (put matrices in .npz/.mtx files)"
        if info.st_size > MAX_CASE_FILE:
            raise CaseError(source, "", f"a case file of {info.st_size} bytes, {limit}")
        chunks, size = [], 0
        while size <= MAX_CASE_FILE:
            chunk = os.read(fd, MAX_CASE_FILE + 1 - size)
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
        if size > MAX_CASE_FILE:
            raise CaseError(source, "", f"a case file that grew while it was read, {limit}")
    except OSError as err:
        raise CaseError(source, "", f"cannot read case file ({type(err).__name__}: "
                        f"{err.strerror or err})") from None
    finally:
        os.close(fd)
    try:
        text = b"".join(chunks).decode("utf-8")
    except UnicodeDecodeError as err:
        raise CaseError(source, "", f"cannot read case file ({type(err).__name__}: "
                        f"{' '.join(str(err).split())})") from None
    return text.replace("\r\n", "\n").replace("\r", "\n")
