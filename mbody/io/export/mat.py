"""The MATLAB .mat export: the `flat_arrays` names, M and G (and the world-axes map T when
asked for) as MATLAB sparse matrices, vectors as columns (``M*vdot + b``), label lists as
cell columns and the conventions also as a struct. scipy.io is imported when a .mat file
is written or read, not before: it is slow to import and most runs never touch MATLAB
files.

A .mat file is read as input that may be hostile (`checked`): scipy allocates the arrays
a file declares, recurses into nested cells as deep as they go and inflates each
compressed variable whole, so the file's structure is walked first, within a byte budget
(`mbody.util.budget.byte_limit`), and scipy reads the walked, inflated copy."""

from __future__ import annotations

import io
import math
import struct
import zlib
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from mbody.errors import MbodyError
from mbody.io.export.assembly import (
    COLUMN_TEXT,
    MORE,
    ExportedAssembly,
    build,
    check_sparse,
    flat_arrays,
)
from mbody.util.budget import DATA_BYTES, byte_limit
from mbody.util.npzfile import over_budget, read_bytes


def _cell(values: Iterable[Any]) -> np.ndarray:
    """A MATLAB cell column of strings (an n x 1 cellstr).

    MATLAB and Octave index it with ``strcmp(S.coordinates, 'rod.x')``;
    ``scipy.io.loadmat(path, simplify_cells=True)`` returns it as an array of str (a list
    of one label squeezed to that str), plain ``loadmat`` as nested 1 x 1 arrays. A char
    matrix would pad its rows with spaces in every reader, so labels stay cells.
    """
    items = [str(v) for v in values]
    out = np.empty((len(items), 1), dtype=object)
    for i, v in enumerate(items):
        out[i, 0] = v
    return out


def write(exp: ExportedAssembly, path: Path) -> None:
    """Write `exp` to `path` as a compressed MATLAB 5 file (not atomic by itself).

    Parameters
    ----------
    exp
        The export to write.
    path
        The file to write; scipy would add ``.mat`` to a name without it.
    """
    import scipy.io

    arrs = flat_arrays(exp)
    for k in ("coordinates", "reactions", "body_names", "world_reactions",
              *(f"column_{k}" for k in COLUMN_TEXT[1:])):
        if k in arrs:
            arrs[k] = _cell(arrs[k])
    arrs["M"], arrs["G"] = exp.M, exp.G
    if exp.T is not None:  # world = T * lambda
        arrs["T"] = exp.T
    # The conventions also as a MATLAB struct (lists as cells) for people reading it there.
    arrs["conventions"] = {k: (_cell(v) if isinstance(v, list) else v)
                           for k, v in exp.conventions.items()}
    scipy.io.savemat(path, arrs, oned_as="column", do_compression=True)


def load(path: Path, max_bytes: int | None = None, simplify_cells: bool = False
         ) -> dict[str, Any]:
    """`scipy.io.loadmat` of the .mat file `path` as input that may be hostile: `checked`
    first, and then every sparse matrix in it (in cells and structs too) checked
    (`check_sparse`) before anything uses it."""
    import scipy.io

    stream = checked(path, max_bytes)
    try:
        data = scipy.io.loadmat(stream, simplify_cells=simplify_cells)
    except (scipy.io.matlab.MatReadError, OverflowError, TypeError, ValueError, IndexError,
            KeyError) as exc:  # what the walk does not look into (a sparse matrix whose
        # column pointers end below 0: an OverflowError)
        raise MbodyError(f"{path}: damaged or truncated .mat export (scipy cannot read "
                         f"it: {type(exc).__name__}: {exc})") from None

    def walk(name: str, value: Any) -> None:  # nested at most MAX_DEPTH (`checked`)
        if isinstance(value, dict):
            for key, v in value.items():
                walk(f"{name}.{key}", v)
        elif isinstance(value, list | tuple):
            for v in value:
                walk(f"{name} (in a cell)", v)
        elif isinstance(value, np.ndarray) and value.dtype == object:
            for v in value.flat:
                walk(f"{name} (in a cell)", v)
        elif isinstance(value, np.ndarray) and value.dtype.names:  # a struct array
            for v in value.flat:
                for field in value.dtype.names:
                    walk(f"{name}.{field}", v[field])
        else:
            check_sparse(path, name, value)

    for key, value in data.items():
        walk(key, value)
    return data


def read(path: Path, max_bytes: int | None = None) -> ExportedAssembly:
    """The `ExportedAssembly` stored in the .mat file `path` (`load`)."""
    data = load(path, max_bytes)

    def unstr(v: Any) -> str:
        v = np.asarray(v)
        return str(v.ravel()[0]) if v.size else ""

    def get(k: str) -> Any:
        v = data[k]
        if isinstance(v, np.ndarray) and v.dtype == object:  # a cell column of strings
            return [unstr(x) for x in v.ravel()]
        if isinstance(v, np.ndarray) and v.dtype.kind == "U":
            return unstr(v)
        v = np.asarray(v)
        # MATLAB has no scalars: these three come back as 1x1 matrices
        return v.ravel()[0] if v.size == 1 and k in ("version", "dimension", "t") else v

    return build(path, get, data["M"], data["G"], data.get("T"))


