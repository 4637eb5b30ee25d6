"""What the machine has: the memory available now.

The one reader of it, below every layer: the case layer checks the size of a generated solid
against it before meshing, the factorization memory model (:mod:`substruct.linalg.memory`)
before factorizing.
"""

from __future__ import annotations

import os

__all__ = ["available_memory", "gigabytes"]


def available_memory() -> float | None:
    """Bytes the machine can give a process now without swapping (``MemAvailable`` of
    ``/proc/meminfo``; the free physical pages elsewhere), or ``None`` where that is not
    known."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    try:
        return float(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def gigabytes(nbytes: float) -> str:
    """``"6 GB"`` / ``"250 MB"`` / ``"3.2e+03 TB"``: a memory figure for a message."""
    if nbytes >= 1e12:
        return f"{nbytes / 1e12:.3g} TB"
    return f"{nbytes / 1e9:.3g} GB" if nbytes >= 1e8 else f"{nbytes / 1e6:.3g} MB"
