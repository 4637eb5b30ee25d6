r"""Ansys ``.full`` files: the assembled stiffness and mass matrices that Mechanical APDL
writes (``Jobname.FULL``), with the map of their equations by node and degree of freedom.

The file is a sequence of Fortran-style binary records, each
``[n] [flags] [n 4-byte words] [n]``: ``n`` counts the data's 4-byte words, ``flags`` has its
top bit set for integers and is 0 for double-precision reals. MAPDL may write a record
compressed, flagged in the top byte: ``0x10000000`` windowed sparse (the count of values, the
count of windows, each window one value at an index, a run of values, or one value repeated),
``0x08000000`` bit sparse (at most 32 values and a mask of the non-zero ones); both are
expanded, their sizes checked before anything is allocated (a record of
``0x90000000``, integers in windows, holds the DOF table of ``sparse.full``, for instance).
Zlib-compressed (``0x20000000``) and single-precision (``0x40000000``) records are refused,
naming their flags. What is read:

1. the standard header (100 integers; item 1, the file number, is 4 for a FULL file);
2. the FULL header: item 1 ``-4``, ``neqn`` (equations), ``wfmax`` (longest column), ``lenbac`` (nodes), ``numdof`` (degrees of freedom a node), ``ntermK`` (terms of
   ``K``, two words), ``lumpm`` (lumped mass), ``keyuns`` (unsymmetric), ``extopt``,
   ``ncefull`` (constraint equations), ``ptrSTF``, ``ptrMAS``, ``ptrDMP``, ``ptrDOF``,
   ``nNodes``, ``ntermM`` (pointers in 4-byte words from the start of the file);
3. the DOF labels (``numdof`` integers; 1-6 are ``UX UY UZ ROTX ROTY ROTZ``) and the nodal
   equivalence table (the node number of each of the ``nNodes`` nodes, in equation order);
4. at ``ptrSTF`` and ``ptrMAS``, per equation ``j`` (column), a record of row numbers
   (1-based) and a record of as many doubles: one triangle of the symmetric matrix;
5. at ``ptrDOF``, the degrees of freedom of each node and the constraint table (a negative
   entry marks an equation held by a constraint; MAPDL keeps it with a unit diagonal).

The load vector (``ptrRHS``) and the other tables are not read. The equations are ``numdof``
per node, in the order of the equivalence table; the result is
``A = T + T^T - \operatorname{diag} T`` of the triangle ``T`` read, without the constrained
equations, sorted by (node, degree of freedom).

Refused, in one line naming the file, the record and the problem: a file that is not a FULL
file (standard-header file number, FULL header key), a lumped mass (``lumpm``), unsymmetric
matrices (``keyuns``), the frontal and other layouts (``extopt`` 3 and 4), constraint
equations (``ncefull``), a damping matrix (``ptrDMP``), values that are not real double
precision (complex or single, by the record flags), zlib-compressed records, a compressed
record whose windows or mask disagree with its words or its declared count, a node whose degrees of freedom differ
from ``numdof``, a label outside 1-6, a record whose length or end marker disagree with the
file or with the header, a row number outside ``1..neqn``, a term given twice, a value that is
not finite. Sizes are checked before anything is allocated: the file (2 GB), the equations
(:data:`~substruct.case.fields.MAX_MATRIX_SIZE`), the terms against the file's words.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.sparse as sp

from substruct.case.errors import CaseError
from substruct.case.fields import MAX_MATRIX_SIZE

__all__ = ["FullMatrices", "read_full", "MAX_FULL_FILE", "FULL_LABELS"]

#: Largest ``.full`` file read (bytes).
MAX_FULL_FILE = 2_000_000_000
#: Ansys DOF labels read, by number: the components 1-6 of a grid.
FULL_LABELS = {1: "UX", 2: "UY", 3: "UZ", 4: "ROTX", 5: "ROTY", 6: "ROTZ"}
_INT_FLAG = -2**31      # 0x80000000: an integer record
_REAL_FLAG = 0          # a double-precision real record
_SINGLE = 0x40000000    # single precision (short integers)
_ZLIB = 0x20000000      # zlib-compressed
_WSPARSE = 0x10000000   # windowed sparse: windows of values or of one repeated value
_BSPARSE = 0x08000000   # bit sparse: at most 32 values, a bit for each non-zero


class FullMatrices:
    """What :func:`read_full` read.

    Attributes:
        K, M: symmetric, CSC, over the free equations sorted by (node, degree of freedom).
        dofs: the ``(node, component)`` (1-6) of each row.
        constrained: the ``(node, component)`` of the equations held by constraints (left out).
    """

    def __init__(self, K: sp.csc_matrix, M: sp.csc_matrix, dofs: list[tuple[int, int]],
                 constrained: list[tuple[int, int]]):
        self.K, self.M, self.dofs, self.constrained = K, M, dofs, constrained


class _Records:
    """The 4-byte words of a file and the records in them."""

    def __init__(self, words: np.ndarray, name: str, order: str):
        self.w, self.name, self.real = words, name, np.dtype(order + "f8")

    def error(self, where: str, problem: str) -> CaseError:
        return CaseError(self.name, where, problem)

    def record(self, pos: int, what: str, flag: int,
               most: int = MAX_MATRIX_SIZE) -> tuple[np.ndarray, int]:
        """The data of the record at word ``pos`` (a compressed record expanded, to at most
        ``most`` values) and the position after it."""
        w = self.w
        if pos < 0 or pos + 2 > len(w):
            raise self.error(what, f"record at word {pos} lies beyond the end of the file "
                             f"({len(w)} words): the file is truncated")
        n = int(w[pos])
        if n < 0 or pos + 3 + n > len(w):
            raise self.error(what, f"record at word {pos} declares {n} words, but "
                             f"{len(w) - pos - 3} are left in the file")
        if int(w[pos + 2 + n]) != n:
            raise self.error(what, f"record at word {pos} declares {n} words but ends with "
                             f"the length {int(w[pos + 2 + n])}: wrong record length")
        flags = int(w[pos + 1]) & 0xFFFFFFFF
        want = flag & 0xFFFFFFFF
        kind = "integers" if flag == _INT_FLAG else "double-precision reals"
        data = w[pos + 2:pos + 2 + n]
        if flags == want:
            return data, pos + 3 + n
        form = flags & ~0x80000000
        if flags & 0x80000000 == want and form in (_WSPARSE, _BSPARSE):
            return self._expand(data, pos, what, form, flag == _INT_FLAG, most), pos + 3 + n
        problem = ("a zlib-compressed record" if flags & _ZLIB else
                   "a single-precision record" if flags & _SINGLE else
                   "an integer record" if flags & 0x80000000 else "a real record"
                   if flags & ~0x80000000 in (0, _WSPARSE, _BSPARSE) else "an unknown form")
        raise self.error(what, f"record at word {pos} has flags {flags:#x}, not {kind}: "
                         f"{problem}; read are plain records ({want:#x}) and the compressed "
                         f"forms windowed sparse ({want | _WSPARSE:#x}) and bit sparse "
                         f"({want | _BSPARSE:#x})")

    def _expand(self, data: np.ndarray, pos: int, what: str, form: int, ints: bool,
                most: int) -> np.ndarray:
        """The values of a compressed record, as the words a plain record would hold.

        Both forms start with the count of values ``size``.  Windowed sparse
        (``0x10000000``): then the count of windows, each either ``i > 0`` and one value
        at 0-based index ``i``, or ``-start`` and ``length``: ``length`` values from
        ``start`` on, or (``length < 0``) one value repeated ``-length`` times.  Bit sparse
        (``0x08000000``): then a 32-bit mask, bit ``k`` set for each stored value ``k``
        (so ``size <= 32``).  Values not stored are 0."""
        step = 1 if ints else 2          # words of a value
        where = f"{form | (0x80000000 if ints else 0):#x} record at word {pos}"

        def bad(problem: str) -> CaseError:
            return self.error(what, f"{where}: {problem}")

        if len(data) < 2:
            raise bad(f"{len(data)} words, fewer than its 2-word head")
        size = int(data[0])
        if not 0 <= size <= most:
            raise bad(f"{size} values declared; 0 to {most} are accepted here")
        out = np.zeros(size * step, dtype=data.dtype)

        def values(at: int, count: int) -> np.ndarray:
            if at + count * step > len(data):
                raise bad(f"its values run past its {len(data)} words")
            return data[at:at + count * step]

        if form == _BSPARSE:
            if size > 32:
                raise bad(f"{size} values declared, a 32-bit mask holds at most 32")
            mask = int(data[1]) & 0xFFFFFFFF
            if mask >> size:
                raise bad(f"mask {mask:#x} marks values beyond the {size} declared")
            at = 2
            for k in range(size):
                if mask >> k & 1:
                    out[k * step:(k + 1) * step] = values(at, 1)
                    at += step
            if at != len(data):
                raise bad(f"{len(data) - at} words left after its values")
            return out
        nwin = int(data[1])
        if not 0 <= nwin <= len(data):
            raise bad(f"{nwin} windows declared in {len(data)} words")
        at, end = 2, 0                   # end: the first index after the last window
        for k in range(nwin):
            if at >= len(data):
                raise bad(f"window {k + 1} of {nwin} lies past its {len(data)} words")
            loc = int(data[at])
            at += 1
            if loc > 0:                  # one value at index loc
                start, count, repeat = loc, 1, False
            else:
                if at >= len(data):
                    raise bad(f"window {k + 1} has no length")
                start, length = -loc, int(data[at])
                at += 1
                if length == 0:
                    raise bad(f"window {k + 1} (at index {start}) has length 0")
                count, repeat = abs(length), length < 0
            if start < end or start + count > size:
                raise bad(f"window {k + 1} covers indices {start} to {start + count - 1}, "
                          f"not after the previous window and within 0 to {size - 1}")
            got = values(at, 1 if repeat else count)
            at += len(got)
            block = np.tile(got, count) if repeat else got
            out[start * step:(start + count) * step] = block
            end = start + count
        if at != len(data):
            raise bad(f"{len(data) - at} words left after its {nwin} windows")
        return out


def _long(low: int, high: int) -> int:
    return (high << 32) | (low & 0xFFFFFFFF)


def _triangle(rec: _Records, ptr: int, neqn: int, nterm: int, wfmax: int,
              what: str) -> sp.csc_matrix:
    """The symmetric matrix whose triangle, column by column, starts at word ``ptr``."""
    if not 0 < ptr < len(rec.w):
        raise rec.error(f"{what} pointer", f"word {ptr} lies outside the file "
                        f"({len(rec.w)} words)")
    if nterm > len(rec.w):   # each term takes at least its row word (values may be compressed)
        raise rec.error(f"{what} terms", f"{nterm} terms declared, more than the file's "
                        f"{len(rec.w)} words can hold")
    most = min(wfmax, neqn)  # values a column's (compressed) record may expand to
    rows, vals, counts = [], [], np.empty(neqn, np.int64)
    pos, total = ptr, 0
    for j in range(neqn):
        idx, pos = rec.record(pos, f"{what} column {j + 1} rows", _INT_FLAG, most)
        raw, pos = rec.record(pos, f"{what} column {j + 1} values", _REAL_FLAG, most)
        if len(raw) != 2 * len(idx):
            raise rec.error(f"{what} column {j + 1} values", f"{len(raw) // 2} values for "
                            f"{len(idx)} rows")
        if len(idx) > wfmax:
            raise rec.error(f"{what} column {j + 1} rows", f"{len(idx)} rows, more than the "
                            f"longest column of the header (wfmax {wfmax})")
        total += len(idx)
        if total > nterm:
            raise rec.error(f"{what} column {j + 1}", f"more terms than the {nterm} the "
                            "header declares")
        if len(idx) and (idx.min() < 1 or idx.max() > neqn):
            bad = int(idx[(idx < 1) | (idx > neqn)][0])
            raise rec.error(f"{what} column {j + 1} rows", f"row {bad} is outside 1..{neqn}")
        rows.append(idx - 1)
        vals.append(np.frombuffer(raw.tobytes(), rec.real))
        counts[j] = len(idx)
    if total != nterm:
        raise rec.error(what, f"{total} terms read, but the header declares {nterm}")
    r = np.concatenate(rows) if rows else np.empty(0, np.int64)
    c = np.repeat(np.arange(neqn), counts)
    v = np.concatenate(vals).astype(np.float64) if vals else np.empty(0)
    if not np.all(np.isfinite(v)):
        k = int(np.flatnonzero(~np.isfinite(v))[0])
        raise rec.error(f"{what} column {int(c[k]) + 1}", f"row {int(r[k]) + 1} holds "
                        f"{float(v[k])!r}, not a finite number")
    lo, hi = np.minimum(r, c), np.maximum(r, c)
    key = hi * neqn + lo
    order = np.argsort(key, kind="stable")
    dup = np.flatnonzero(np.diff(key[order]) == 0)
    if len(dup):
        k = int(order[dup[0] + 1])
        raise rec.error(f"{what} column {int(c[k]) + 1}", f"term ({int(hi[k]) + 1}, "
                        f"{int(lo[k]) + 1}) is given twice (both triangles or twice in a "
                        "column)")
    T = sp.coo_matrix((v, (lo, hi)), shape=(neqn, neqn)).tocsc()
    return (T + T.T - sp.diags(T.diagonal())).tocsc()


def read_full(path: Path, name: str) -> FullMatrices:
    """Read the stiffness and mass matrices of the Ansys FULL file ``path`` (``name`` in
    messages); see the module for what is read and refused.

    Raises:
        CaseError: one line naming ``name``, the record and the problem.
    """
    size = path.stat().st_size
    if size > MAX_FULL_FILE:
        raise CaseError(name, "", f"{size} bytes, more than the {MAX_FULL_FILE} read")
    data = path.read_bytes()
    if len(data) < 8 or len(data) % 4:
        raise CaseError(name, "", f"{len(data)} bytes, not a whole number of 4-byte words of "
                        "an Ansys binary file")
    order = ">" if int.from_bytes(data[:4], "big") == 100 else "<"
    words = np.frombuffer(data, order + "i4")
    if int(words[0]) != 100:
        raise CaseError(name, "standard header", "an Ansys binary file starts with a "
                        "100-word record (either byte order)", int(words[0]))
    rec = _Records(words, name, order)
    std, pos = rec.record(0, "standard header", _INT_FLAG)
    if int(std[0]) != 4:
        raise rec.error("standard header", f"file number {int(std[0])}, not 4 (a FULL file)")
    h, pos = rec.record(pos, "FULL header", _INT_FLAG)
    if len(h) < 41:
        raise rec.error("FULL header", f"{len(h)} words, fewer than the 41 read")
    item = [int(x) for x in h]
    if item[0] != -4:
        raise rec.error("FULL header", f"key {item[0]}, not -4 (the sparse assembly layout "
                        "read)")
    neqn, lenbac, numdof = item[1], item[6], item[7]
    for what, value in (("lumpm", item[10]), ("keyuns", item[13]), ("ncefull", item[20]),
                        ("ptrDMP", _long(item[28], item[29]))):
        if value != 0:
            problem = {"lumpm": "a lumped mass matrix is not read",
                       "keyuns": "unsymmetric matrices are not read",
                       "ncefull": "constraint equations are not read",
                       "ptrDMP": "a damping matrix is not read"}[what]
            raise rec.error(f"FULL header {what}", f"{problem}, got {value}")
    if item[14] in (3, 4):
        raise rec.error("FULL header extopt", f"layout {item[14]} is not read (3 and 4 store "
                        "the matrices otherwise)")
    nnodes = item[32]
    if not 1 <= neqn <= MAX_MATRIX_SIZE:
        raise rec.error("FULL header neqn", f"{neqn} equations, not 1 to {MAX_MATRIX_SIZE}")
    if not 1 <= numdof <= 6 or nnodes != lenbac or nnodes * numdof != neqn:
        raise rec.error("FULL header", f"{nnodes} nodes of {numdof} degrees of freedom do not "
                        f"make the {neqn} equations")
    labels, pos = rec.record(pos, "DOF labels", _INT_FLAG)
    if len(labels) != numdof or any(int(x) not in FULL_LABELS for x in labels):
        raise rec.error("DOF labels", f"{numdof} labels from 1 to 6 (UX-ROTZ) are read, got "
                        f"{[int(x) for x in labels]}")
    nodes, pos = rec.record(pos, "nodal equivalence table", _INT_FLAG)
    if len(nodes) != nnodes or nodes.min() < 1 or len(np.unique(nodes)) != nnodes:
        raise rec.error("nodal equivalence table", f"{nnodes} distinct positive node numbers "
                        f"expected, got {len(nodes)} entries")
    ndof, pos = rec.record(_long(item[35], item[36]), "DOF table", _INT_FLAG, nnodes)
    if len(ndof) != nnodes or np.any(ndof != numdof):
        raise rec.error("DOF table", f"every one of the {nnodes} nodes must have the "
                        f"{numdof} degrees of freedom of the header")
    const, pos = rec.record(pos, "constraint table", _INT_FLAG, neqn)
    if len(const) != neqn:
        raise rec.error("constraint table", f"{len(const)} entries for {neqn} equations")
    K = _triangle(rec, _long(item[18], item[19]), neqn, _long(item[8], item[9]), item[5], "K")
    M = _triangle(rec, _long(item[26], item[27]), neqn, _long(item[33], item[21]), item[5], "M")
    node_of = np.repeat(nodes.astype(np.int64), numdof)
    comp_of = np.tile(labels.astype(np.int64), nnodes)
    free = np.flatnonzero(const >= 0)
    free = free[np.lexsort((comp_of[free], node_of[free]))]
    held = np.flatnonzero(const < 0)
    dofs = [(int(node_of[i]), int(comp_of[i])) for i in free]
    constrained = [(int(node_of[i]), int(comp_of[i])) for i in held]
    return FullMatrices(K[free][:, free].tocsc(), M[free][:, free].tocsc(), dofs, constrained)
