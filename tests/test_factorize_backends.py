"""The registry of factorization backends (substruct.linalg.backends): every backend installed
solves the package's three kinds of matrices to its backward error, the numbers of any two
agree to what the matrix's condition allows, ``auto`` uses the backend it names, and the
fallback chain skips an absent backend silently and a broken or failing one loudly."""

from __future__ import annotations

import dataclasses
import re
import sys
import warnings

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from substruct.linalg import backends as bk
from substruct.linalg import factorize as fz
from substruct.linalg.pardiso import PardisoError
from substruct.models.solid import BoxGrid, solid_box

EPS = np.finfo(float).eps
E, NU, RHO = 2.1e11, 0.3, 7850.0
#: the modules whose absence removes each optional backend
MODULES = {"pardiso": ["pypardiso"], "cholmod": ["sksparse", "sksparse.cholmod"],
           "superlu-metis": ["pymetis"]}


def _box():
    return solid_box("b", BoxGrid((2.0, 0.5, 0.5), (14, 4, 4)), E, NU, RHO,
                     fixed=[{"box": [[0, 0, 0], [0, 0.5, 0.5]]}])


@pytest.fixture(scope="module")
def matrices():
    """The three kinds on a clamped 3D box (about 1,000 coordinates): ``K - sigma M``
    (SPD), a saddle point tying 30 pairs of coordinates (symmetric indefinite) and the
    damped impedance between the third and fourth modes (complex symmetric, indefinite)."""
    box = _box()
    K, M = sp.csr_array(box.K), sp.csr_array(box.M)
    n = K.shape[0]
    lam = spla.eigsh(K, k=4, M=M, sigma=-1.0, return_eigenvectors=False)
    lam.sort()
    spd = sp.csr_array(K + 1e-3 * lam[0] * M)
    rng = np.random.default_rng(3)
    pairs = rng.choice(n, size=(30, 2), replace=False)
    A = sp.csr_array((np.tile([1.0, -1.0], 30) / np.sqrt(2),
                      (np.repeat(np.arange(30), 2), pairs.ravel())), shape=(30, n))
    s = float(np.mean(K.diagonal()))
    kkt = sp.csr_array(sp.block_array([[spd, s * A.T], [s * A, None]]))
    w2 = 0.5 * (lam[2] + lam[3])
    Z = sp.csr_array(K * (1 + 0.02j) - w2 * M)
    return {"spd": spd, "symmetric": kkt, "complex-symmetric": Z}


def _rhs(A: sp.sparray, kind: str) -> np.ndarray:
    rng = np.random.default_rng(7)
    b = rng.standard_normal((A.shape[0], 3))
    return b + 1j * rng.standard_normal(b.shape) if kind == "complex-symmetric" else b


def backward_error(A: sp.sparray, x: np.ndarray, b: np.ndarray) -> float:
    r""":math:`\|A x - b\|_1 / (\|A\|_1 \|x\|_1)`, column by column, the largest."""
    r = abs(A @ x - b).sum(axis=0)
    return float(np.max(r / (spla.norm(A, 1) * abs(x).sum(axis=0))))


def condition(A: sp.sparray, solve) -> float:
    r"""Estimated :math:`\kappa_1(A) = \|A\|_1 \|A^{-1}\|_1` (Hager-Higham, ``onenormest``);
    ``A`` symmetric, so :math:`A^{-H} y = \overline{A^{-1} \bar y}`."""
    n = A.shape[0]
    inv = spla.LinearOperator((n, n), matvec=solve, rmatvec=lambda y: np.conj(solve(np.conj(y))),
                              dtype=A.dtype)
    return float(spla.norm(A, 1) * spla.onenormest(inv))


def bound(A: sp.sparray) -> float:
    r"""The backward error of a stable sparse factorization: :math:`10 \sqrt{n}\,\epsilon`
    (rounding in the inner products of the triangular solves, pivot growth below 10)."""
    return 10.0 * np.sqrt(A.shape[0]) * EPS


def present(kind: str) -> list[str]:
    return [name for name in bk.AUTO_ORDER[kind] if bk.backend_status(name) is None]


@pytest.mark.parametrize("kind", ["spd", "symmetric", "complex-symmetric"])
def test_every_installed_backend_solves_to_its_backward_error_and_they_agree(matrices, kind):
    """Backward error below :func:`bound`; two backends' solutions differ by at most
    :math:`\\kappa_1 (\\eta_a + \\eta_b)` (with a factor 10 for the estimate of
    :math:`\\kappa_1`), SuperLU being the reference."""
    A = matrices[kind]
    b = _rhs(A, kind)
    ref = bk.backend_factorizer("superlu", kind)(A)
    x_ref = ref(b)
    eta_ref = backward_error(A, x_ref, b)
    kappa = condition(A, lambda v: ref(v))
    assert kappa > 1e3  # the comparison below is not trivial
    names = present(kind)
    assert "superlu" in names
    for name in names:
        x = bk.backend_factorizer(name, kind)(A)(b)
        eta = backward_error(A, x, b)
        assert eta < bound(A), (name, eta)
        diff = float(np.max(abs(x - x_ref).sum(axis=0) / abs(x_ref).sum(axis=0)))
        assert diff <= 10 * kappa * (eta + eta_ref), (name, diff, kappa)


