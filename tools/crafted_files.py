"""Crafted data files, as someone hostile (or a damaged disk) would hand them to mbody: the
one home of the builders that the hardening tests (tests/test_run_file_hardening.py,
tests/test_export_hardening.py) and the benchmark of refusals (tools/bench_run_files.py)
use alike.

- npz: members written as given (`npz_members`: an array as numpy saves it, or the
  member's raw bytes, such as a `npy_header` with no data); one member with a header of
  one's own and bytes that need not fit it (`npz_with`); a zip bomb, one member of
  zeros that inflates a thousandfold, streamed so that making it holds no more than a
  chunk (`npz_bomb`).
- MAT 5 (`mbody.load_export` of a .mat export): its data elements (`mat_tag`,
  `mat_array`), a file of variables (`mat_file`), and a bomb, one compressed variable of
  zeros, streamed as well (`mat_bomb`).

Tests import it as ``tools`` modules are imported elsewhere (tests/test_fast.py): with
the ``tools`` folder on ``sys.path``.
"""

from __future__ import annotations

import io
import struct
import zipfile
import zlib
from pathlib import Path

import numpy as np

MIB = 1 << 20
CHUNK = 16 * MIB
"""Zeros written at a time into a bomb: the most its making holds in memory."""


# -- npz ----------------------------------------------------------------------------------


def npy_header(shape: tuple[int, ...], descr: str) -> bytes:
    """A .npy header for `shape` values of `descr`, and no data."""
    b = io.BytesIO()
    np.lib.format.write_array_header_1_0(b, {"descr": descr, "fortran_order": False,
                                             "shape": shape})
    return b.getvalue()


def npy_bytes(value: np.ndarray) -> bytes:
    """`value` as numpy saves it in an .npy member."""
    b = io.BytesIO()
    np.save(b, value)
    return b.getvalue()


def npz_members(path: Path, data: dict[str, np.ndarray | bytes | None],
                method: int = zipfile.ZIP_DEFLATED) -> Path:
    """An npz of `data`: an array saved as numpy saves it, bytes as the member's whole
    content (a raw .npy header, `npy_header`), None left out."""
    with zipfile.ZipFile(path, "w", method) as z:
        for k, v in data.items():
            if isinstance(v, bytes):
                z.writestr(k + ".npy", v)
            elif v is not None:
                z.writestr(k + ".npy", npy_bytes(v))
    return path


def npz_with(path: Path, data: dict[str, np.ndarray], member: str, header: dict,
             body: bytes, method: int = zipfile.ZIP_STORED) -> Path:
    """`data` as an npz whose `member` has the .npy `header` (a dict as numpy writes it:
    descr, fortran_order, shape) and the bytes `body`, whether they fit it or not."""
    b = io.BytesIO()
    np.lib.format.write_array_header_1_0(b, header)
    b.write(body)
    return npz_members(path, {**data, member: b.getvalue()}, method)


def npz_bomb(path: Path, data: dict[str, np.ndarray], samples: int,
             member: str = "t") -> Path:
    """`data` with `member` deflated from `samples` zero doubles: 8 bytes a sample once
    inflated, about 1/1000 of that on disk (written `CHUNK` at a time)."""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for k, v in data.items():
            if k != member:
                z.writestr(k + ".npy", npy_bytes(v))
                continue
            with z.open(member + ".npy", "w", force_zip64=True) as f:
                f.write(npy_header((samples,), "<f8"))
                left = 8 * samples
                while left > 0:
                    f.write(bytes(min(CHUNK, left)))
                    left -= CHUNK
    return path


# -- MAT 5 --------------------------------------------------------------------------------


def _element_head(kind: int, size: int) -> bytes:
    return struct.pack("<II", kind, size)


def mat_tag(kind: int, data: bytes) -> bytes:
    """A MAT 5 data element: type, size, data padded to 8 bytes."""
    return _element_head(kind, len(data)) + data + bytes(-len(data) % 8)


def mat_array(cls: int, shape: tuple[int, ...], body: bytes = b"", name: bytes = b"") -> bytes:
    """An miMATRIX element of MATLAB class `cls` (1 cell, 6 double) and `shape`."""
    return mat_tag(14, mat_tag(6, struct.pack("<II", cls, 0))
                   + mat_tag(5, struct.pack(f"<{len(shape)}i", *shape)) + mat_tag(1, name)
                   + body)


def _mat_head(version: bytes = b"5.0") -> bytes:
    text = b"MATLAB " + version + b" MAT-file, written by tools/crafted_files.py"
    return text.ljust(116) + bytes(8) + struct.pack("<H", 0x0100 if version == b"5.0"
                                                    else 0x0200) + b"IM"


def mat_file(path: Path, *variables: bytes, version: bytes = b"5.0",
             compress: bool = True) -> Path:
    """A MAT file of `variables`, each compressed (as scipy writes them), or each element
    as it is given (`compress` False)."""
    body = b"".join(_element_head(15, len(c)) + c
                    for c in (zlib.compress(v) for v in variables)) if compress \
        else b"".join(variables)
    path.write_bytes(_mat_head(version) + body)
    return path


def mat_bomb(path: Path, samples: int, name: bytes = b"b") -> Path:
    """A .mat whose one compressed double column `name` inflates to 8 bytes a sample,
    compressed `CHUNK` at a time (the file is about 1/1000 of that)."""
    data = 8 * samples
    matrix = (mat_tag(6, struct.pack("<II", 6, 0)) + mat_tag(5, struct.pack("<2i", samples, 1))
              + mat_tag(1, name) + _element_head(9, data))
    deflate = zlib.compressobj()
    parts = [deflate.compress(_element_head(14, len(matrix) + data) + matrix)]
    left = data
    while left > 0:
        parts.append(deflate.compress(bytes(min(CHUNK, left))))
        left -= CHUNK
    parts.append(deflate.flush())
    packed = b"".join(parts)
    path.write_bytes(_mat_head() + _element_head(15, len(packed)) + packed)
    return path
