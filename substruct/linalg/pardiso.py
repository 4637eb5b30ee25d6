r"""PARDISO (Intel oneMKL) through the library the ``pypardiso`` wheel installs.

``pypardiso`` exposes one matrix type (real unsymmetric, ``mtype = 11``) and real data only;
the factorizations here call the same ``pardiso`` routine of ``mkl_rt`` (found by
``pypardiso``) directly, with the matrix type of the system:

==================================  ======  ================================================
matrix                              mtype   method
==================================  ======  ================================================
real symmetric positive definite      2     Cholesky :math:`L L^T`, upper triangle given
real symmetric indefinite (KKT)      -2     :math:`L D L^T`, Bunch-Kaufman pivots in
                                            supernodes, weighted matching and scaling
complex symmetric (sweeps)            6     the same in complex arithmetic (:math:`A = A^T`,
                                            not Hermitian)
real unsymmetric                     11     :math:`L U`, matching and scaling
complex unsymmetric                  13     the same in complex arithmetic
==================================  ======  ================================================

Each factorization orders with METIS nested dissection (``iparm[1] = 2``), runs the analysis
and numeric phases (12) once, keeps its own handle and frees it (phase -1) when the solve
that holds it is collected.  A factorization in which PARDISO had to perturb pivots (smaller
than :math:`10^{-8} \|A\|` for the indefinite types, ``iparm[13] > 0``) is refused as singular
to working precision (:class:`PardisoError`, code -4) rather than solved with the nearby matrix:
SciPy's SuperLU then factorizes it or reports it singular (none of the benchmark matrices has
a perturbed pivot).  Solves with a real symmetric indefinite (KKT) factor take two steps of
iterative refinement each (``iparm[7] = 2``): PARDISO's pivoting within supernodes leaves
residuals about a thousand times SciPy's on the benchmark KKT matrices without them
(:math:`\|A x - b\| / \|b\|` 6.9e-11, with them 6.9e-14, at 3k coordinates).
"""

from __future__ import annotations

import ctypes
import os
import sys
import weakref
from pathlib import Path
from typing import Any, Callable

import numpy as np
import scipy.sparse as sp

__all__ = ["MTYPES", "PardisoError", "pardiso_available", "load_mkl_pardiso", "mkl_wheel_library",
           "pardiso", "pardiso_factor_entries"]

#: PARDISO's matrix type for each matrix kind of :mod:`substruct.linalg.backends`.
MTYPES = {"spd": 2, "symmetric": -2, "complex-symmetric": 6, "real": 11, "complex": 13}

_MESSAGES = {-1: "input inconsistent", -2: "not enough memory", -3: "reordering problem",
             -4: "zero pivot (not positive definite for mtype 2)", -5: "unclassified error",
             -6: "preordering failed", -7: "diagonal matrix is singular",
             -8: "32-bit integer overflow", -9: "not enough memory for out-of-core",
             -10: "error opening out-of-core files", -11: "read/write error with OOC files",
             -12: "pardiso_64 called from a 32-bit library", -13: "interrupted"}

_I32 = ctypes.POINTER(ctypes.c_int32)
_LIB: list[Any] = []


class PardisoError(RuntimeError):
    """PARDISO returned a nonzero error code (:attr:`code`)."""

    def __init__(self, code: int, phase: int, message: str | None = None):
        self.code = code
        super().__init__(f"PARDISO error {code} in phase {phase}: "
                         f"{message or _MESSAGES.get(code, 'unknown error')}")


def mkl_wheel_library() -> str | None:
    """The path of the ``mkl_rt`` library the ``mkl`` wheel installed, from the wheel's own
    list of its files (``None`` without the wheel, e.g. MKL from conda or the system).

    Given to ``pypardiso`` (its ``PYPARDISO_MKL_RT``) while it is imported: without it,
    ``pypardiso`` searches for the library with ``ctypes.util.find_library`` (which runs
    ``ldconfig``, the C compiler and the linker) and then by walking every folder of the
    environment, 0.15-0.25 s of CPU time at each start of a process that factorizes.
    """
    from importlib import metadata

    try:
        files = metadata.files("mkl") or []
    except metadata.PackageNotFoundError:
        return None
    for file in sorted((f for f in files if "mkl_rt" in f.name), key=lambda f: len(str(f))):
        path = Path(str(file.locate()))
        try:
            ctypes.CDLL(str(path))  # loaded once: pypardiso's load of it is then a lookup
        except OSError:
            continue
        return str(path)
    return None