# -- a MAT 5 file walked before scipy reads it ------------------------------------------------

MAX_DEPTH = 64
"""Deepest nesting of cells and structs read (scipy recurses once a level; mbody writes 2)."""

_HEADER = 128
_MATRIX, _COMPRESSED = 14, 15
_ITEM = {1: 1, 2: 1, 3: 2, 4: 2, 5: 4, 6: 4, 7: 4, 9: 8, 12: 8, 13: 8, 16: 1, 17: 2, 18: 4}
"""Bytes per item of each MAT data type (miINT8 ... miUTF32)."""
_CLASS_ITEM = {4: 4, 6: 8, 7: 4, 8: 1, 9: 1, 10: 2, 11: 2, 12: 4, 13: 4, 14: 8, 15: 8}
"""Bytes per element of each numeric or char array class in memory (mxCHAR as numpy's
4-byte characters), what scipy allocates for a declared shape."""
_CELL, _STRUCT, _CHAR, _SPARSE = 1, 2, 4, 5
_INT8 = 1
"""The MAT type of names and field names (miINT8)."""


class _Walk:
    """One pass over a MAT 5 file's variables: every element within its parent, every
    shape within the bytes there, the memory scipy will allocate added up (`spent`)."""

    def __init__(self, path: Path, limit: int, order: str):
        self.path, self.limit, self.order = path, limit, order
        self.spent = 0

    def fail(self, problem: str) -> MbodyError:
        return MbodyError(f"{self.path}: damaged or truncated .mat export ({problem})")

    def spend(self, n: int) -> None:
        self.spent += n
        if self.spent > self.limit:
            raise MbodyError(over_budget(str(self.path), self.spent, self.path.stat().st_size,
                                         self.limit, MORE))

    def element(self, buf: bytes, pos: int, end: int) -> tuple[int, int, int, int]:
        """(type, bytes, where its data starts, where the next element starts) of the data
        element at `pos`, which must end by `end`."""
        if pos + 8 > end:
            raise self.fail(f"an element at byte {pos} runs past its parent")
        kind, size = struct.unpack_from(self.order + "II", buf, pos)
        if kind >> 16:  # the small format: up to 4 bytes of data within the tag
            size, kind = kind >> 16, kind & 0xFFFF
            if size > 4:
                raise self.fail(f"a small element at byte {pos} says it holds {size} bytes")
            return kind, size, pos + 4, pos + 8
        if pos + 8 + size > end:
            raise self.fail(f"an element at byte {pos} says it holds {size:,} bytes, more "
                            "than its parent has")
        return kind, size, pos + 8, min(end, pos + 8 + size + (-size) % 8)

    def matrix(self, buf: bytes, start: int, end: int, depth: int) -> None:
        """The miMATRIX whose data is buf[start:end]: flags, shape, name, then its parts."""
        if start == end:  # an empty array
            return
        if depth > MAX_DEPTH:
            raise self.fail(f"cells or structs nested over {MAX_DEPTH} deep")
        kind, size, at, pos = self.element(buf, start, end)
        if kind != 6 or size != 8:
            raise self.fail(f"an array without its flags at byte {start}")
        flags = struct.unpack_from(self.order + "I", buf, at)[0]
        cls, parts = flags & 0xFF, 2 if flags & 0x0800 else 1
        kind, size, at, pos = self.element(buf, pos, end)
        if kind != 5 or size % 4 or size < 8:
            raise self.fail(f"an array without its shape at byte {at}")
        shape = struct.unpack_from(f"{self.order}{size // 4}i", buf, at)
        if min(shape) < 0:
            raise self.fail(f"an array of shape {shape}")
        count = math.prod(shape)
        # every element's type is checked: scipy's compiled reader looks a type up in a
        # table of the known ones unchecked (a sparse matrix's row indices of type 5637
        # crashed the process, review R3)
        kind, _, at, pos = self.element(buf, pos, end)
        if kind != _INT8:
            raise self.fail(f"an array whose name at byte {at} is of MAT type {kind}, "
                            "expected text (miINT8)")
        if cls in (_CELL, _STRUCT):
            fields = 1
            if cls == _STRUCT:
                kind, size, at, pos = self.element(buf, pos, end)
                if kind != 5 or size != 4:  # one int32, as MATLAB and scipy write it
                    raise self.fail(f"a struct without the width of its field names at "
                                    f"byte {at}")
                width = struct.unpack_from(self.order + "i", buf, at)[0]
                kind, size, at, pos = self.element(buf, pos, end)
                if kind != _INT8:
                    raise self.fail(f"a struct whose field names at byte {at} are of MAT "
                                    f"type {kind}, expected text (miINT8)")
                if width <= 0 or size % width:
                    raise self.fail("a struct whose field names do not fit their width")
                fields = size // width
            slots = count * max(fields, 1)
            if slots * 8 > end - pos:  # each slot is an element of 8 bytes at least
                raise self.fail(f"a {'cell' if cls == _CELL else 'struct'} array of shape "
                                f"{shape} in {end - pos:,} bytes")
            self.spend(8 * slots)
            for _ in range(count * fields):
                kind, size, at, pos = self.element(buf, pos, end)
                if kind != _MATRIX:
                    raise self.fail(f"a cell or field at byte {at} that is not an array")
                self.matrix(buf, at, at + size, depth + 1)
        elif cls == _SPARSE:
            for _ in range(2 + parts):  # row indices, column pointers, values (real, imag)
                kind, size, at, pos = self.element(buf, pos, end)
                if kind not in _ITEM:
                    raise self.fail(f"a sparse array whose data at byte {at} is of MAT type "
                                    f"{kind}, not numbers")
                self.spend(2 * size)  # scipy's copy and the matrix's own
        elif cls in _CLASS_ITEM:
            for _ in range(parts):
                kind, size, at, pos = self.element(buf, pos, end)
                item = _ITEM.get(kind)
                fits = (size >= count if kind == 16 else item is not None and
                        size == count * item)
                if not fits:
                    raise self.fail(f"an array of shape {shape} whose data at byte {at} "
                                    f"holds {size:,} bytes")
                self.spend(count * _CLASS_ITEM[cls])
        else:
            raise self.fail(f"an array of MATLAB class {cls} (objects, functions), which an "
                            "export never holds")


