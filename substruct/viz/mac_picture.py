"""The MAC matrix between two sets of modes as a picture (matplotlib, no display)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Sequence

import numpy as np

__all__ = ["mac_picture"]


def mac_picture(mac: np.ndarray, path: str | os.PathLike, labels: Sequence[str] = ("A", "B"),
                freq_a: Sequence[float] = (), freq_b: Sequence[float] = ()) -> Path:
    """Draw ``mac`` (rows: modes of ``labels[0]``, columns: of ``labels[1]``) with its values,
    the axes ticked by mode number and frequency (Hz) if given; write a PNG; return its path.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    p, q = mac.shape
    fig, ax = plt.subplots(figsize=(1.6 + 0.8 * max(q, 4), 1.0 + 0.5 * max(p, 4)))
    im = ax.imshow(mac, vmin=0.0, vmax=1.0, cmap="viridis", origin="upper")
    fig.colorbar(im, ax=ax, label="MAC")

    def ticks(n: int, freqs: Sequence[float]) -> list[str]:
        return [f"{k + 1}\n{freqs[k]:.4g} Hz" if k < len(freqs) else str(k + 1)
                for k in range(n)]

    ax.set_xticks(range(q), ticks(q, freq_b), fontsize=7)
    ax.set_yticks(range(p), [t.replace("\n", " ") for t in ticks(p, freq_a)], fontsize=7)
    ax.set_xlabel(f"modes of {labels[1]}")
    ax.set_ylabel(f"modes of {labels[0]}")
    if p * q <= 400:
        for j in range(p):
            for k in range(q):
                ax.text(k, j, f"{mac[j, k]:.2f}", ha="center", va="center", fontsize=6,
                        color="black" if mac[j, k] > 0.6 else "white")
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
