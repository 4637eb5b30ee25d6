r"""The system a convergence study refines: a rod with spring-mass attachments and point
constraints (:class:`RodSystemSpec`), the paper's tapered rod of section 6
(:func:`paper_rod_spec`, docs/verification.md section 3), and its rod at each level of a
discretization (:func:`rod_model`, :func:`reduced_rod`).

A :class:`RodSystemSpec` holds no discretization: :func:`rod_model` makes the rod of one level
(assumed modes, eq 51; enriched assumed modes; finite elements with nodes at the attachment and
constraint points), and :meth:`RodSystemSpec.assemble` stacks it with the attachments
(eqs 17-20) and builds the constraint rows, the compatibility ones (eqs 23-27) and the extra
ones,

.. math::  \sum_k c_k\, u(x_k) = 0 \qquad \text{(eq 52)}.

The rod system of a case file: :func:`substruct.builder.rod_system_case.spec_from_case`.
"""

from __future__ import annotations

from dataclasses import dataclass

from substruct.assembly.stack import (
    Assembly,
    Connection,
    LinearConstraint,
    PointRef,
    assemble,
)
from substruct.models.discrete import fixed_free, free_free
from substruct.models.enrichment import rod_assumed_modes_enriched
from substruct.models.reduction import modal_truncation
from substruct.models.rod import Profile, paper_taper, rod_assumed_modes, rod_fe
from substruct.substructure import Substructure

__all__ = ["ROD", "DISCRETIZATIONS", "Attachment", "PointConstraint", "RodSystemSpec",
           "paper_rod_spec", "rod_model", "reduced_rod"]

#: The rod's name in the assembled system.
ROD = "rod"
#: The discretizations of the rod :func:`rod_model` makes: the uniform-rod eigenfunctions
#: (eq 51), the same plus static shapes at the points, Lagrange elements of degree 1 and 2.
DISCRETIZATIONS = ("sines", "enriched", "fe-p1", "fe-p2")


@dataclass(frozen=True)
class Attachment:
    """A spring-mass(-damper) secondary system attached to the rod at ``x`` (eqs 17-20).

    Attributes:
        name: its name (kept verbatim in outputs).
        x: attachment position on the rod.
        kind: ``"fixed-free"`` (mass on a spring to ground, attached at the mass) or
            ``"free-free"`` (absorber: massless boundary DOF at the rod, spring, mass).
        mass, stiffness, damping: ``m``, ``k``, ``c``.
    """

    name: str
    x: float
    kind: str = "fixed-free"
    mass: float = 1.0
    stiffness: float = 1.0
    damping: float = 0.0

    def substructure(self) -> Substructure:
        """The secondary system as a :class:`Substructure`."""
        if self.kind == "fixed-free":
            return fixed_free(self.name, self.mass, self.stiffness, self.damping)
        if self.kind == "free-free":
            return free_free(self.name, self.mass, self.stiffness, self.damping)
        raise ValueError(f"attachment {self.name}: kind must be 'fixed-free' or 'free-free', "
                         f"got {self.kind!r}")


@dataclass(frozen=True)
class PointConstraint:
    r"""A homogeneous constraint on rod points, :math:`\sum_k c_k u(x_k) = 0` (eq 52).

    Attributes:
        terms: ``(x, c)`` pairs.
        name: label in outputs.
    """

    terms: tuple[tuple[float, float], ...]
    name: str = ""


@dataclass(frozen=True)
class RodSystemSpec:
    """A rod with attachments and extra point constraints: what a convergence study refines.

    Attributes:
        name: system name (outputs are ``<name>_convergence.h5`` ...).
        length: rod length ``L``.
        EA, m: stiffness and mass per unit length: constants or vectorized callables of ``x``.
        support: rod end conditions, one of :data:`substruct.models.rod.SUPPORTS`.
        attachments: secondary systems.
        constraints: extra linear constraints on rod points.
        n_modes: number of lowest roots studied.
    """

    name: str
    length: float
    EA: Profile | float
    m: Profile | float
    support: str = "fixed-free"
    attachments: tuple[Attachment, ...] = ()
    constraints: tuple[PointConstraint, ...] = ()
    n_modes: int = 6

    @property
    def points(self) -> tuple[float, ...]:
        """Attachment and constraint positions, sorted, without repeats: where the mode shapes
        have slope jumps (FE nodes, enrichment load points)."""
        xs = [float(a.x) for a in self.attachments]
        xs += [float(x) for c in self.constraints for x, _ in c.terms]
        out: list[float] = []
        for x in sorted(xs):
            if not out or abs(x - out[-1]) > 1e-9 * float(self.length):
                out.append(x)
        return tuple(out)

    @property
    def damped(self) -> bool:
        """Whether any attachment has damping (the roots are then complex)."""
        return any(a.damping > 0 for a in self.attachments)

    def constraint_names(self) -> str:
        """The constraints' names, joined (``"eq52"``)."""
        return ", ".join(c.name or f"constraint {i + 1}" for i, c in enumerate(self.constraints))

    def assemble(self, rod: Substructure) -> Assembly:
        """Stack ``rod`` (named ``"rod"``) with the attachments and build ``A`` (eqs 23-27, 52)."""
        subs = [rod] + [a.substructure() for a in self.attachments]
        links = [Connection(PointRef(rod.name, a.x), PointRef(a.name, "boundary"),
                            name=f"{a.name} at x={a.x:g}") for a in self.attachments]
        extra = [LinearConstraint(tuple((PointRef(rod.name, x), float(c)) for x, c in pc.terms),
                                  name=pc.name or f"constraint {i + 1}")
                 for i, pc in enumerate(self.constraints)]
        return assemble(subs, links, extra)