def _import_pypardiso() -> Any:
    """``import pypardiso``, its library named by :func:`mkl_wheel_library` when the user has
    not named one (``PYPARDISO_MKL_RT``); the variable is not left set."""
    if "pypardiso" in sys.modules or "PYPARDISO_MKL_RT" in os.environ:
        import pypardiso

        return pypardiso
    found = mkl_wheel_library()
    if found is not None:
        os.environ["PYPARDISO_MKL_RT"] = found
    try:
        import pypardiso  # optional dependency: x86_64 Linux and Windows wheels (with mkl)
    finally:
        if found is not None:
            os.environ.pop("PYPARDISO_MKL_RT", None)
    return pypardiso


def load_mkl_pardiso() -> Any:
    """The ``pardiso`` routine of the ``mkl_rt`` library ``pypardiso`` found (imported here,
    each call, so an uninstalled ``pypardiso`` raises :class:`ImportError`)."""
    pypardiso = _import_pypardiso()

    if not _LIB:
        fn = pypardiso.ps.libmkl.pardiso
        fn.restype = None
        fn.argtypes = [ctypes.POINTER(ctypes.c_int64), _I32, _I32, _I32, _I32, _I32,
                       ctypes.c_void_p, _I32, _I32, _I32, _I32, _I32, _I32,
                       ctypes.c_void_p, ctypes.c_void_p, _I32]
        _LIB.append(fn)
    return _LIB[0]


def pardiso_available() -> bool:
    """Whether PARDISO can be loaded (``pypardiso`` importable and its ``mkl_rt`` found)."""
    try:
        load_mkl_pardiso()
    except (ImportError, OSError, AttributeError):
        return False
    return True


class _Handle:
    """One PARDISO factorization: its handle ``pt``, parameters and matrix arrays (kept alive
    for the iterative refinement of the solves)."""

    def __init__(self, mtype: int, n: int, data: np.ndarray, indptr: np.ndarray,
                 indices: np.ndarray):
        self.fn = load_mkl_pardiso()
        self.pt = np.zeros(64, dtype=np.int64)
        self.iparm = np.zeros(64, dtype=np.int32)
        ip = self.iparm
        ip[0] = 1    # parameters given
        ip[1] = 2    # METIS nested dissection
        ip[7] = 2 if mtype == -2 else 0  # iterative refinement steps: KKT always (docstring)
        ip[9] = 8 if mtype in (-2, 6) else 13  # pivot perturbation 1e-8 / 1e-13
        ip[10] = 0 if mtype == 2 else 1        # scaling ...
        ip[12] = 0 if mtype == 2 else 1        # ... and weighted matching (indefinite)
        ip[17] = -1  # report nnz(factor)
        ip[34] = 1   # zero-based indices
        self.mtype, self.n = mtype, n
        self.data, self.indptr, self.indices = data, indptr, indices
        self.dtype = data.dtype

    def call(self, phase: int, b: np.ndarray | None = None, x: np.ndarray | None = None,
             nrhs: int = 1) -> None:
        err = ctypes.c_int32(0)
        one = ctypes.c_int32(1)
        self.fn(self.pt.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)), ctypes.byref(one),
                ctypes.byref(one), ctypes.byref(ctypes.c_int32(self.mtype)),
                ctypes.byref(ctypes.c_int32(phase)), ctypes.byref(ctypes.c_int32(self.n)),
                self.data.ctypes.data, self.indptr.ctypes.data_as(_I32),
                self.indices.ctypes.data_as(_I32), None, ctypes.byref(ctypes.c_int32(nrhs)),
                self.iparm.ctypes.data_as(_I32), ctypes.byref(ctypes.c_int32(0)),
                None if b is None else b.ctypes.data, None if x is None else x.ctypes.data,
                ctypes.byref(err))
        if err.value != 0:
            raise PardisoError(int(err.value), phase)


