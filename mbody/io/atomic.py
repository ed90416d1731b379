"""Writing outputs without ever leaving a partial file: write a temporary file in the
target's folder, flush it to disk, then rename it into place (atomic on POSIX)."""

from __future__ import annotations

import contextlib
import gc
import os
import shutil
import sys
import tempfile
import traceback
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO, Any

from mbody.errors import MbodyError, OutputError


def ensure_writable(target: str | os.PathLike[str]) -> Path:
    """Check (before any long work) that `target` can be written: its folder exists or can
    be made, is a folder, and is writable; `target` itself is not a folder. Missing
    folders are created. Returns the folder; raises `MbodyError` with the reason."""
    target = Path(target)
    folder = target.parent if str(target.parent) else Path(".")
    if target.is_dir():
        raise MbodyError(f"cannot write {str(target)!r}: it is a folder; give a file name")
    for p in (folder, *folder.parents):
        if p.exists():
            if not p.is_dir():
                raise MbodyError(f"cannot write {str(target)!r}: {str(p)!r} is a file, "
                                 "not a folder")
            break
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise MbodyError(f"cannot write {str(target)!r}: cannot make the folder "
                         f"{str(folder)!r} ({exc.strerror or exc})") from None
    if not os.access(folder, os.W_OK):
        raise MbodyError(f"cannot write {str(target)!r}: the folder {str(folder)!r} is "
                         "not writable")
    return folder


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike[str], suffix: str = "") -> Iterator[Path]:
    """Yield a temporary path next to `target`; on success rename it onto `target`.

    On any exception the temporary file is removed and `target` is left untouched; an
    operating-system error (ENOSPC, EDQUOT, EFBIG, EIO...) becomes one `OutputError`
    (an `MbodyError` and an `OSError`) naming `target`.
    `suffix` keeps the extension for writers that look at it (numpy, scipy.io).
    """
    target = Path(target)
    folder = ensure_writable(target)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=suffix or target.suffix,
                                   dir=folder)
    except OSError as exc:
        raise MbodyError(f"cannot write {str(target)!r}: {exc.strerror or exc}") from None
    os.close(fd)
    tmp_path = Path(tmp)
    os.chmod(tmp_path, 0o666 & ~_umask())  # mkstemp makes 0600; give what open() would
    try:
        yield tmp_path
        with open(tmp_path, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp_path, target)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            tmp_path.unlink(missing_ok=True)
        if isinstance(exc, OSError):  # a full disk, a quota, a file-size limit, I/O
            _release(exc)
            raise OutputError(f"cannot write {str(target)!r}: {exc.strerror or exc}; "
                              "nothing was written (the temporary file is removed, and "
                              f"{target.name!r} is as it was)", exc, str(target)) from None
        raise


def write_atomic(target: str | os.PathLike[str],
                 write: Callable[[IO[Any]], object] | bytes | str,
                 binary: bool | None = None) -> Path:
    """Write `write` (bytes, text, or a callable given the open file) atomically.

    Parameters
    ----------
    target
        The file to write.
    write
        The content, or a callable that writes it to the open file it is given (text
        is encoded, and bytes decoded, as UTF-8 when the mode asks for the other).
    binary
        Open the file in binary mode; by default, unless `write` is a str.

    Returns
    -------
    Path
        `target`.
    """
    if binary is None:
        binary = not isinstance(write, str)
    with atomic_path(target) as tmp:
        if binary:
            with open(tmp, "wb") as fb:
                if callable(write):
                    write(fb)
                else:
                    fb.write(write.encode("utf-8") if isinstance(write, str) else write)
        else:
            with open(tmp, "w", encoding="utf-8") as ft:
                if callable(write):
                    write(ft)
                else:
                    ft.write(write if isinstance(write, str) else write.decode("utf-8"))
    return Path(target)


@contextlib.contextmanager
def atomic_folder(target: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary folder next to `target`; on success move its files into `target`.

    A new `target` is the temporary folder renamed (one atomic step). An existing one
    gets each file renamed in (each file atomic; files of `target` not written are kept),
    only after every file is complete, so a failed writer changes nothing.

    Parameters
    ----------
    target
        The folder to fill; created with its parents if needed.

    Raises
    ------
    MbodyError
        When `target` exists and is not a folder.
    OutputError
        On an operating-system error (a full disk...), naming `target`; the temporary
        folder is removed.
    """
    target = Path(target)
    if target.exists() and not target.is_dir():
        raise MbodyError(f"{target}: exists and is not a folder")
    parent = target.parent if str(target.parent) else Path(".")
    try:
        parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=parent))
    except OSError as exc:
        raise MbodyError(f"cannot write {str(target)!r}: {exc.strerror or exc}") from None
    os.chmod(tmp, 0o777 & ~_umask())  # mkdtemp makes 0700; give what mkdir() would
    try:
        yield tmp
        if not target.exists():
            os.replace(tmp, target)
        else:
            for f in sorted(tmp.iterdir()):
                os.replace(f, target / f.name)
            tmp.rmdir()
    except BaseException as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        if isinstance(exc, OSError) and not isinstance(exc, OutputError):
            _release(exc)
            raise OutputError(f"cannot write {str(target)!r}: {exc.strerror or exc}; the "
                              "temporary folder is removed, and the target is as it was",
                              exc, str(target)) from None
        raise


def _release(exc: BaseException) -> None:
    """Free, quietly, what the failed writer's frames still hold: numpy < 2's savez keeps a
    ZipFile on its file, whose __del__ (at exit, the file long closed) would print a
    traceback after the clean message."""
    hook = sys.unraisablehook
    sys.unraisablehook = lambda unraisable: None
    try:
        seen: set[int] = set()
        chain: list[BaseException | None] = [exc]
        while chain:  # the error, and those raised while its writer was cleaning up
            e = chain.pop()
            if e is not None and id(e) not in seen:
                seen.add(id(e))
                traceback.clear_frames(e.__traceback__)
                chain += [e.__context__, e.__cause__]
        gc.collect()
    finally:
        sys.unraisablehook = hook


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