@pytest.mark.parametrize("kind", ["spd", "symmetric", "complex-symmetric"])
def test_every_installed_backend_takes_a_block_of_no_column(matrices, kind):
    """A block of no right-hand side (an AMLS subdomain without a boundary) gives an empty
    block of the same height on every backend, and a block of one column its solve."""
    A = matrices[kind]
    n = A.shape[0]
    b = _rhs(A, kind)
    for name in present(kind):
        solve = bk.backend_factorizer(name, kind)(A)
        X = np.asarray(solve(np.zeros((n, 0), dtype=b.dtype)))
        assert X.shape == (n, 0), name
        one = np.asarray(solve(b.reshape(n, -1)[:, :1]))
        assert backward_error(A, one, b.reshape(n, -1)[:, :1]) < bound(A), name


@pytest.mark.parametrize("kind", ["spd", "symmetric", "complex-symmetric"])
def test_auto_uses_the_backend_it_names(matrices, kind, monkeypatch):
    """:func:`auto_backend` is the first installed of AUTO_ORDER, and ``auto`` factorizes with
    it and with no other."""
    calls = []
    for name, backend in list(bk.BACKENDS.items()):
        def spy(A, k, _name=name, _f=backend.factorize):
            calls.append(_name)
            return _f(A, k)
        monkeypatch.setitem(bk.BACKENDS, name, dataclasses.replace(backend, factorize=spy))
    first = bk.auto_backend(kind)
    assert first == present(kind)[0]
    A = matrices[kind]
    b = _rhs(A, kind)
    x = bk.auto_factorizer(kind)(A)(b)
    assert calls == [first]
    assert backward_error(A, x, b) < bound(A)


@pytest.mark.parametrize("kind", ["spd", "symmetric", "complex-symmetric"])
def test_absent_backends_are_skipped_silently_down_to_superlu(matrices, kind, monkeypatch):
    """Each optional backend's package made unimportable in turn, in AUTO_ORDER: ``auto``
    moves to the next, warns of nothing, and its numbers stay those of the reference to the
    condition bound of the test above."""
    A = matrices[kind]
    b = _rhs(A, kind)
    ref = bk.backend_factorizer("superlu", kind)(A)
    x_ref = ref(b)
    kappa = condition(A, lambda v: ref(v))
    eta_ref = backward_error(A, x_ref, b)
    for name in bk.AUTO_ORDER[kind][:-1]:
        for module in MODULES[name]:
            monkeypatch.setitem(sys.modules, module, None)
        assert bk.backend_status(name) == "not installed"
        chosen = bk.auto_backend(kind)
        assert chosen == [m for m in present(kind) if m != name][0]
        with warnings.catch_warnings():
            warnings.simplefilter("error", bk.FactorizationFallback)
            x = bk.auto_factorizer(kind)(A)(b)
        eta = backward_error(A, x, b)
        assert eta < bound(A)
        diff = float(np.max(abs(x - x_ref).sum(axis=0) / abs(x_ref).sum(axis=0)))
        assert diff <= 10 * kappa * (eta + eta_ref)
    assert bk.auto_backend(kind) == "superlu"
    monkeypatch.setitem(sys.modules, "pypardiso", None)
    with pytest.raises(ValueError, match="'pardiso' cannot be used: pypardiso not installed"):
        fz.factorizer("pardiso")


def test_a_broken_backend_is_named_and_skipped(matrices, monkeypatch):
    """Installed but not loadable (its shared library missing): a FactorizationFallback
    warning names it, the reason and the backend used instead."""
    def broken():
        raise OSError("libmkl_rt.so.2: cannot open shared object file")

    monkeypatch.setitem(bk.BACKENDS, "pardiso",
                        dataclasses.replace(bk.BACKENDS["pardiso"], load=broken))
    A = matrices["complex-symmetric"]
    b = _rhs(A, "complex-symmetric")
    nxt = [m for m in bk.AUTO_ORDER["complex-symmetric"] if m != "pardiso" and
           bk.backend_status(m) is None][0]
    with pytest.warns(bk.FactorizationFallback,
                      match=rf"PARDISO cannot be loaded \(OSError: libmkl_rt.so.2: cannot "
                            rf"open .*\); falling back to {re.escape(bk.BACKENDS[nxt].label)}"):
        x = bk.auto_factorizer("complex-symmetric")(A)(b)
    assert backward_error(A, x, b) < bound(A)


