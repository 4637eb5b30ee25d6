"""Regenerate ``<name>_reference.npz`` from ``<name>.full`` (``file`` and ``sparse``, or the
names given as arguments) with ansys-mapdl-reader (run by hand, in an environment of its own:
``pip install ansys-mapdl-reader``; made with version 0.56.x under NumPy 2).

Members: ``K`` and ``M`` as ``load_km(as_sparse=False, sort=True)`` gives them (one triangle,
the constrained equations' rows and columns zero), ``dof_ref`` (node, index of the degree of
freedom in the node, 0-based), ``const`` (node, index) of the constrained equations, and the
reader's ``version``.
"""

import sys
from pathlib import Path

import numpy as np
from ansys.mapdl import reader

here = Path(__file__).parent
for name in sys.argv[1:] or ["file", "sparse"]:
    full = reader.read_binary(str(here / f"{name}.full"))
    dof_ref, K, M = full.load_km(as_sparse=False, sort=True)
    np.savez_compressed(here / f"{name}_reference.npz", K=K, M=M,
                        dof_ref=np.asarray(dof_ref), const=np.asarray(full.const),
                        version=np.array(reader.__version__))
    print(name, reader.__version__, K.shape, np.asarray(full.const).shape)
