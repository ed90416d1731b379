"""A ``.npz`` archive read as input that may be hostile: what it holds is known, and
checked, before anything is inflated; and a data file (a run file, an export) read within
its byte budget (`mbody.util.budget`).

A run file (`mbody.Trajectory.save`) and an npz export are zip archives of ``.npy``
arrays, files that people pass around. `numpy.load` trusts what they say: a member's
``.npy`` header may claim 10^15 values, which numpy allocates before it reads a byte, and
a member of 2 MB on disk may inflate to 2 GB. `NpzArchive` first reads the zip directory
and every member's ``.npy`` header (a few hundred bytes each) and refuses the archive
unless

- each member is stored or deflated (what numpy writes), not encrypted, and named once;
- its header's shape and dtype account for exactly the member's size in the zip
  directory, which is also the most that member can inflate to (`zipfile` stops there),
  and its values are at least a byte wide (values of 0 bytes would claim any number of
  them in no bytes at all);
- the members' sizes add up to at most the byte budget (`mbody.util.budget`: 1 GiB by
  default).

Only then is an array read: reading an archive costs time and memory in proportion to
what it holds, at most the budget, whatever its headers claim.

    with NpzArchive(path, "trajectory file") as z:
        z.shape("t")        # from the header, nothing inflated
        t = z.read("t")
"""

from __future__ import annotations

import math
import os
import stat
import zlib
from types import TracebackType
from typing import IO, TYPE_CHECKING

import numpy as np

from mbody.errors import MbodyError
from mbody.util.budget import DATA_BYTES, TEXT_BYTES, byte_limit
from mbody.util.formatting import size_text, sizes_apart
from mbody.util.frozen import Frozen

if TYPE_CHECKING:
    import zipfile

HEADER_CHARS = 10_000
"""Longest ``.npy`` header read (numpy's own default): the header is a Python literal."""

_METHODS = (0, 8)
"""The zip methods numpy writes: stored, deflated."""


def over_budget(name: str, holds: int, on_disk: int, limit: int, more: str) -> str:
    """The message for a file that holds more than the budget: what it holds (inflated),
    its size on disk, the budget and how to raise it (`more`)."""
    packed = f" once inflated ({size_text(on_disk)} on disk)" if on_disk < holds else ""
    held, most = sizes_apart(holds, limit)
    return f"{name}: holds {held} of data{packed}; at most {most} is read ({more})"


def read_bytes(path: str | os.PathLike[str], max_bytes: int | None = None,
               more: str = "mbody.load_export(path, max_bytes=N) reads more",
               error: type[MbodyError] = MbodyError, default: int = DATA_BYTES) -> bytes:
    """The bytes of a data file (a .mat, JSON or CSV export), refused unread when it is
    larger than its budget (`mbody.util.budget.byte_limit` of `max_bytes` and `default`),
    or is not a regular file (a pipe would block, a device never end).

    Raises
    ------
    error
        Naming the file: too large (the budget and `more`), not a regular file.
    """
    limit = byte_limit(max_bytes, default)
    st = os.stat(path)
    if not stat.S_ISREG(st.st_mode):
        raise error(f"{path}: not a regular file (a folder, a device or a pipe); expected "
                    "a file mbody wrote")
    if st.st_size > limit:
        raise error(over_budget(str(path), st.st_size, st.st_size, limit, more))
    with open(path, "rb") as fh:  # what stat() said, and a byte to see if it grew since
        raw = fh.read(st.st_size + 1)  # (read(limit) would allocate the whole limit)
    if len(raw) > limit:
        raise error(over_budget(str(path), len(raw), len(raw), limit, more))
    return raw


def read_text(path: str | os.PathLike[str], max_bytes: int | None = None,
              more: str = "mbody.load_export(path, max_bytes=N) reads more",
              error: type[MbodyError] = MbodyError) -> str:
    """The UTF-8 text of a JSON or CSV export: `read_bytes` with the text budget
    (`TEXT_BYTES` by default).

    Raises
    ------
    error
        As `read_bytes`.
    UnicodeDecodeError
        The file is not UTF-8 (a `ValueError`).
    """
    return read_bytes(path, max_bytes, more, error, TEXT_BYTES).decode("utf-8")


