"""A plain progress bar on stderr for long sweeps (frequencies of an FRF, levels of a study)."""

from __future__ import annotations

from typing import TextIO

__all__ = ["PROGRESS_MIN", "ProgressBar"]

#: Sweeps with more frequencies than this show a progress bar (unless ``--quiet``).
PROGRESS_MIN = 50


class ProgressBar:
    """A progress bar for sweeps of more than ``minimum`` points (:data:`PROGRESS_MIN`).

    Called as ``bar(done, total, label)``.  On a terminal it redraws one line with ``\\r``; in
    a log file it writes one line per finished sweep and no carriage return.

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
        bar = "#" * filled + "." * (self.width - filled)
        self.stream.write(f"\r{self.title} {label:<20s} [{bar}] {done}/{total}")
        if done >= total:
            self.stream.write("\n")
            self.last = -1
        self.stream.flush()