def test_a_failed_factorization_of_an_spd_matrix_falls_back_and_says_so(matrices,
                                                                       monkeypatch):
    """A backend that fails on a matrix that is SPD (here PARDISO out of memory, code -2):
    the next backend factorizes it and a warning says which failed, on what, and why."""
    def fails(A, kind):
        raise PardisoError(-2, 12)

    monkeypatch.setitem(bk.BACKENDS, "pardiso", dataclasses.replace(
        bk.BACKENDS["pardiso"], load=lambda: None, factorize=fails))
    A = matrices["spd"]
    assert spla.eigsh(A, k=1, sigma=0, return_eigenvectors=False)[0] > 0  # truly SPD
    b = _rhs(A, "spd")
    n = A.shape[0]
    with pytest.warns(bk.FactorizationFallback,
                      match=rf"PARDISO failed on the {n}-coordinate symmetric positive "
                            rf"definite matrix \(PARDISO error -2 in phase 12: not enough "
                            rf"memory\); falling back to"):
        x = fz.factorizer("auto")(A)(b)
    assert backward_error(A, x, b) < bound(A)


@pytest.mark.skipif(bk.backend_status("pardiso") is not None, reason="PARDISO not installed")
def test_pardiso_refuses_what_is_not_spd_and_a_singular_matrix(matrices):
    """PARDISO's Cholesky stops at a negative pivot (error -4) and ``auto`` goes on, saying
    so; a singular complex symmetric matrix is
    refused too (a perturbed pivot) and left to SuperLU, saying so."""
    Z = matrices["complex-symmetric"]
    indefinite = sp.csr_array(Z.real)
    with pytest.raises(PardisoError, match="error -4"):
        bk.backend_factorizer("pardiso", "spd")(indefinite)
    with pytest.warns(bk.FactorizationFallback, match="PARDISO failed .* error -4"):
        x = fz.factorizer("auto")(indefinite)(np.ones(Z.shape[0]))
    assert backward_error(indefinite, x[:, None], np.ones((Z.shape[0], 1))) < bound(Z)
    # a last coordinate repeating the first: its row and column equal the first's
    first = sp.csr_array(Z[:, [0]])
    dup = sp.csr_array(sp.block_array([[Z, first], [first.T, Z[[0]][:, [0]]]]))
    with pytest.raises(PardisoError):
        bk.backend_factorizer("pardiso", "complex-symmetric")(dup)
    with pytest.warns(bk.FactorizationFallback, match=r"PARDISO failed .* pivot\(s\) perturbed"
                                                      r".*; falling back to SuperLU"):
        fz.complex_symmetric(dup)  # SuperLU's pivots are rounding errors: it raises or not


def test_factorizer_names_and_refusals(matrices):
    A = matrices["spd"]
    b = _rhs(A, "spd")
    for name in ["superlu", "auto"] + [m for m in ("pardiso", "cholmod", "superlu-metis")
                                       if bk.backend_status(m) is None]:
        assert backward_error(A, fz.factorizer(name)(A)(b), b) < bound(A)
    with pytest.raises(ValueError, match="'superlu-metis' needs a symmetric positive definite"):
        fz.factorizer("superlu-metis", spd=False)
    with pytest.raises(ValueError, match="CHOLMOD does not factorize symmetric indefinite"):
        bk.backend_factorizer("cholmod", "symmetric")
    with pytest.raises(ValueError, match="unknown matrix kind 'hermitian'"):
        bk.auto_factorizer("hermitian")
    with pytest.raises(ValueError, match="unknown factorization backend 'mumps'"):
        bk.backend_factorizer("mumps", "spd")


@pytest.mark.skipif(bk.backend_status("pardiso") is not None, reason="PARDISO not installed")
@pytest.mark.parametrize("kind", ["spd", "symmetric", "complex-symmetric"])
def test_the_memory_model_covers_what_pardiso_says_it_holds(matrices, kind):
    """PARDISO's peak-memory model is at least the memory PARDISO reports holding after the
    factorization (``iparm[15] + iparm[16]`` kB: its permanent data and the factor), and its
    growing part :math:`c \\operatorname{nnz}(A) n^p` at most 4 times that (the measured peaks
    the model was fitted to include the matrix copies and a solve)."""
    from substruct.linalg.memory import PEAK, factor_memory

    A = matrices[kind]
    solve = bk.backend_factorizer("pardiso", kind)(A)
    ip = solve.handle.iparm
    held = 1024.0 * (int(ip[15]) + int(ip[16]))
    model = factor_memory(A, "pardiso", matrix=kind)
    assert model >= held
    assert model - PEAK[("pardiso", kind)][0] <= 4 * held, (held, model)