class Member(Frozen):
    """One ``.npy`` member as its header and the zip directory describe it (frozen:
    `Frozen`). A plain class, not a dataclass: a dataclass compiles its methods from
    source when the class is made, 0.25 ms (0.5 ms frozen) of every process that
    simulates, since `Trajectory` imports this module.

    Parameters
    ----------
    name : str
        The array's name (the member's name without ``.npy``).
    shape : tuple of int
        The shape its header gives.
    dtype : numpy.dtype
        The element type its header gives.
    nbytes : int
        The member's size inflated, from the zip directory (header and data).
    """

    name: str
    shape: tuple[int, ...]
    dtype: np.dtype
    nbytes: int

    def __init__(self, name: str, shape: tuple[int, ...], dtype: np.dtype, nbytes: int):
        self.__dict__.update(name=name, shape=shape, dtype=dtype, nbytes=nbytes)

    def __repr__(self) -> str:
        return (f"Member(name={self.name!r}, shape={self.shape!r}, dtype={self.dtype!r}, "
                f"nbytes={self.nbytes!r})")


class NpzArchive:
    """An ``.npz`` archive whose every member is checked before any is read (module doc).

    Parameters
    ----------
    path : str or os.PathLike
        The archive.
    what : str
        What the file is, for messages ("trajectory file", "export file").
    max_bytes : int, optional
        The budget (default `mbody.util.budget.DATA_BYTES`, or the one set around the
        call: `mbody.util.budget.byte_limit`).
    more : str
        How a user reads a larger file, quoted when the budget refuses it.
    error : type of MbodyError
        The exception raised for a damaged or refused archive; its message names the
        file, and the member when one is at fault.
    damage : str, optional
        What a damaged archive is called in messages (default "damaged or truncated
        `what`").

    Raises
    ------
    error
        The archive is not a zip, a member is not an array mbody reads (another
        compression, encrypted, named twice, Python objects, a header that does not
        fit its size), or it holds more than `max_bytes`.
    """

    def __init__(self, path: str | os.PathLike[str], what: str, *,
                 max_bytes: int | None = None, more: str = "", error: type[MbodyError]
                 = MbodyError, damage: str | None = None) -> None:
        self.name = str(path)
        self.what = what
        self.damage = damage or f"damaged or truncated {what}"
        self.error = error
        self.limit = byte_limit(max_bytes, DATA_BYTES)
        # here, not at the top: a simulation imports this module without reading a file,
        # and zipfile (with bz2, lzma, shutil) costs milliseconds of its first import
        import zipfile
        try:  # kept open until close(): members are read when asked for
            if not stat.S_ISREG(os.stat(path).st_mode):  # a pipe would block in open()
                raise error(f"{self.name}: not a regular file (a folder, a device or a "
                            f"pipe); expected a {what}")
            self._fh: IO[bytes] = open(path, "rb")  # noqa: SIM115
        except OSError as exc:
            raise error(f"{self.name}: cannot read the file: {exc.strerror}") from None
        try:
            self._zip = zipfile.ZipFile(self._fh)
            self.members = self._scan(more)
        except BaseException as exc:
            self.close()
            if isinstance(exc, MbodyError):
                raise
            if isinstance(exc, zipfile.BadZipFile | zlib.error | EOFError | ValueError
                          | OSError | RuntimeError | NotImplementedError):
                raise self.damaged(f"{type(exc).__name__}: {exc}") from None
            raise

    # -- checks before anything is inflated -------------------------------------------------
    def _scan(self, more: str) -> dict[str, Member]:
        infos = [i for i in self._zip.infolist() if i.filename.endswith(".npy")]
        seen: set[str] = set()
        for info in infos:
            if info.filename in seen:
                raise self.damaged(f"member {info.filename} is there twice")
            seen.add(info.filename)
            if info.flag_bits & 0x1:
                raise self.damaged(f"member {info.filename} is encrypted")
            if info.compress_type not in _METHODS:
                raise self.damaged(f"member {info.filename} is compressed by zip "
                                   f"method {info.compress_type}; numpy writes "
                                   "stored or deflated members")
        holds = sum(i.file_size for i in infos)
        if holds > self.limit:
            raise self.error(over_budget(self.name, holds, os.fstat(self._fh.fileno()).st_size,
                                         self.limit, more))
        return {i.filename[:-4]: self._member(i) for i in infos}

    def _member(self, info: zipfile.ZipInfo) -> Member:
        """The member's header, checked against its size in the directory."""
        where = f"member {info.filename}"
        with self._zip.open(info) as f:
            try:
                version = np.lib.format.read_magic(f)
                if version == (1, 0):
                    shape, _, dtype = np.lib.format.read_array_header_1_0(
                        f, max_header_size=HEADER_CHARS)
                elif version == (2, 0):
                    shape, _, dtype = np.lib.format.read_array_header_2_0(
                        f, max_header_size=HEADER_CHARS)
                else:
                    raise ValueError(f".npy format version {version[0]}.{version[1]}, "
                                     "expected 1.0 or 2.0")
            except (ValueError, EOFError) as exc:
                raise self.damaged(f"{where} is not a numpy array ({exc})") from None
            header = f.tell()
        if dtype.hasobject:
            raise self.damaged(f"{where} holds Python objects, which mbody never "
                               "unpickles")
        values = math.prod(shape)
        if dtype.itemsize == 0 and values:
            # the size check below says nothing of how many values such a member claims,
            # and each may become a Python object (a text of 0 characters: 10^12 of them
            # in a file of 5 kB); numpy writes even an empty text 1 character wide
            raise self.damaged(f"{where}'s header says it holds {_shape_text(shape)} values "
                               f"of 0 bytes each, dtype {dtype.str}: numpy writes every value "
                               "at least a byte wide")
        data = values * dtype.itemsize
        if header + data != info.file_size:
            raise self.damaged(
                f"{where}'s header says it holds {_shape_text(shape)} values of "
                f"{dtype.itemsize} bytes ({size_text(data)}), but the zip directory gives "
                f"it {size_text(max(info.file_size - header, 0))} of data")
        return Member(info.filename[:-4], tuple(shape), dtype, info.file_size)

    def damaged(self, problem: str) -> MbodyError:
        """The error for a damaged archive: the file, then `problem`."""
        return self.error(f"{self.name}: {self.damage} ({problem})")

    # -- reading -----------------------------------------------------------------------------
    @property
    def files(self) -> list[str]:
        """The arrays' names, in the archive's order."""
        return list(self.members)

    def __contains__(self, key: str) -> bool:
        return key in self.members

    def shape(self, key: str) -> tuple[int, ...]:
        """The shape of array `key`, from its header (nothing inflated)."""
        return self.members[key].shape

    def read(self, key: str) -> np.ndarray:
        """Array `key`, inflated (at most its checked size).

        Raises
        ------
        error
            The member's data is cut short or does not match its checksum.
        """
        import zipfile  # imported by __init__ already: its error type

        try:
            with self._zip.open(key + ".npy") as f:
                return np.lib.format.read_array(f, allow_pickle=False,
                                                max_header_size=HEADER_CHARS)
        except (zipfile.BadZipFile, zlib.error, EOFError, ValueError, OSError) as exc:
            raise self.damaged(f"member {key}.npy: {type(exc).__name__}: {exc}") \
                from None

    def close(self) -> None:
        """Close the archive and its file."""
        zf = getattr(self, "_zip", None)
        if zf is not None:
            zf.close()
        self._fh.close()

    def __enter__(self) -> NpzArchive:
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()


def _shape_text(shape: tuple[int, ...]) -> str:
    """'1,000,000,000,000,000' for (10**15,), '61 x 1 x 2' for (61, 1, 2)."""
    return " x ".join(f"{n:,}" for n in shape) if shape else "1 (a scalar)"
