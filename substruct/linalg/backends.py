r"""The registry of sparse factorization backends, and the automatic choice among them.

Four kinds of matrices are factorized (:data:`MATRIX_KINDS`):

=======================  ======================================================================
kind                     where
=======================  ======================================================================
``"spd"``                symmetric positive definite: :math:`K - \sigma M` of shift-invert
                         eigensolves, static condensation, implicit time steps
``"symmetric"``          real symmetric indefinite: the saddle-point (KKT) systems
                         :math:`[B, A^T; A, 0]`
``"complex-symmetric"``  complex symmetric (not Hermitian): the impedances
                         :math:`K - \omega^2 M + i \omega C` of frequency sweeps
``"general"``            any square matrix, real or complex
=======================  ======================================================================

The backends (:data:`BACKENDS`), fastest first as measured on the benchmark models
(docs/performance.md): PARDISO (oneMKL, through the ``pypardiso`` wheels, every kind), CHOLMOD
(SuiteSparse through scikit-sparse, ``"spd"`` only), SuperLU after a METIS nested-dissection
ordering (``pymetis``; the symmetric kinds) and SciPy's SuperLU (always there, every kind).

The saddle points are the exception: PARDISO factorizes them fastest (3.8x SuperLU after METIS
at 30k coordinates) and backward stably, but its pivoting, confined to supernodes, loses
forward accuracy where SuperLU's threshold pivoting keeps it: on a free-free pair of tied
halves (six rigid-body modes, ``K - sigma M`` conditioned 5e9) the generalized-inverse modes
through PARDISO's KKT solves were off by 4e-4, through SuperLU's by 3e-10 (after METIS,
3e-9).  ``auto`` leaves PARDISO out for them; it is there by name.

:func:`auto_factorizer` tries them in the order of :data:`AUTO_ORDER`: a backend that is not
installed is skipped; one that is installed but cannot be loaded, or that fails to factorize
(PARDISO's or CHOLMOD's error on a matrix they should take, out of memory), is skipped, and
named in a :class:`FactorizationFallback` warning (it, the matrix and the backend used) once a
later one succeeds.  The last backend's error is raised unchanged and without warnings
(SuperLU's ``RuntimeError`` for a singular matrix: singular for every backend).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Callable

import scipy.sparse as sp

import substruct.linalg.cholmod as _cholmod
import substruct.linalg.metis as _metis
import substruct.linalg.pardiso as _pardiso
import substruct.linalg.superlu as _slu
from substruct.linalg.solve_type import Factorize, Solve

__all__ = [
    "AUTO_ORDER",
    "BACKENDS",
    "MATRIX_KINDS",
    "FactorizationBackend",
    "FactorizationFallback",
    "auto_backend",
    "auto_factorizer",
    "available_backends",
    "backend_factorizer",
    "backend_status",
]

#: The kinds of matrices factorized (module docstring).
MATRIX_KINDS = ("spd", "symmetric", "complex-symmetric", "general")

_DESCRIBED = {"spd": "symmetric positive definite", "symmetric": "symmetric indefinite",
              "complex-symmetric": "complex symmetric", "general": "square"}


class FactorizationFallback(RuntimeWarning):
    """A backend could not be loaded or failed to factorize; the next one was used."""


@dataclass(frozen=True)
class FactorizationBackend:
    """A factorization backend of the registry.

    Attributes:
        name: the name a case or a call gives (``"pardiso"``).
        label: the name printed (``"PARDISO"``).
        kinds: the :data:`MATRIX_KINDS` it factorizes.
        module: the top-level module whose absence means "not installed".
        load: imports what it needs; raises :class:`ImportError` or :class:`OSError` if it
            cannot be used.
        factorize: ``(A, kind) -> Solve``.
        failures: the exceptions of a factorization that failed (as opposed to a bug).
    """

    name: str
    label: str
    kinds: tuple[str, ...]
    module: str
    load: Callable[[], object]
    factorize: Callable[[sp.sparray | sp.spmatrix, str], Solve]
    failures: Callable[[], tuple[type[BaseException], ...]]


def _superlu(A: sp.sparray | sp.spmatrix, kind: str) -> Solve:
    """SciPy's SuperLU in the mode of each matrix kind (:mod:`substruct.linalg.superlu`)."""
    if kind == "spd":
        return _slu.superlu_spd(A)
    if kind == "symmetric":
        return _slu.superlu_saddle(A)
    if kind == "complex-symmetric":
        return _slu.superlu_complex_symmetric(A)
    return _slu.complex_lu(A)


def _pardiso_kind(A: sp.sparray | sp.spmatrix, kind: str) -> Solve:
    """PARDISO with the matrix type of ``kind`` (``"general"``: real or complex
    unsymmetric by ``A``'s data type)."""
    if kind == "general":
        kind = "complex" if sp.csr_array(A).dtype.kind == "c" else "real"
    return _pardiso.pardiso(A, kind)


def _import_cholmod() -> object:
    import sksparse.cholmod

    return sksparse.cholmod


def _import_metis() -> object:
    import pymetis

    return pymetis


def _pardiso_failures() -> tuple[type[BaseException], ...]:
    return (_pardiso.PardisoError, MemoryError)


def _superlu_failures() -> tuple[type[BaseException], ...]:
    return (RuntimeError, MemoryError)


