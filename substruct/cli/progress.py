"""What a long run says while it runs, on stderr: the phases as they start (with sizes and the
elapsed time), a warning before a dense eigen solve that will be slow, and a progress bar
(tqdm) for sweeps (frequencies of an FRF, levels of a study) and for counted phases of a
study (:class:`CountBar`: the shared reductions, the samples).

The phases are shown when stderr is a terminal, or when ``SUBSTRUCT_PROGRESS=1`` asks for them
(a log file, the tests); ``SUBSTRUCT_PROGRESS=0`` and ``--quiet`` turn them off.  The slow-solve
warning is shown unless ``--quiet``.
"""

from __future__ import annotations

import os
import time
from typing import Any, TextIO

__all__ = ["PROGRESS_MIN", "DENSE_SECONDS_PER_N3", "SLOW_SECONDS", "ProgressBar", "PhaseLog",
           "CountBar", "dense_seconds", "phases_wanted"]

#: Sweeps with more frequencies than this show a progress bar (unless ``--quiet``).
PROGRESS_MIN = 50
#: Seconds per cubed coordinate of one dense eigen solve (eqs 28-34, all roots of the balanced
#: pencil, the generalized-inverse formulation): measured with one BLAS thread on the tapered
#: rod by P2 elements, 0.20 s for 102 coordinates, 1.17 s for 206, 11.2 s for 406 (1.3e-7 to
#: 1.9e-7 n^3), 44 s for 606 (estimate 38 s; null-space took 0.7 s there, kkt 78 s).
DENSE_SECONDS_PER_N3 = 1.7e-7
#: A dense solve estimated longer than this is announced with a warning.
SLOW_SECONDS = 20.0


def dense_seconds(n: int) -> float:
    r"""Estimated seconds of one dense eigen solve of ``n`` coordinates on this machine.

    .. math::  t \approx c\, n^3, \qquad c = 1.7 \times 10^{-7}\ \mathrm{s}
    """
    return DENSE_SECONDS_PER_N3 * float(n) ** 3


def phases_wanted(stream: Any, quiet: bool) -> bool:
    """Whether phases are shown: not ``quiet``, and ``SUBSTRUCT_PROGRESS=1`` or a terminal."""
    if quiet:
        return False
    env = os.environ.get("SUBSTRUCT_PROGRESS", "")
    if env in ("0", "1"):
        return env == "1"
    return bool(getattr(stream, "isatty", lambda: False)())


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


class PhaseLog:
    """The ``events(kind, what, size)`` callback of a run
    (:class:`substruct.analysis.events.Phase`): one line per phase,
    ``[   1.2 s] modes (null-space): dense eigen solve (134 coordinates)``.

    Args:
        stream: where to write (``sys.stderr``).
        show: print the phases (see :func:`phases_wanted`).
        warn: warn before a dense eigen solve estimated longer than :data:`SLOW_SECONDS`.
    """

    def __init__(self, stream: TextIO, show: bool, warn: bool = True):
        self.stream, self.show, self.warn = stream, show, warn
        self.start = time.perf_counter()
        self.warned: set[int] = set()

    def __call__(self, kind: str, what: str, size: int) -> None:
        """A phase starts."""
        elapsed = time.perf_counter() - self.start
        if kind == "dense-eigen" and self.warn and size not in self.warned:
            estimate = dense_seconds(size)
            if estimate > SLOW_SECONDS:
                self.warned.add(size)
                self.stream.write(
                    f"substruct: warning: dense eigen solve of {size} coordinates: about "
                    f"{_duration(estimate)} for the generalized-inverse formulation on this "
                    f"machine ({DENSE_SECONDS_PER_N3:.1e} s x n^3), up to twice that for each "
                    f"check; solver: sparse computes the lowest modes in seconds\n")
                self.stream.flush()
        if not self.show:
            return
        sizes = {"dense-eigen": f" ({size} coordinates)", "sparse-eigen":
                 f" ({size} coordinates)"}
        self.stream.write(f"[{elapsed:7.1f} s] {what}{sizes.get(kind, '')}\n")
        self.stream.flush()


class ProgressBar:
    """A progress bar (tqdm) for sweeps of more than ``minimum`` points (:data:`PROGRESS_MIN`).

    Called as ``bar(done, total, label)``.  On a terminal tqdm redraws one line; in a log file
    one line is written per finished sweep and no carriage return.

    Args:
        stream: where to write (``sys.stderr``).
        width: characters of the bar.
        title: what is swept (``FRF``, ``converge``).
        unit: what is counted (``frequencies``, ``levels``).
        minimum: shorter sweeps show nothing.
    """

    def __init__(self, stream: TextIO, width: int = 30, *, title: str = "FRF",
                 unit: str = "frequencies", minimum: int = PROGRESS_MIN):
        self.stream, self.width, self.last = stream, width, -1
        self.title, self.unit, self.minimum = title, unit, minimum
        self.bar: Any = None

    def __call__(self, done: int, total: int, label: str) -> None:
        """Report ``done`` of ``total`` points of the sweep ``label``."""
        if total <= self.minimum:
            return
        tty = getattr(self.stream, "isatty", lambda: False)()
        if not tty:  # a log file: one line per sweep, no carriage returns
            if done >= total:
                self.stream.write(f"{self.title} {label}: {total} {self.unit} done\n")
                self.stream.flush()
            return
        filled = int(self.width * done / total)
        if filled == self.last and done < total:
            return
        self.last = filled
        from tqdm import tqdm

        tqdm.monitor_interval = 0  # no monitor thread: a run may fork (cli.isolated) later
        if self.bar is None or self.bar.total != total:
            # drawn only by refresh() below (delay: never by itself), one redraw per step
            self.bar = tqdm(total=total, file=self.stream, ascii=".#", mininterval=0,
                            bar_format=f"{{desc}} [{{bar:{self.width}}}] "
                                       "{n_fmt}/{total_fmt}", delay=1e9, leave=False)
        self.bar.set_description_str(f"{self.title} {label:<20s}", refresh=False)
        self.bar.n = done
        self.bar.refresh()
        if done >= total:
            self.bar.close()
            self.bar = None
            self.stream.write("\n")
            self.last = -1
        self.stream.flush()


class CountBar:
    """A tqdm bar (count, elapsed, ETA) of a phase made of ``total`` tasks, called as
    ``bar(done, total)`` as they finish; drawn only when ``show`` (see :func:`phases_wanted`),
    created at the first call, closed by :meth:`close`.

    Args:
        stream: where to write (``sys.stderr``).
        desc: what the phase is (``study``, ``reductions``).
        unit: what is counted (``sample``, ``part``).
        show: draw the bar at all.
    """

    def __init__(self, stream: TextIO, desc: str, unit: str, show: bool):
        self.stream, self.desc, self.unit, self.show = stream, desc, unit, show
        self.bar: Any = None

    def __call__(self, done: int, total: int) -> None:
        """``done`` of the ``total`` tasks have finished."""
        if not self.show:
            return
        if self.bar is None:
            from tqdm import tqdm

            tqdm.monitor_interval = 0  # no monitor thread (see ProgressBar)
            self.bar = tqdm(total=total, file=self.stream, unit=self.unit, desc=self.desc)
        self.bar.update(done - self.bar.n)

    def close(self) -> None:
        """Close the bar, if it was drawn."""
        if self.bar is not None:
            self.bar.close()
            self.bar = None
