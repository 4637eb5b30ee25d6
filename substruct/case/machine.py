"""What the machine has: the memory available now, against which the size of a generated solid
is checked before it is meshed (the case layer cannot use :mod:`substruct.linalg.memory`, which
the analyses use for the same figure: the two bottom layers are independent)."""

from __future__ import annotations

__all__ = ["available_memory"]


def available_memory() -> float | None:
    """Bytes the machine can give a process now without swapping (``MemAvailable`` of
    ``/proc/meminfo``), or ``None`` where that is not known."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    return None
