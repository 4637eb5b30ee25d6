"""The beam elements computed all at once (substruct/models/beam_batch.py) are the elements
computed one at a time (substruct/models/beam.py), and a frame built with them is the frame
assembled element by element."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from substruct.models.beam import Material, Section, beam_matrices
from substruct.models.beam_batch import BeamBatch, beam_matrices_batch
from substruct.models.frame import Beam, frame


def _random_batch(n: int, seed: int = 1) -> BeamBatch:
    rng = np.random.default_rng(seed)
    xa = rng.normal(size=(n, 3))
    E = rng.uniform(1, 3, n) * 1e11
    Iy, Iz = rng.uniform(1, 5, n) * 1e-6, rng.uniform(1, 5, n) * 1e-6
    return BeamBatch(xa, xa + rng.normal(size=(n, 3)), rng.normal(size=(n, 3)), E, E / 2.6,
                     rng.uniform(1, 8, n) * 1e3, rng.uniform(1, 5, n) * 1e-3, Iy, Iz,
                     Iy + Iz, 1.1 * (Iy + Iz), rng.uniform(.5, 1, n), rng.uniform(.5, 1, n),
                     rng.random(n) < .5)


@pytest.mark.parametrize("mass", ["consistent", "lumped"])
def test_each_batched_element_is_the_element_alone(mass):
    """Random lengths, orientations, sections, materials, both theories: every element's K
    and M equal beam_matrices' to 1e-14 of their largest entry (measured 7e-16)."""
    b = _random_batch(60)
    K, M, ok = beam_matrices_batch(b, mass)
    assert ok.all()
    for e in range(60):
        Ks, Ms = beam_matrices(b.xa[e], b.xb[e], b.v[e],
                               Section(b.A[e], b.Iy[e], b.Iz[e], b.J[e], b.ky[e], b.kz[e],
                                       b.Ip[e]),
                               Material(b.E[e], b.G[e], b.rho[e]),
                               "timoshenko" if b.timoshenko[e] else "euler-bernoulli", mass)
        assert np.abs(K[e] - Ks).max() <= 1e-14 * np.abs(Ks).max()
        assert np.abs(M[e] - Ms).max() <= 1e-14 * np.abs(Ms).max()


def test_refused_elements_are_flagged():
    b = _random_batch(3)
    v = b.v.copy()
    v[1] = b.xb[1] - b.xa[1]  # along the axis
    xb = b.xb.copy()
    xb[2] = b.xa[2]  # no length
    _, _, ok = beam_matrices_batch(BeamBatch(b.xa, xb, v, *[getattr(b, k) for k in (
        "E", "G", "rho", "A", "Iy", "Iz", "J", "Ip", "ky", "kz", "timoshenko")]))
    assert ok.tolist() == [True, False, False]


MAT = Material(E=2.1e11, G=8.1e10, rho=7850.0)
SEC = Section(A=2.85e-3, Iy=1.943e-5, Iz=1.42e-6, J=6.98e-8, ky=.8, kz=.7)
NODES = {1: (0.0, 0.0, 0.0), 2: (0.0, 0.0, 3.0), 5: (2.0, 0.5, 3.0), 3: (4.0, 0.0, 3.2),
         4: (4.0, 0.0, 0.0)}


@pytest.mark.parametrize("mass", ["consistent", "lumped"])
def test_frame_is_assembled_as_element_by_element(mass):
    """A portal with pins, both theories and several divisions: K and M equal the sum of
    beam_matrices over its elements (with the releases) to 1e-13."""
    members = [Beam((1, 2), SEC, MAT, (0.0, 1.0, 0.0), divisions=3),
               Beam((2, 5), SEC, MAT, (0.0, 0.0, 1.0), "timoshenko", 4, pin_b="56"),
               Beam((5, 3), SEC, MAT, (0.0, 0.0, 1.0), "timoshenko", 2, pin_a="4"),
               Beam((3, 4), SEC, MAT, (1.0, 1.0, 0.0), divisions=5)]
    f = frame("p", NODES, members, mass=mass)
    xyz = np.asarray(f.meta["node_xyz"])
    n = 6 * len(xyz)
    K, M = sp.lil_array((n, n)), sp.lil_array((n, n))
    k = 0
    for m in members:
        for d in range(m.divisions):
            i, j = f.meta["elements"][k]
            k += 1
            # pin digit c is local coordinate c - 1 at end A, 6 + c - 1 at end B
            rel = ([int(c) - 1 for c in m.pin_a] if d == 0 else []) + \
                ([5 + int(c) for c in m.pin_b] if d == m.divisions - 1 else [])
            Ke, Me = beam_matrices(xyz[i], xyz[j], m.orientation, m.section, m.material,
                                   m.theory, mass, rel)
            dofs = np.concatenate([6 * i + np.arange(6), 6 * j + np.arange(6)])
            K[np.ix_(dofs, dofs)] += Ke
            M[np.ix_(dofs, dofs)] += Me
    for got, ref in ((f.K, K), (f.M, M)):
        ref = ref.toarray()
        assert np.abs(got.toarray() - ref).max() <= 1e-13 * np.abs(ref).max()


def test_a_refused_element_names_its_member():
    members = [Beam((1, 2), SEC, MAT, (0.0, 1.0, 0.0), divisions=3),
               Beam((3, 4), SEC, MAT, (0.0, 0.0, 1.0), divisions=2)]
    with pytest.raises(ValueError, match=r"p: member \(3, 4\): orientation vector .* is "
                                         r"parallel to the element axis"):
        frame("p", {1: (0, 0, 0), 2: (1, 0, 0), 3: (0, 0, 0), 4: (0, 0, 2)}, members)