def checked(path: Path, max_bytes: int | None = None) -> io.BytesIO:
    """The MAT 5 file `path` walked and inflated, as an uncompressed MAT 5 stream for
    `scipy.io.loadmat`: every variable's declared size counted against `max_bytes`
    (default `mbody.util.budget.DATA_BYTES`) before it is inflated, every array's shape
    against the bytes that hold it, nesting at most `MAX_DEPTH`. scipy then allocates only
    what the bytes there hold, and never inflates anything itself.

    Raises
    ------
    MbodyError
        Naming the file and what is wrong: not a MAT 5 file (v4 and v7.3/HDF5 files are
        not read), more than the budget, an element or shape that does not fit.
    """
    limit = byte_limit(max_bytes, DATA_BYTES)
    raw = read_bytes(path, limit, MORE)
    order = {b"IM": "<", b"MI": ">"}.get(raw[126:128])
    if (len(raw) < _HEADER or order is None or not raw.startswith(b"MATLAB 5.0")
            or struct.unpack_from(order + "H", raw, 124)[0] != 0x0100):
        raise MbodyError(f"{path}: not a MATLAB 5 .mat file as mbody writes it (v4 and "
                         "v7.3 files are not read)")
    walk = _Walk(path, limit, order)
    out = [raw[:116], bytes(8), raw[124:_HEADER]]  # no subsystem data
    pos = _HEADER
    while pos < len(raw):
        try:
            body, pos = _variable(walk, raw, pos)
        except zlib.error as exc:
            raise walk.fail(f"the compressed variable at byte {pos} does not inflate: "
                            f"{exc}") from None
        except struct.error as exc:  # each size is checked before it is unpacked
            raise walk.fail(f"an element in the variable at byte {pos} is cut short: "
                            f"{exc}") from None
        out += [body, bytes(-len(body) % 8)]
    return io.BytesIO(b"".join(out))


def _variable(walk: _Walk, raw: bytes, pos: int) -> tuple[bytes, int]:
    """The variable at byte `pos` of the file `raw`, inflated and walked, and where the
    next one starts."""
    kind, size, at, after = walk.element(raw, pos, len(raw))
    if kind == _COMPRESSED:
        inflate = zlib.decompressobj()
        head = inflate.decompress(raw[at:at + size], 8)
        if len(head) < 8:
            raise walk.fail(f"a compressed variable at byte {pos} is cut short")
        inner, inner_size = struct.unpack_from(walk.order + "II", head)
        walk.spend(inner_size + 8)  # before it is inflated
        # (a max_length of 0 would be no limit at all)
        body = head + (inflate.decompress(inflate.unconsumed_tail, inner_size)
                       if inner_size else b"")
        if inner != _MATRIX or len(body) != inner_size + 8:
            raise walk.fail(f"the compressed variable at byte {pos} does not hold the "
                            f"{inner_size:,} bytes of an array it says it holds")
        after = at + size
    elif kind == _MATRIX:
        body = raw[pos:at + size]
        walk.spend(size + 8)
    else:
        raise walk.fail(f"an element of MAT type {kind} at byte {pos}, where a "
                        "variable was expected")
    walk.matrix(body, 8, len(body), 0)
    return body, after
