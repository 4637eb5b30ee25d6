"""The matrices each bulk data element makes, held to the range of the case's numbers.

Every real field of a card is 0 or within ``1e-30 .. 1e30`` in magnitude
(:mod:`substruct.case.numbers`, checked where the field is read), but an element's matrices are
products of its fields and of its grids' positions: a CONM2 offset of ``1e25`` makes a mass
moment ``M |X|^2`` of ``1e51``, a CBAR offset ``W`` of ``1e20`` turns ``mu L`` into rotary
inertia ``mu L |W|^2``, a stiff bar of length ``1e-20`` makes ``E I / L^3``.  No float64
overflows there, but the model then mixes magnitudes that no eigensolver resolves, and its
modes are nonsense (or the solver fails inside).  So each element's stiffness and mass
(``PARAM,WTMASS`` applied) is held to :data:`~substruct.case.numbers.MAX_MAGNITUDE` in every
entry, and an element beyond it is refused naming its card, by the product.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from substruct.case.bdf import BulkData
from substruct.case.bdf_fields import BdfError
from substruct.case.numbers import MAX_MAGNITUDE, RANGE

__all__ = ["check_element", "check_elements", "check_solid_block"]


def _largest(a: np.ndarray) -> float:
    with np.errstate(all="ignore"):
        return float(np.nan_to_num(np.abs(a), nan=np.inf).max(initial=0.0))


def _refuse(bulk: BulkData, card: str, ident: int, line: int, what: str, top: float
            ) -> BdfError:
    return BdfError(bulk.source, f"a product of its fields and its grids' positions is out of "
                    f"range: the {what} matrix it makes has an entry beyond 1e30 "
                    f"in magnitude ({RANGE})", float(f"{top:.3g}"), line=line, card=card,
                    ident=ident)


def check_element(bulk: BulkData, card: str, ident: int, line: int, K: np.ndarray | None,
                  M: np.ndarray | None) -> None:
    """Refuse one element whose stiffness ``K`` or mass ``M`` (before WTMASS) has an entry
    beyond :data:`~substruct.case.numbers.MAX_MAGNITUDE` (or not finite).

    Raises:
        BdfError: naming the card, its id and line, and the largest entry.
    """
    for what, X, scale in (("stiffness", K, 1.0), ("mass", M, bulk.wtmass)):
        if X is not None:
            top = _largest(X) * scale
            if not top <= MAX_MAGNITUDE:
                raise _refuse(bulk, card, ident, line, what, top)


def check_elements(bulk: BulkData, cards: list[tuple[str, int, int]], K: np.ndarray,
                   M: np.ndarray) -> None:
    """:func:`check_element` of a batch: ``K``, ``M`` of shape ``(n, k, k)``, ``cards`` the
    ``(card, id, line)`` of each; the first element out of range is refused."""
    if not len(cards):
        return
    with np.errstate(all="ignore"):
        tops = [np.nan_to_num(np.abs(X), nan=np.inf).reshape(len(cards), -1).max(axis=1)
                * scale for X, scale in ((K, 1.0), (M, bulk.wtmass))]
    bad = np.flatnonzero(~((tops[0] <= MAX_MAGNITUDE) & (tops[1] <= MAX_MAGNITUDE)))
    if bad.size:
        e = int(bad[0])
        check_element(bulk, *cards[e], K[e], M[e])


def check_solid_block(bulk: BulkData, index: dict[int, int], conn: np.ndarray, K: sp.coo_array,
                      M: sp.coo_array) -> None:
    """:func:`check_element` of a group of solids assembled together (``conn``: the grid
    indices of its cells): when an entry of the group's ``K`` or ``M`` is out of range, the
    cell of the largest extent (its entries grow with it) is refused."""
    tops = (_largest(K.data), _largest(M.data) * bulk.wtmass)
    if tops[0] <= MAX_MAGNITUDE and tops[1] <= MAX_MAGNITUDE:
        return
    xyz = np.array([bulk.grids[g] for g in index])
    extent = np.ptp(xyz[conn], axis=1).max(axis=1)
    k = int(np.argmax(extent))
    cells = {tuple(index[g] for g in cell.nodes): cell for cell, _ in bulk.solids}
    cell = cells[tuple(int(i) for i in conn[k])]
    what, top = ("stiffness", tops[0]) if tops[0] > MAX_MAGNITUDE else ("mass", tops[1])
    raise _refuse(bulk, cell.kind, cell.id, cell.line, what, top)
