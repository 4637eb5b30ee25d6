"""``substruct compare A.h5 B.h5``: the modes of two results (or two variants) side by side,
the peaks of their recovered transient quantities (:mod:`substruct.cli.compare_recovery`) and
of their receptances, plain and recovered (:mod:`substruct.cli.compare_frf`).

Prints a frequency table (each mode of the first paired with the mode of the second of largest
MAC, :mod:`substruct.analysis.modes.mac`; by order when no coordinates are shared) and the MAC
matrix; ``--image PNG`` draws the matrix (:mod:`substruct.viz.mac_picture`), ``--json`` prints
all of it as JSON.  The shapes are compared on the coordinates the two models share by label
(all of them for two variants or two runs of one case).

A result whose frequencies or mode shapes are not finite (NaN, inf) is refused (one line,
exit code 2): a corrupt file, not a table of ``nan``.  The picture follows the path policy of
every writer (:mod:`substruct.cli.files`): it ends in ``.png``, ``.svg`` or ``.pdf``, is never
one of the two results (even with ``--force``), replaces an existing file only with
``--force``, and is written under the folder's lock and renamed into place, so a full disk or
a read-only folder leaves no file (one line, exit code 2).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from substruct.analysis.modes.mac import mac_matrix, pair_modes
from substruct.cli.errors import InputError
from substruct.cli.files import check_out_file, check_targets, load_result, optional_module

__all__ = ["compare_command", "compare_modes"]


def _modes(path: str, variant: str | None) -> tuple[Any, Any]:
    result = load_result(path)
    if variant is not None:
        if variant not in result.variants:
            known = ", ".join(result.variants) or "none"
            raise InputError(f"{path} has no variant {variant!r} (it has {known})")
        return result, _finite(path, f"variants.{variant}", result.variants[variant])
    if result.modes is None:
        raise InputError(f"{path} holds no modes")
    return result, _finite(path, "modes", result.modes)


def _finite(path: str, where: str, modes: Any) -> Any:
    """``modes``, unless a frequency or a shape of it is not finite (a corrupt file)."""
    for field, values in (("omega", modes.omega), ("shapes", modes.shapes)):
        bad = ~np.isfinite(np.asarray(values))
        if bad.any():
            first = np.asarray(values)[bad].ravel()[0]
            raise InputError(f"{path}: {where}.{field}: must be finite, got {first} "
                             f"({int(bad.sum())} value(s))")
    return modes


def compare_modes(a: Any, ma: Any, b: Any, mb: Any) -> dict[str, Any]:
    """The comparison of the modes ``ma`` of result ``a`` with ``mb`` of ``b`` as data: the
    common coordinates, the MAC matrix (``None`` without common coordinates) and the rows of
    the frequency table."""
    labels_b = {lab: k for k, lab in enumerate(b.model.dof_labels)}
    common = [(i, labels_b[lab]) for i, lab in enumerate(a.model.dof_labels) if lab in labels_b]
    mac = None
    if common:
        ia, ib = (np.array(x) for x in zip(*common))
        mac = mac_matrix(ma.shapes[ia], mb.shapes[ib])
    pairs = pair_modes(mac) if mac is not None else np.arange(len(ma))
    rows = []
    for j in range(len(ma)):
        k = int(pairs[j])
        fa = float(ma.freq_hz[j])
        fb = float(mb.freq_hz[k]) if 0 <= k < len(mb) else None
        rows.append({"mode_a": j + 1, "freq_a_hz": fa, "mode_b": k + 1 if fb is not None else None,
                     "freq_b_hz": fb, "difference": (fb - fa) / fa if fb is not None and fa
                     else None,
                     "mac": float(mac[j, k]) if mac is not None and fb is not None else None})
    return {"common_coordinates": len(common), "rows": rows,
            "mac": None if mac is None else mac.tolist()}


def _peaks_only(args: argparse.Namespace) -> int | None:
    """Two results without modes but with recovered transient peaks or receptances: their
    tables alone (:mod:`substruct.cli.compare_recovery`, :mod:`substruct.cli.compare_frf`);
    ``None`` when the modes are to be compared."""
    from substruct.cli.compare_frf import compare_frf_peaks, print_frf_comparison
    from substruct.cli.compare_recovery import compare_peaks, print_peak_comparison

    a, b = load_result(args.first), load_result(args.second)
    if a.modes is not None and b.modes is not None or args.variant_a or args.variant_b or \
            args.image is not None:
        return None
    rows, frf = compare_peaks(a, b), compare_frf_peaks(a, b)
    if not rows and not frf:
        return None
    if args.json:
        print(json.dumps({"a": args.first, "b": args.second, "peaks": rows,
                          "frf_peaks": frf}, indent=1))
        return 0
    print(f"A: {args.first}\nB: {args.second}")
    print_peak_comparison(rows, sys.stdout)
    print_frf_comparison(frf, sys.stdout)
    return 0


def compare_command(args: argparse.Namespace) -> int:
    """Print the comparison of the modes of ``args.first`` and ``args.second``, of their
    recovered transient peaks and of their receptance peaks; return 0."""
    from substruct.cli.compare_frf import compare_frf_peaks, print_frf_comparison
    from substruct.cli.compare_recovery import compare_peaks, print_peak_comparison

    if args.force and args.image is None:
        raise InputError("--force replaces the picture of --image, the only file compare "
                         "writes: give --image, or leave --force out")
    only = _peaks_only(args)
    if only is not None:
        return only
    image = check_out_file(args.image, "--image", _PICTURES) if args.image is not None \
        else None
    a, ma = _modes(args.first, args.variant_a)
    b, mb = _modes(args.second, args.variant_b)
    data = compare_modes(a, ma, b, mb)
    peaks = compare_peaks(a, b)
    if peaks:
        data["peaks"] = peaks
    frf = compare_frf_peaks(a, b)
    if frf:
        data["frf_peaks"] = frf
    name_a = args.first + (f" ({args.variant_a})" if args.variant_a else "")
    name_b = args.second + (f" ({args.variant_b})" if args.variant_b else "")
    if image is not None:
        if data["mac"] is None:
            raise InputError("the results share no coordinate: no MAC matrix to draw")
        _draw(image, args, np.array(data["mac"]), (Path(name_a).name, Path(name_b).name),
              ma.freq_hz, mb.freq_hz)
    if args.json:
        print(json.dumps({"a": name_a, "b": name_b, **data}, indent=1))
        return 0
    n = data["common_coordinates"]
    print(f"A: {name_a}: {len(ma)} mode(s)\nB: {name_b}: {len(mb)} mode(s)")
    print(f"MAC on {n} common coordinate(s)" if n else
          "no common coordinates: modes paired by order, no MAC")
    print(f"{'mode A':>6} {'f_A (Hz)':>12} {'mode B':>6} {'f_B (Hz)':>12} {'diff':>9} "
          f"{'MAC':>6}")
    for r in data["rows"]:
        mac = f"{r['mac']:6.3f}" if r["mac"] is not None else f"{'-':>6}"
        if r["mode_b"] is None:
            print(f"{r['mode_a']:>6} {r['freq_a_hz']:12.6g} {'-':>6}")
            continue
        diff = f"{100 * r['difference']:8.3f}%" if r["difference"] is not None else f"{'-':>9}"
        print(f"{r['mode_a']:>6} {r['freq_a_hz']:12.6g} {r['mode_b']:>6} "
              f"{r['freq_b_hz']:12.6g} {diff} {mac}")
    if data["mac"] is not None and len(ma) <= 12 and len(mb) <= 12:
        print("MAC matrix (rows: A, columns: B):")
        for row in data["mac"]:
            print("  " + " ".join(f"{v:5.3f}" for v in row))
    print_peak_comparison(peaks, sys.stdout)
    print_frf_comparison(frf, sys.stdout)
    if image is not None:
        print(f"written: {image[0] / image[1]}")
    return 0


#: The endings of ``--image`` (the formats the picture is written in).
_PICTURES = (".png", ".svg", ".pdf")


def _draw(image: tuple[Path, str], args: argparse.Namespace, mac: np.ndarray,
          labels: tuple[str, str], freq_a: Any, freq_b: Any) -> None:
    """Draw the MAC picture into a staging folder beside ``image`` and move it into place,
    under the folder's lock (:class:`~substruct.io.file_set.OutputDir`)."""
    from substruct.io.file_set import OutputDir
    from substruct.io.paths import write_errors

    folder, name = image
    picture = optional_module("viz.mac_picture")
    with OutputDir(folder) as target:
        check_targets(folder, [name], [args.first, args.second], args.force)
        staging = target.stage(Path(name).stem)
        with write_errors(folder / name):
            picture.mac_picture(mac, staging / name, labels, freq_a, freq_b)
        target.commit(staging)