def _release(fn: Any, pt: np.ndarray, mtype: int, n: int) -> None:
    """Free a handle's memory (phase -1)."""
    err = ctypes.c_int32(0)
    one = ctypes.c_int32(1)
    ip = np.zeros(64, dtype=np.int32)
    fn(pt.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)), ctypes.byref(one), ctypes.byref(one),
       ctypes.byref(ctypes.c_int32(mtype)), ctypes.byref(ctypes.c_int32(-1)),
       ctypes.byref(ctypes.c_int32(n)), None, None, None, None, ctypes.byref(one),
       ip.ctypes.data_as(_I32), ctypes.byref(ctypes.c_int32(0)), None, None, ctypes.byref(err))


def _stored(A: sp.sparray | sp.spmatrix, symmetric: bool, dtype: type) -> sp.csr_array:
    """The CSR matrix PARDISO reads: the upper triangle for the symmetric types, with every
    diagonal entry stored (an explicit zero where ``A`` has none, as PARDISO requires), sorted
    indices, 32-bit."""
    A = sp.csr_array(A, dtype=dtype)
    if not symmetric:
        A.sort_indices()
        return A
    U = sp.coo_array(sp.triu(A, format="coo"))
    n = A.shape[0]
    d = np.arange(n)
    S = sp.coo_array((np.concatenate([U.data, np.zeros(n, dtype=dtype)]),
                      (np.concatenate([U.row, d]), np.concatenate([U.col, d]))),
                     shape=A.shape).tocsr()  # duplicates summed, explicit zeros kept
    S.sort_indices()
    return sp.csr_array(S)


def pardiso(A: sp.sparray | sp.spmatrix, kind: str) -> Callable[[np.ndarray], np.ndarray]:
    r"""PARDISO factorization of the square sparse ``A`` as the matrix ``kind`` of
    :data:`MTYPES` (``"spd"``, ``"symmetric"``, ``"complex-symmetric"``, ``"real"``,
    ``"complex"``); returns the solve ``b -> A^{-1} b`` (``b`` a vector or ``n x k`` block).
    A real factor solves a complex ``b`` as its real and imaginary parts in one call.

    Raises:
        PardisoError: the factorization failed (e.g. code -4 for an ``"spd"`` matrix that is
            not positive definite, -2 out of memory).
        ImportError: ``pypardiso`` is not installed.
    """
    mtype = MTYPES[kind]
    complex_ = mtype in (6, 13)
    dtype = complex if complex_ else float
    if not complex_ and np.iscomplexobj(sp.csr_array(A).data):
        raise ValueError(f"PARDISO {kind!r} needs a real matrix")
    S = _stored(A, mtype in (2, -2, 6), dtype)
    n = S.shape[0]
    h = _Handle(mtype, n, S.data, S.indptr.astype(np.int32), S.indices.astype(np.int32))
    weakref.finalize(h, _release, h.fn, h.pt, mtype, n)
    h.call(12)

    def solve(b: np.ndarray) -> np.ndarray:
        b = np.asarray(b)
        vector = b.ndim == 1
        B = b.reshape(n, -1)
        if not complex_ and np.iscomplexobj(B):
            k = B.shape[1]
            X = run(np.hstack([B.real, B.imag]))
            X = X[:, :k] + 1j * X[:, k:]
        else:
            X = run(B)
        return X.ravel() if vector else X

    def run(B: np.ndarray) -> np.ndarray:
        Bf = np.array(B, dtype=h.dtype, order="F")  # a copy: PARDISO may write to it
        X = np.zeros_like(Bf)
        if Bf.shape[1]:  # no right-hand side: nothing to solve (PARDISO refuses nrhs = 0)
            h.call(33, Bf, X, Bf.shape[1])
        return X

    if h.iparm[13] > 0:  # pivots below 1e-8 ||A|| replaced: singular or nearly so
        raise PardisoError(-4, 12, f"{int(h.iparm[13])} pivot(s) perturbed: singular to "
                                   f"working precision")
    solve.handle = h  # type: ignore[attr-defined]
    return solve


def pardiso_factor_entries(solve: Callable[[np.ndarray], np.ndarray]) -> int:
    """The nonzeros of the factor of a :func:`pardiso` solve, as PARDISO reports them
    (``iparm[17]``)."""
    return int(solve.handle.iparm[17])  # type: ignore[attr-defined]
