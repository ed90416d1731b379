"""Writing outputs without ever leaving a partial file: write a temporary file in the
target's folder, flush it to disk, then rename it into place (atomic on POSIX)."""

from __future__ import annotations

import contextlib
import gc
import os
import sys
import tempfile
import traceback
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO

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


def write_atomic(target: str | os.PathLike[str], write: Callable[[IO], object] | bytes | str,
                 binary: bool | None = None) -> Path:
    """Write `write` (bytes, text, or a callable given the open file) atomically."""
    if binary is None:
        binary = not isinstance(write, str)
    with atomic_path(target) as tmp, open(tmp, "wb" if binary else "w",
                                          **({} if binary else {"encoding": "utf-8"})) as fh:
        if callable(write):
            write(fh)
        else:
            fh.write(write)
    return Path(target)


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
