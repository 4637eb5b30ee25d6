"""A plain-Python reader and writer of the UFF 58 records the tests need, independent of
``pyuff`` and of ``substruct``: the specification's columns read by hand.

* :func:`read_plain`: datasets 15 (node numbers) and 58 / 58b (record 6 codes, record 7 data
  form, records 8-10 data types, record 12 values), returned as dictionaries;
* :func:`ascii58`: one ASCII dataset 58 (complex double, uneven abscissa: the spec's case 8,
  ``E13.5,2E20.12``; or real double, case 6) with every header code given by the caller, so
  that the tests can write the files a test lab (or a hostile user) would.
"""

from __future__ import annotations

import struct


def read_plain(data: bytes) -> dict:
    """``{"nodes": [...], "functions": [{...}, ...]}`` of a UFF file's 15 and 58 datasets."""
    nodes: list[int] = []
    functions: list[dict] = []
    at = 0
    while True:
        start = data.find(b"    -1\n", at)
        if start < 0:
            break
        line_end = data.index(b"\n", start + 7)
        kind = data[start + 7:line_end].decode()
        at = line_end + 1
        number = int(kind[:6])
        if number == 58:
            head = []
            for _ in range(11):
                end = data.index(b"\n", at)
                head.append(data[at:end].decode())
                at = end + 1
            r6, r7 = head[5], head[6]
            f = {"func_type": int(r6[0:5]), "rsp_node": int(r6[41:51]),
                 "rsp_dir": int(r6[51:55]), "ref_node": int(r6[66:76]),
                 "ref_dir": int(r6[76:80]), "ord_type": int(r7[0:10]),
                 "num_pts": int(r7[10:20]), "spacing": int(r7[20:30]),
                 "abscissa": int(head[7][0:10]), "numerator": int(head[8][0:10]),
                 "denominator": int(head[9][0:10]), "id4": head[3].strip(),
                 "id5": head[4].strip()}
            n = f["num_pts"]
            assert f["ord_type"] == 6 and f["spacing"] == 0  # what substruct writes
            if kind[6] == "b":
                assert int(kind[7:13]) == 1 and int(kind[13:19]) == 2  # little endian, IEEE
                size = int(kind[31:43])
                assert size == 24 * n
                values = struct.unpack(f"<{3 * n}d", data[at:at + size])
                at += size
                assert data[at:at + 7] == b"    -1\n"
                at += 7
            else:
                values = []
                while not data[at:].startswith(b"    -1\n"):
                    end = data.index(b"\n", at)
                    line = data[at:end].decode()
                    values += [float(line[0:13]), float(line[13:33]), float(line[33:53])]
                    at = end + 1
                at += 7
            f["x"] = list(values[0::3])
            f["y"] = [complex(re, im) for re, im in zip(values[1::3], values[2::3])]
            functions.append(f)
        else:
            end = data.index(b"\n    -1\n", at)
            if number == 15:
                nodes += [int(line[:10]) for line in data[at:end].decode().splitlines()]
            at = end + 8
    return {"nodes": nodes, "functions": functions}


def ascii58(x, y, rsp=(1, 1), ref=(1, 1), func_type=4, load_case=0, abscissa=18,
            units="Hz", numerator=8, denominator=13, num_pts=None, real=False) -> str:
    """One ASCII dataset 58 with the given codes (``num_pts`` as declared, default
    ``len(x)``)."""
    n = len(x) if num_pts is None else num_pts
    lines = ["    -1", "    58", "test", "NONE", "NONE", "NONE", "NONE",
             f"{func_type:5d}{0:10d}{0:5d}{load_case:10d} {'NONE':<10}{rsp[0]:10d}{rsp[1]:4d}"
             f" {'NONE':<10}{ref[0]:10d}{ref[1]:4d}",
             f"{4 if real else 6:10d}{n:10d}{0:10d}{0.0:13.5e}{0.0:13.5e}{0.0:13.5e}",
             f"{abscissa:10d}{0:5d}{0:5d}{0:5d} {'Frequency':<20} {units:<20}",
             f"{numerator:10d}{0:5d}{0:5d}{0:5d} {'NONE':<20} {'NONE':<20}",
             f"{denominator:10d}{0:5d}{0:5d}{0:5d} {'NONE':<20} {'NONE':<20}",
             f"{0:10d}{0:5d}{0:5d}{0:5d} {'NONE':<20} {'NONE':<20}"]
    if real:
        cells = [f"{xi:13.5e}{complex(yi).real:20.12e}" for xi, yi in zip(x, y)]
        lines += ["".join(cells[k:k + 2]) for k in range(0, len(cells), 2)]
    else:
        lines += [f"{xi:13.5e}{complex(yi).real:20.12e}{complex(yi).imag:20.12e}"
                  for xi, yi in zip(x, y)]
    return "\n".join(lines + ["    -1"]) + "\n"