def paper_rod_spec() -> RodSystemSpec:
    r"""The tapered rod of section 6 (Table 1; docs/verification.md section 3).

    :math:`L = 200`, :math:`EA(x) = \frac65\, 6\cdot 10^6 [1 - (x/L)^2/2]`,
    :math:`m(x) = \frac65 [1 - (x/L)^2/2]` (eq 50), fixed-free; ``a``, ``b`` fixed-free at
    ``L/4``, ``L/2`` (``k = 3000, 9000``), ``c``, ``d`` free-free at ``3L/4``, ``L``
    (``k = 7000, 3000``), all masses 1; constraint (52)
    :math:`2u(L/4) - 5u(L/2) - 4u(3L/4) + 3u(L) = 0`; 6 modes.
    """
    L = 200.0
    EA, m = paper_taper(2.0e5 * 30.0, 1.0, L)
    att = (Attachment("a", L / 4, "fixed-free", 1.0, 3000.0),
           Attachment("b", L / 2, "fixed-free", 1.0, 9000.0),
           Attachment("c", 3 * L / 4, "free-free", 1.0, 7000.0),
           Attachment("d", L, "free-free", 1.0, 3000.0))
    eq52 = PointConstraint(((L / 4, 2.0), (L / 2, -5.0), (3 * L / 4, -4.0), (L, 3.0)), "eq52")
    return RodSystemSpec("tapered_rod", L, EA, m, "fixed-free", att, (eq52,), 6)


def rod_model(spec: RodSystemSpec, discretization: str, n: int) -> Substructure:
    r"""The rod of ``spec`` (named :data:`ROD`) at level ``n`` of a discretization.

    * ``"sines"``: ``n`` uniform-rod eigenfunctions of ``spec.support`` (eq 51,
      :func:`substruct.models.rod.rod_assumed_modes`);
    * ``"enriched"``: the same ``n`` sines plus the static shapes of unit loads at
      ``spec.points`` (:func:`substruct.models.enrichment.rod_assumed_modes_enriched`);
    * ``"fe-p1"``, ``"fe-p2"``: about ``n`` Lagrange elements of degree 1 or 2
      (:func:`substruct.models.rod.rod_fe`),

    each with the mass and stiffness of :math:`EA(x)`, :math:`m(x)` and a node (or a row
    ``u(x) = r q``) at every point of ``spec.points``.

    Raises:
        ValueError: a discretization not in :data:`DISCRETIZATIONS`, or a level the model
            refuses.
    """
    L, EA, m, sup, pts = spec.length, spec.EA, spec.m, spec.support, spec.points
    if discretization == "sines":
        return rod_assumed_modes(ROD, L, EA, m, n, sup, nodes_at=pts)
    if discretization == "enriched":
        return rod_assumed_modes_enriched(ROD, L, EA, m, n, pts, sup)
    if discretization in ("fe-p1", "fe-p2"):
        return rod_fe(ROD, L, EA, m, n, int(discretization[-1]), sup, nodes_at=pts)
    raise ValueError(f"unknown discretization {discretization!r}; expected one of "
                     f"{', '.join(DISCRETIZATIONS)}")


def reduced_rod(rod: Substructure, g: int) -> Substructure:
    r"""``rod`` reduced to its ``g`` lowest undamped modes (eqs 21-22,
    :func:`substruct.models.reduction.modal_truncation`): :math:`q = \Phi_g \eta`."""
    return modal_truncation(rod, g)

