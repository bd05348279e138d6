"""PCD files (the Point Cloud Library's format), read by meshlap itself: the points' x, y, z.

A PCD file is a header of lines (``FIELDS``, ``SIZE``, ``TYPE``, ``COUNT``, ``WIDTH``,
``HEIGHT``, ``POINTS``, ``DATA``) and a body that is ``ascii`` (one point per line), ``binary``
(packed records, little endian) or ``binary_compressed`` (two uint32 sizes, then LZF-compressed
data laid out field after field). Fields other than x, y and z (intensity, rgb, normals, ...)
are read past. An organized cloud (a depth camera's, ``HEIGHT`` > 1) marks pixels without a
return with NaN coordinates: PCL's convention for "no point", so those rows are left out.
"""

from __future__ import annotations

import numpy as np

from ._jit import jit
from .errors import MeshError

__all__: list[str] = []

_KINDS = {"F": "f", "I": "i", "U": "u"}


@jit()
def _lzf(src, n_out):  # pragma: no cover - compiled
    # LZF (liblzf) decompression: a control byte below 32 starts a literal run of ctrl + 1 bytes;
    # above, a back reference of length (ctrl >> 5) + 2 (7: plus the next byte) at distance
    # ((ctrl & 31) << 8) + next + 1. Returns -1 where the data do not decode to n_out bytes.
    out = np.empty(n_out, dtype=np.uint8)
    i = 0
    o = 0
    n = len(src)
    while i < n:
        ctrl = int(src[i])
        i += 1
        if ctrl < 32:
            run = ctrl + 1
            if i + run > n or o + run > n_out:
                return out, -1
            out[o:o + run] = src[i:i + run]
            i += run
            o += run
        else:
            length = ctrl >> 5
            if length == 7:
                if i >= n:
                    return out, -1
                length += int(src[i])
                i += 1
            if i >= n:
                return out, -1
            ref = o - ((ctrl & 31) << 8) - int(src[i]) - 1
            i += 1
            length += 2
            if ref < 0 or o + length > n_out:
                return out, -1
            for _ in range(length):  # byte by byte: the reference may overlap what it writes
                out[o] = out[ref]
                o += 1
                ref += 1
    return out, o


def read(data: bytes, name: str) -> np.ndarray:
    """The (n, 3) float64 points of a PCD file's bytes (rows with NaN coordinates left out)."""
    head: dict[str, list[str]] = {}
    pos = 0
    while "DATA" not in head:
        end = data.find(b"\n", pos)
        if end < 0:
            raise MeshError(f"{name}: not a PCD file (no DATA line ends its header)")
        line = data[pos:end].decode("ascii", errors="replace").split("#", 1)[0].split()
        pos = end + 1
        if line:
            head[line[0].upper()] = line[1:]
    try:
        fields = head["FIELDS"]
        size = [int(s) for s in head.get("SIZE", ["4"] * len(fields))]
        kind = head.get("TYPE", ["F"] * len(fields))
        count = [int(c) for c in head.get("COUNT", ["1"] * len(fields))]
        n = int(head["POINTS"][0]) if "POINTS" in head else int(head["WIDTH"][0]) * int(head["HEIGHT"][0])
        mode = head["DATA"][0].lower()
        dtypes = [np.dtype(f"<{_KINDS[t.upper()]}{s}") for t, s in zip(kind, size, strict=True)]
    except (KeyError, IndexError, ValueError, TypeError) as exc:
        raise MeshError(f"{name}: a PCD header without valid FIELDS, SIZE, TYPE, COUNT, POINTS or DATA "
                        f"({exc!r})") from exc
    if len(count) != len(fields) or not {"x", "y", "z"} <= set(fields):
        raise MeshError(f"{name}: the PCD fields {' '.join(fields)} do not include x, y and z")
    # each field's first column among all columns (a field of COUNT c takes c of them)
    first = dict(zip(fields, np.cumsum([0] + count[:-1]).tolist(), strict=True))
    columns = [(dt, c) for dt, c in zip(dtypes, count, strict=True)]
    if mode == "ascii":
        rows = data[pos:].decode("ascii", errors="replace").split()
        width = sum(count)
        if len(rows) < n * width:
            raise MeshError(f"{name}: the PCD file declares {n} points but holds {len(rows) // width}")
        try:
            table = np.array(rows[:n * width], dtype=np.float64).reshape(n, width)
        except ValueError as exc:
            raise MeshError(f"{name}: a PCD value that is not a number ({exc})") from exc
        P = table[:, [first["x"], first["y"], first["z"]]]
    elif mode == "binary":
        record = np.dtype([(f"f{i}", dt, (c,)) for i, (dt, c) in enumerate(columns)])
        if len(data) - pos < n * record.itemsize:
            raise MeshError(f"{name}: the binary PCD file is cut short ({len(data) - pos} bytes for {n} "
                            f"points of {record.itemsize})")
        body = np.frombuffer(data, record, n, pos)
        P = np.column_stack([body[f"f{fields.index(a)}"][:, 0].astype(np.float64) for a in "xyz"])
    elif mode == "binary_compressed":
        if len(data) - pos < 8:
            raise MeshError(f"{name}: the compressed PCD body is cut short")
        packed, unpacked = (int(v) for v in np.frombuffer(data, "<u4", 2, pos))
        src = np.frombuffer(data, np.uint8, min(packed, len(data) - pos - 8), pos + 8)
        raw, got = _lzf(src, unpacked)
        if got != unpacked or packed > len(data) - pos - 8:
            raise MeshError(f"{name}: the compressed PCD body does not decompress to its {unpacked} bytes")
        # field after field: each a block of n values of its type and count
        offsets = np.cumsum([0] + [n * dt.itemsize * c for dt, c in columns]).tolist()
        P = np.column_stack([
            np.frombuffer(raw, dtypes[i], n * count[i], offsets[i])[::count[i]].astype(np.float64)
            for i in (fields.index(a) for a in "xyz")])
    else:
        raise MeshError(f"{name}: PCD data {mode!r}; meshlap reads ascii, binary and binary_compressed")
    return P[~np.isnan(P).any(axis=1)]
