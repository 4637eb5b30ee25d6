"""Case-file substructures made by substruct: rods, spring-mass-damper attachments, springs
between two points (or to ground) and point masses.

A rod (section 6) is discretized by assumed modes (eqs 45-51) or Lagrange finite elements and
optionally reduced to its lowest modes (eqs 21-22); its ``EA(x)`` and ``m(x)`` are checked to
be finite and positive on ``[0, L]`` while the case is validated.  Discretizations that could
not fit in memory are refused here, before anything is computed, with an estimate.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, Union

import numpy as np
from pydantic import Field, PrivateAttr, ValidationInfo, model_validator

from substruct.case.errors import FieldError
from substruct.case.expressions import ExpressionError, profile, scalar
from substruct.case.fields import (
    MAX_ASSUMED_MODES,
    MAX_ELEMENTS,
    MEMORY_LIMIT,
    Count,
    Distribution,
    Name,
    NonNegative,
    Positive,
    StrictModel,
    gigabytes,
)
from substruct.case.numbers import (
    MAX_DAMPING_RATIO,
    MAX_MAGNITUDE,
    MIN_MAGNITUDE,
    number_problem,
)
from substruct.vocabulary import Support

__all__ = ["AssumedModes", "FiniteElements", "Discretization", "ModalDamping", "Reduce",
           "RodSpec", "DiscreteSpec", "SpringSpec", "MassSpec"]


class AssumedModes(StrictModel):
    """``{method: assumed-modes, n: 8, mapping: physical | paper-literal}`` (eqs 45-51)."""

    method: Literal["assumed-modes"]
    n: Count
    mapping: Literal["physical", "paper-literal"] = "physical"

    @model_validator(mode="after")
    def _size(self) -> "AssumedModes":
        n = self.n
        # quadrature of n functions and derivatives at about 52 n points, with their copies,
        # plus the n x n matrices: measured 1.6 GB at n = 1000 (a whole run, one BLAS thread)
        need = 4 * 8 * n * 52 * max(n, 16) + 16 * n * n
        if n > MAX_ASSUMED_MODES or need > MEMORY_LIMIT:
            raise FieldError("n", f"{n} assumed modes would need about {gigabytes(need)} of "
                             f"memory (dense quadrature of n functions), more than the "
                             f"{gigabytes(MEMORY_LIMIT)} allowed: use fewer modes or "
                             f"method: fe", n)
        return self


class FiniteElements(StrictModel):
    """``{method: fe, elements: 64, order: 1 | 2}``: Lagrange elements, nodes at the points."""

    method: Literal["fe"]
    elements: Count
    order: Literal[1, 2] = 1

    @model_validator(mode="after")
    def _size(self) -> "FiniteElements":
        # assembly, reduction and the run: measured 0.74 GB for 400k P1 elements and 1.5 GB
        # for 400k P2 (one BLAS thread), about 1.9 kB per element and order
        need = 2000.0 * self.elements * self.order
        if self.elements > MAX_ELEMENTS or need > MEMORY_LIMIT:
            raise FieldError("elements", f"{self.elements} elements would need about "
                             f"{gigabytes(need)} of memory; at most {MAX_ELEMENTS} elements "
                             f"are accepted", self.elements)
        return self


Discretization = Annotated[Union[AssumedModes, FiniteElements], Field(discriminator="method")]


class ModalDamping(StrictModel):
    """``{ratio: z}`` or ``{ratio: [z1, ...]}`` (per kept mode) or ``{rayleigh: [alpha, beta]}``."""

    ratio: Any = None
    rayleigh: tuple[NonNegative, NonNegative] | None = None

    @model_validator(mode="after")
    def _one(self, info: ValidationInfo) -> "ModalDamping":
        if (self.ratio is None) == (self.rayleigh is None):
            raise ValueError("give exactly one of ratio: z (or [z1, z2, ...]) and "
                             "rayleigh: [alpha, beta]")
        if self.ratio is not None:
            values = self.ratio if isinstance(self.ratio, list) else [self.ratio]
            params = dict((info.context or {}).get("parameters", {}))
            for k, z in enumerate(values):
                loc = ("ratio", k) if isinstance(self.ratio, list) else "ratio"
                if isinstance(z, str):  # an expression of the case parameters
                    try:
                        z = values[k] = scalar(z, params)
                    except ExpressionError as err:
                        raise FieldError(loc, f"a damping ratio must be a number or an "
                                         f"expression of the parameters: {err}", z) from None
                if isinstance(z, bool) or not isinstance(z, (int, float)):
                    raise FieldError(loc, "a damping ratio must be a number", z)
                problem = number_problem(z)
                if problem == "must be a finite number" or (problem is None and z < 0):
                    raise FieldError(loc, "a damping ratio must be finite and >= 0", z)
                if problem is not None:
                    raise FieldError(loc, f"a damping ratio {problem}", z)
                if z > MAX_DAMPING_RATIO:
                    raise FieldError(loc, f"a damping ratio must be at most "
                                     f"{MAX_DAMPING_RATIO:g} (1 is critical damping)", z)
            if not isinstance(self.ratio, list):
                self.ratio = values[0]
        return self

    def as_argument(self) -> Any:
        """The ``damping`` argument of :func:`substruct.models.reduction.modal_truncation`."""
        if self.rayleigh is not None:
            return {"rayleigh": tuple(self.rayleigh)}
        return [float(z) for z in self.ratio] if isinstance(self.ratio, list) \
            else float(self.ratio)


class Reduce(StrictModel):
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


class RodSpec(StrictModel):
    """A longitudinally vibrating rod (section 6) of ``length`` with ``EA(x)``, ``m(x)``."""

    name: Name
    type: Literal["rod"]
    length: Positive
    EA: Distribution
    m: Distribution
    support: Support = "fixed-free"
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
            out = (values > MAX_MAGNITUDE) | (values < MIN_MAGNITUDE)
            if out.any():
                k = int(np.argmax(out))
                raise FieldError(field, f"must lie within {MIN_MAGNITUDE:g} .. "
                                 f"{MAX_MAGNITUDE:g} on [0, L]: {field}({x[k]:g}) = "
                                 f"{values[k]:.6g}", spec)
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


class DiscreteSpec(StrictModel):
    """A spring-mass-damper secondary system (eqs 17-20): ``fixed-free`` or ``free-free``."""

    name: Name
    type: Literal["fixed-free", "free-free"]
    mass: Positive
    stiffness: Positive
    damping: NonNegative = 0.0

    def n_dof(self) -> int:
        """1 for fixed-free (the mass is the boundary), 2 for free-free."""
        return 1 if self.type == "fixed-free" else 2


class SpringSpec(StrictModel):
    """A massless spring ``stiffness`` (and damper ``damping``) between two points ``i`` and
    ``j``, ``K = k [[1, -1], [-1, 1]]``; with ``ground: true`` between point ``i`` and ground,
    ``K = [[k]]`` (:func:`substruct.models.discrete.spring`)."""

    name: Name
    type: Literal["spring"]
    stiffness: Positive
    damping: NonNegative = 0.0
    ground: bool = False

    def points(self) -> tuple[str, ...]:
        """The spring's points: ``("i", "j")``, or ``("i",)`` when grounded."""
        return ("i",) if self.ground else ("i", "j")

    def n_dof(self) -> int:
        """2 (the two ends), 1 when grounded."""
        return len(self.points())


class MassSpec(StrictModel):
    """A point mass ``mass`` with one coordinate ``mass`` and no stiffness
    (:func:`substruct.models.discrete.point_mass`)."""

    name: Name
    type: Literal["mass"]
    mass: Positive

    def n_dof(self) -> int:
        """1."""
        return 1
