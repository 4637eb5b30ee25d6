"""The ``substruct`` command: ``run``, ``converge``, ``info``, ``export``, ``compare`` and
``study``.

::

    substruct run CASE.yaml [--out DIR] [--set key.path=value ...] [--force] [--no-pictures]
                  [--quiet] [--json]
    substruct converge CASE.yaml [--levels quick|default|fine|"assumed=4:256; ..."]
                       [--variants constrained,unconstrained,bare] [--out DIR]
                       [--set key.path=value ...] [--tol 1e-6] [--reference richardson|finest]
                       [--force] [--quiet] [--json]
    substruct info RESULT.h5 [--json]
    substruct export RESULT.h5 --format vtu|xdmf|uff [--modes 1-6] [--variant NAME]
                     [--transient] [--out DIR] [--force]
    substruct compare A.h5 B.h5 [--variant-a NAME] [--variant-b NAME] [--image MAC.png]
                      [--force] [--json]
    substruct study CASE.yaml [--workers N | --scheduler tcp://HOST:PORT [--connect-timeout S]]
                    [--out DIR] [--set key.path=value ...] [--force] [--no-pictures] [--quiet]
                    [--json]

Exit codes (:mod:`substruct.cli.main`): 0 success; 2 bad input (one line
``substruct: error: <message>`` on stderr, no traceback, nothing written); 1 a result that
failed its cross-checks (one line, nothing written) or an internal error (its traceback, then
one closing line ``substruct: internal error: ...``); 130 interrupted (Ctrl-C, also while the
command's own modules load: one line ``substruct: interrupted``); 143 terminated (SIGTERM;
partly written files are removed either way).

The files of the package, one command or one concern each: :mod:`~substruct.cli.arguments`
(the parser), :mod:`~substruct.cli.run_command`, :mod:`~substruct.cli.converge_command`,
:mod:`~substruct.cli.result_commands` (``info``, ``export``), :mod:`~substruct.cli.summary`
(tables and JSON), :mod:`~substruct.cli.progress`, :mod:`~substruct.cli.files` (output
directories, result files), :mod:`~substruct.cli.signals` (SIGTERM, closed pipes).
"""

from __future__ import annotations

import os

# BLAS on one thread unless the user says otherwise, before numpy loads: the dense blocks here
# are small or mid-sized and threaded OpenBLAS on two busy cores made a 400-frequency sweep of
# cases/two_rods_spring.yaml 8x slower (50 s vs 6.5 s) and a 1600 x 1600 eig 1.25x slower.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
# ... and MKL (PARDISO) then without a threading layer: on one thread its OpenMP layer only
# costs its start (0.006 s at the first factorization), and which layer MKL takes would
# otherwise depend on whether another library had loaded GNU OpenMP before (scikit-sparse
# does), and its results' last digits with it.  Sequential MKL gives the same digits as its
# default (Intel) layer.
if os.environ["OMP_NUM_THREADS"] == "1" and os.environ["MKL_NUM_THREADS"] == "1":
    os.environ.setdefault("MKL_THREADING_LAYER", "SEQUENTIAL")
# The case schema's validation without pydantic's plugins (observability hooks, found by
# scanning the entry points of every installed distribution at the first validation: 0.006 s
# of each start); a value the user sets is kept.
os.environ.setdefault("PYDANTIC_DISABLE_PLUGINS", "__all__")

import sys  # noqa: E402

try:  # the command's modules take a second or two to load: Ctrl-C there ends it in one line
    from substruct.cli.main import main  # noqa: E402
except KeyboardInterrupt:
    sys.stderr.write("substruct: interrupted\n")
    raise SystemExit(130) from None

__all__ = ["main"]
