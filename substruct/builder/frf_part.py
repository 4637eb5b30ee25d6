"""A substructure known by its receptances (``type: frf``): the labelled receptances that
frequency-based substructuring couples (:mod:`substruct.analysis.frf.coupling`).

It needs NumPy only, so that a script coupling parts it has measured imports no more than
this (the splitting of a case is :mod:`substruct.builder.frf_parts`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FrfPart"]


@dataclass(frozen=True)
class FrfPart:
    """A substructure known by its receptances.

    Attributes:
        name: the substructure's name.
        omega: circular frequencies (rad/s), ascending.
        labels: one label per coordinate (``"3:z"``, a point name, ...), distinct.
        Y: complex ``(n_omega, n, n)`` receptances, ``Y[k, i, j] = u_i / F_j``.
        interpolate: ``"none"`` or ``"linear"``: how it is put on another grid.
        decouple: a part removed from the assembly (``Y`` is then its receptance negated).
        inputs: the labels of ``Y``'s columns when they are not ``labels`` (a measured part
            of sensors x impacts, reduced to virtual points before any coupling); ``Y`` is
            then ``(n_omega, len(labels), len(inputs))``.
    """

    name: str
    omega: np.ndarray
    labels: list[str]
    Y: np.ndarray
    interpolate: str = "none"
    decouple: bool = False
    inputs: list[str] | None = None

    def __post_init__(self) -> None:
        k, n = len(self.omega), len(self.labels)
        m = n if self.inputs is None else len(self.inputs)
        if self.Y.shape != (k, n, m):
            raise ValueError(f"{self.name}: receptances of shape {self.Y.shape}, expected "
                             f"({k}, {n}, {m}) for {k} frequencies and {n} x {m} labels")
        if len(set(self.labels)) != n or (self.inputs is not None and
                                          len(set(self.inputs)) != m):
            raise ValueError(f"{self.name}: labels repeated")

    def columns(self) -> list[str]:
        """The labels of ``Y``'s columns (``inputs``, or ``labels`` when square)."""
        return self.labels if self.inputs is None else self.inputs

    def index(self, label: str) -> int:
        """The coordinate of ``label``.

        Raises:
            ValueError: an unknown label (the known ones listed, up to ten).
        """
        try:
            return self.labels.index(label)
        except ValueError:
            known = ", ".join(self.labels[:10]) + (", ..." if len(self.labels) > 10 else "")
            raise ValueError(f"{self.name} has no coordinate {label!r} (it has {known})") \
                from None