#: Every backend, by name.
BACKENDS: dict[str, FactorizationBackend] = {
    "pardiso": FactorizationBackend("pardiso", "PARDISO", MATRIX_KINDS, "pypardiso", _pardiso.load_mkl_pardiso,
                       _pardiso_kind, _pardiso_failures),
    "cholmod": FactorizationBackend("cholmod", "CHOLMOD", ("spd",), "sksparse", _import_cholmod,
                       lambda A, kind: _cholmod.cholmod(A), _cholmod.cholmod_failures),
    "superlu-metis": FactorizationBackend("superlu-metis", "SuperLU (METIS)",
                             ("spd", "symmetric", "complex-symmetric"), "pymetis",
                             _import_metis, _metis.superlu_metis, _superlu_failures),
    "superlu": FactorizationBackend("superlu", "SuperLU", MATRIX_KINDS, "scipy", lambda: None, _superlu,
                       _superlu_failures),
}

#: The order :func:`auto_factorizer` tries the backends in, per matrix kind: fastest first as
#: measured by benchmarks/factorization.py (docs/performance.md), SuperLU last; the saddle
#: points without PARDISO (module docstring).
AUTO_ORDER: dict[str, tuple[str, ...]] = {
    "spd": ("pardiso", "cholmod", "superlu-metis", "superlu"),
    "symmetric": ("superlu-metis", "superlu"),
    "complex-symmetric": ("pardiso", "superlu-metis", "superlu"),
    "general": ("pardiso", "superlu"),
}


def backend_status(name: str) -> str | None:
    """``None`` if the backend ``name`` can be used, ``"not installed"`` if its package is
    absent, else why it cannot be loaded (installed but broken)."""
    backend = BACKENDS[name]
    try:
        backend.load()
    except ModuleNotFoundError as exc:
        if exc.name is not None and exc.name.split(".")[0] == backend.module:
            return "not installed"
        return f"{type(exc).__name__}: {exc}"
    except (ImportError, OSError, AttributeError) as exc:
        return f"{type(exc).__name__}: {exc}"
    return None


def available_backends(kind: str) -> list[str]:
    """The backends that can factorize the matrix ``kind`` here, in :data:`AUTO_ORDER`."""
    return [name for name in AUTO_ORDER[_check_kind(kind)] if backend_status(name) is None]


def auto_backend(kind: str) -> str:
    """The backend :func:`auto_factorizer` tries first for the matrix ``kind``: the first of
    :data:`AUTO_ORDER` that loads (the ones after it are not imported)."""
    for name in AUTO_ORDER[_check_kind(kind)]:
        if backend_status(name) is None:
            return name
    raise RuntimeError(f"no factorization backend can be loaded for {_DESCRIBED[kind]} "
                       f"matrices")


def _check_kind(kind: str) -> str:
    if kind not in MATRIX_KINDS:
        raise ValueError(f"unknown matrix kind {kind!r}; expected one of "
                         f"{', '.join(MATRIX_KINDS)}")
    return kind


def backend_factorizer(name: str, kind: str) -> Factorize:
    """The factorization of the matrix ``kind`` by the backend ``name``, without fallback.

    Raises:
        ValueError: an unknown backend, one that does not factorize ``kind``, or one that
            cannot be loaded here (with what to install).
    """
    if name not in BACKENDS:
        raise ValueError(f"unknown factorization backend {name!r}; expected one of "
                         f"{', '.join(BACKENDS)}")
    backend = BACKENDS[name]
    if _check_kind(kind) not in backend.kinds:
        raise ValueError(f"{backend.label} does not factorize {_DESCRIBED[kind]} matrices "
                         f"(it takes: {', '.join(backend.kinds)})")
    status = backend_status(name)
    if status is not None:
        raise ValueError(f"factorization {name!r} cannot be used: {backend.module} {status}")

    def factorize(A: sp.sparray) -> Solve:
        return backend.factorize(A, kind)

    return factorize


def auto_factorizer(kind: str, superlu: Factorize | None = None) -> Factorize:
    """The factorization of the matrix ``kind`` by the first backend of :data:`AUTO_ORDER`
    that loads and succeeds (module docstring); a backend skipped for any reason but its
    absence is named in a :class:`FactorizationFallback` warning.

    ``superlu``: a SuperLU factorization to use in place of the SuperLU backends (both), e.g.
    in an ordering computed once for many matrices of one pattern.
    """
    order = AUTO_ORDER[_check_kind(kind)]
    if superlu is not None:
        order = tuple(name for name in order if not name.startswith("superlu")) + ("superlu",)
    own = superlu

    def factorize(A: sp.sparray) -> Solve:
        what = f"the {A.shape[0]}-coordinate {_DESCRIBED[kind]} matrix"
        skipped: list[str] = []

        def used(backend: FactorizationBackend, solve: Solve) -> Solve:
            """Name the backends skipped before ``backend`` (only once one has succeeded: a
            matrix that no backend factorizes raises the last error, with no warning)."""
            for reason in skipped:
                warnings.warn(f"{reason}; falling back to {backend.label}",
                              FactorizationFallback, stacklevel=3)
            return solve

        for i, name in enumerate(order):
            backend = BACKENDS[name]
            status = backend_status(name)
            if status == "not installed":
                continue
            if status is not None:
                skipped.append(f"{backend.label} cannot be loaded ({status})")
                continue
            if i == len(order) - 1:
                return used(backend, own(A) if own is not None else backend.factorize(A, kind))
            try:
                return used(backend, backend.factorize(A, kind))
            except backend.failures() as exc:
                skipped.append(f"{backend.label} failed on {what} ({exc})")
        raise RuntimeError(f"no factorization backend could factorize {what}")

    return factorize
