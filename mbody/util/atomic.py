"""Writing outputs without ever leaving a partial file, and without ever replacing what
is not a file: every output of mbody goes through here.

A regular file (or a new one) is written to a temporary file in its folder, flushed to
disk, then renamed into place (atomic on POSIX); a symbolic link is followed, so the
file it names is replaced and the link stays. A target that is not a regular file (after
following links) is never replaced: a character device (``/dev/null``, a terminal) or a
named pipe is written through (opened and written, from a complete temporary copy, so
that a writer's failure sends nothing); the command's own standard output (``-o
/dev/stdout``) is written through its descriptor; a block device, a socket or a folder
is refused. Folders made for an output are removed again when the output fails.

An output is never one of the command's own inputs, however named, whatever the options
(`refuse_overwriting_inputs`), nor the file of another of its outputs
(`refuse_one_file_twice`), and never a folder or a device where a regular file is meant
(`ensure_writable`, `refuse_special`).
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import stat
import sys
import tempfile
import time
from collections.abc import Callable, Container, Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import IO, Any

from mbody.errors import MbodyError, OutputError

PIPE_WAIT = 2.0
"""Seconds a named pipe given as an output may take to get a reader before it is refused
(opening it blocks until a program reads it; no reader would hang the command)."""
CHUNK = 1 << 20
"""Bytes copied at a time when writing through a device or a pipe."""


def _kind(mode: int) -> str:
    return ("a folder" if stat.S_ISDIR(mode) else "a named pipe" if stat.S_ISFIFO(mode)
            else "a character device" if stat.S_ISCHR(mode)
            else "a block device (a disk)" if stat.S_ISBLK(mode)
            else "a socket" if stat.S_ISSOCK(mode) else "not a regular file")


def _stdout_fd() -> int | None:
    """The descriptor of `sys.stdout`, or None (a test's capture, a closed stream)."""
    try:
        return sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):
        return None


def is_standard_output(target: str | os.PathLike[str]) -> bool:
    """Whether `target` is the file, pipe or terminal this process's standard output goes
    to (``/dev/stdout``, ``/proc/self/fd/1``, or the file stdout is redirected to): a
    command writing its output there prints its messages to stderr instead."""
    fd = _stdout_fd()
    if fd is None:
        return False
    try:
        return os.path.samestat(os.stat(target), os.fstat(fd))
    except (OSError, ValueError):
        return False


def _plan(target: Path) -> tuple[str, Path]:
    """How `target` is written: ("rename", the real path to replace or create),
    ("stdout", target) or ("through", target); refuses what can never be written."""
    try:
        st = os.stat(target)
    except FileNotFoundError:
        return "rename", Path(os.path.realpath(target))
    except OSError as exc:  # a loop of links, a name too long, no permission to look
        raise MbodyError(f"cannot write {str(target)!r}: {exc.strerror or exc}") from None
    fd = _stdout_fd()
    if fd is not None:
        with contextlib.suppress(OSError, ValueError):
            if os.path.samestat(st, os.fstat(fd)):
                return "stdout", target
    if stat.S_ISREG(st.st_mode):
        real = Path(os.path.realpath(target))
        try:
            if os.path.samestat(os.stat(real), st):
                return "rename", real
        except OSError:
            pass
        return "through", target  # a /proc/self/fd link to a file that has no name left
    if stat.S_ISCHR(st.st_mode) or stat.S_ISFIFO(st.st_mode):
        return "through", target
    if stat.S_ISDIR(st.st_mode):
        raise MbodyError(f"cannot write {str(target)!r}: it is a folder; give a file name")
    raise MbodyError(f"cannot write {str(target)!r}: it is {_kind(st.st_mode)}, which mbody "
                     "never writes onto; give a file name")


def _prefix(target: Path) -> str:
    """A temporary file's prefix: a hidden name after the target's, short enough that a
    target name the file system takes (up to 255 bytes) still leaves room for it."""
    return f".{target.stem.encode()[:60].decode(errors='ignore')}."


def _name_fits(target: Path, folder: Path) -> None:
    """Refuse a file name longer than the file system takes, before any work."""
    try:
        limit = os.pathconf(folder, "PC_NAME_MAX")
    except (OSError, ValueError, AttributeError):
        limit = 255
    size = len(os.fsencode(target.name))
    if size > limit:
        raise MbodyError(f"cannot write {str(target)!r}: the file name is {size} bytes long; "
                         f"this file system takes at most {limit}")


def _missing_folders(folder: Path) -> list[Path]:
    """`folder` and those of its parents that do not exist yet, deepest first; refuses
    a parent that exists and is not a folder."""
    missing = []
    for p in (folder, *folder.parents):
        if p.exists():
            if not p.is_dir():
                raise MbodyError(f"{str(p)!r} is a file, not a folder")
            break
        missing.append(p)
    return missing


def ensure_writable(target: str | os.PathLike[str]) -> Path:
    """Check (before any long work) that `target` can be written, and change nothing:
    a device or a named pipe must be writable by this user; a file's folder must exist
    and be writable, or be one that can be made in a writable folder; `target` is not a
    folder, a block device or a socket. Returns the folder (which may not exist yet);
    raises `MbodyError` with the reason."""
    target = Path(target)
    how, real = _plan(target)
    if how != "rename":
        if how == "through" and not os.access(target, os.W_OK):
            raise MbodyError(f"cannot write {str(target)!r}: permission denied")
        return target.parent
    folder = real.parent
    try:
        missing = _missing_folders(folder)
    except MbodyError as exc:
        raise MbodyError(f"cannot write {str(target)!r}: {exc}") from None
    existing = missing[-1].parent if missing else folder
    if not os.access(existing, os.W_OK):
        raise MbodyError(f"cannot write {str(target)!r}: the folder {str(existing)!r} is "
                         "not writable")
    _name_fits(target, existing)
    return folder


def refuse_special(target: str | os.PathLike[str], what: str) -> None:
    """Refuse a `target` that exists and is not a regular file (after following links),
    for an output that is appended to and read back (a sweep's journal): a named pipe
    would block the read, a device never hold the rows. A missing `target` passes."""
    try:
        mode = os.stat(target).st_mode
    except FileNotFoundError:
        return
    except OSError as exc:
        raise MbodyError(f"cannot write {str(target)!r}: {exc.strerror or exc}") from None
    if not stat.S_ISREG(mode):
        raise MbodyError(f"cannot write {str(target)!r}: it is {_kind(mode)}, and {what} "
                         "must be a regular file; remove it or give another output")


def refuse_overwriting_inputs(outputs: Iterable[tuple[str, str]],
                              inputs: Iterable[tuple[str, str]],
                              folders: Container[str] = (),
                              suffixes: Mapping[str, Sequence[str]] | None = None,
                              resumed: Container[str] = ()) -> None:
    """Refuse an output that is one of the command's own inputs: the same file, compared
    by identity (device and inode: a link or another spelling of the path is the same
    file), not by name. No option passes it (``--force`` neither): an input written over
    is lost, and the command, which reads it first, would not have it to read again.
    `outputs` and `inputs` are (what, path) pairs: ``("-o", "m.yaml")``, ``("the model",
    "m.yaml")``. The message says which output, which input, and what to do; where the
    output could not be written there anyway it says why: an output whose option is in
    `folders` writes a folder; one whose option's suffix chooses the format (`suffixes`:
    option -> the suffixes it writes) has a name without one of them; one whose option
    is in `resumed` is read back to resume the run (a sweep's results and their
    journal), which needs its inputs as they were."""

    def why(flag: str, path: str, what: str) -> str:
        """What to do instead of writing `path` (`what`) with `flag`."""
        if flag in folders:
            return f"{flag} writes a folder; give a folder's name"
        if flag in resumed:
            return (f"{flag} is read back to resume the run, which needs {what} as it was; "
                    "give another output file")
        allowed = (suffixes or {}).get(flag)
        if allowed and Path(path).suffix.lower() not in allowed:
            return (f"{flag} writes a file ending in {', '.join(allowed)}; give another "
                    "output file")
        return ("writing there would replace the input, which no option allows (--force "
                "neither); give another output file")

    seen = []
    for what, path in inputs:
        try:
            st = os.stat(path)
        except (OSError, ValueError):
            continue
        if stat.S_ISREG(st.st_mode):
            seen.append((what, path, st))
    for flag, path in outputs:
        try:
            st = os.stat(path)
        except (OSError, ValueError):
            continue  # a new file: nothing to lose
        for what, source, st_in in seen:
            if os.path.samestat(st, st_in):
                same = "" if source == path else ", the same file"
                raise MbodyError(f"{flag} {path} is {what} itself ({source}{same}): "
                                 f"{why(flag, path, what)}")


def refuse_one_file_twice(outputs: Iterable[tuple[str, str]]) -> None:
    """Refuse two outputs of one command that are one file, whatever the options (the
    second written would replace the first): compared by identity where the file is
    there (a link, a hard link, another spelling of the path), else by the path with its
    links followed. `outputs` are (option, path) pairs, as `refuse_overwriting_inputs`
    takes them. A device or a named pipe is written through, not replaced: two outputs
    there (``/dev/null``) pass; so do two on the command's own standard output, written
    one after the other through its descriptor (`_plan`), whether it goes to a terminal,
    a pipe or a file."""
    seen: dict[object, tuple[str, str]] = {}
    fd = _stdout_fd()
    try:
        out = os.fstat(fd) if fd is not None else None
    except (OSError, ValueError):
        out = None
    for flag, path in outputs:
        try:
            st = os.stat(path)
        except FileNotFoundError:
            key: object = os.path.normcase(os.path.realpath(path))  # new: where it will be
        except (OSError, ValueError):
            continue  # refused, with its reason, where it is written
        else:
            if not (stat.S_ISREG(st.st_mode) or stat.S_ISDIR(st.st_mode)):
                continue
            if out is not None and os.path.samestat(st, out):
                continue  # the standard output, appended to, never replaced
            key = (st.st_dev, st.st_ino)
        if key in seen:
            first, where = seen[key]
            both = (f"{flag} {path} is given twice" if (first, where) == (flag, path) else
                    f"{first} and {flag} are both {path}" if where == path else
                    f"{flag} {path} is {first} {where}, the same file")
            raise MbodyError(f"{both}: one output would replace the other; give each output "
                             "its own file")
        seen[key] = (flag, path)


def make_folders(target: str | os.PathLike[str], folder: Path) -> list[Path]:
    """Make `folder` (where `target`, or a file beside it, is written) with its missing
    parents; return those made (deepest first). A folder that cannot be made is an
    `OutputError` naming `target`, the output the user gave."""
    try:
        missing = _missing_folders(folder)
        folder.mkdir(parents=True, exist_ok=True)
    except MbodyError as exc:
        raise MbodyError(f"cannot write {str(target)!r}: {exc}") from None
    except OSError as exc:
        raise OutputError(f"cannot write {str(target)!r}: cannot make the folder "
                          f"{str(folder)!r} ({exc.strerror or exc})", exc, str(folder)
                          ) from None
    return missing



def _remove_folders(made: list[Path]) -> None:
    """Remove the folders an output made, deepest first, if they are still empty."""
    for p in made:
        try:
            p.rmdir()
        except OSError:
            break


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike[str], suffix: str = "") -> Iterator[Path]:
    """Yield a temporary path to write the whole output to; on success put it in place.

    A regular or new file is replaced by a rename (atomic); a device, a named pipe or
    standard output is written through from the complete temporary file (see the
    module's text). On any exception the temporary file (and any folder made for it) is
    removed and `target` is left untouched; an operating-system error (ENOSPC, EDQUOT,
    EFBIG, EIO...) becomes one `OutputError` (an `MbodyError` and an `OSError`) naming
    `target`. `suffix` keeps the extension for writers that look at it (numpy,
    scipy.io).
    """
    target = Path(target)
    how, real = _plan(target)
    made: list[Path] = []
    if how == "rename":
        made = make_folders(target, real.parent)
        where: str | None = str(real.parent)
    else:  # written through: the whole output is made first, away from the device
        where = None
    try:
        fd, tmp = tempfile.mkstemp(prefix=_prefix(target), suffix=suffix or target.suffix[:20],
                                   dir=where)
    except OSError as exc:
        _remove_folders(made)
        raise MbodyError(f"cannot write {str(target)!r}: {exc.strerror or exc}") from None
    os.close(fd)
    tmp_path = Path(tmp)
    os.chmod(tmp_path, 0o666 & ~_umask())  # mkstemp makes 0600; give what open() would
    sent = False
    try:
        yield tmp_path
        if how == "rename":
            with open(tmp_path, "rb+") as fh:
                os.fsync(fh.fileno())
            os.replace(tmp_path, real)
        else:
            sent = True
            _write_through(tmp_path, target, how == "stdout")
    except BaseException as exc:
        with contextlib.suppress(OSError):
            tmp_path.unlink(missing_ok=True)
        _remove_folders(made)
        if isinstance(exc, OSError) and not isinstance(exc, OutputError):
            _release(exc)
            raise OutputError(_failed(target, exc, sent), exc, str(target)) from None
        raise
    finally:
        if how != "rename":
            with contextlib.suppress(OSError):
                tmp_path.unlink(missing_ok=True)


def _failed(target: Path, exc: OSError, sent: bool) -> str:
    """The message of an output that failed with `exc` (after writing through began
    when `sent`)."""
    reason = exc.strerror or str(exc)
    if sent:
        return (f"cannot write {str(target)!r}: {reason}; the output is incomplete (a "
                "device or a pipe is written as it goes and cannot be taken back)")
    return (f"cannot write {str(target)!r}: {reason}; nothing was written (the temporary "
            f"file is removed, and {target.name!r} is as it was)")


def _open_through(target: Path) -> int:
    """A descriptor writing to the device or pipe `target`, opened without blocking (a
    pipe without a reader is retried for PIPE_WAIT seconds, then refused)."""
    flags = os.O_WRONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
    deadline = time.monotonic() + PIPE_WAIT
    while True:
        try:
            fd = os.open(target, flags)
            break
        except OSError as exc:
            if exc.errno != errno.ENXIO:  # ENXIO: a named pipe that nobody reads yet
                raise
            if time.monotonic() >= deadline:
                raise MbodyError(f"cannot write {str(target)!r}: no program reads this named "
                                 f"pipe (waited {PIPE_WAIT:g} s); start the reader first, or "
                                 "give a file name") from None
            time.sleep(0.05)
    with contextlib.suppress(OSError, ImportError):  # writes block again, as for any pipe
        import fcntl

        fcntl.fcntl(fd, fcntl.F_SETFL, fcntl.fcntl(fd, fcntl.F_GETFL) & ~os.O_NONBLOCK)
    return fd


def _write_through(tmp: Path, target: Path, to_stdout: bool) -> None:
    """Copy the complete output `tmp` into `target` (a device, a pipe, standard output)."""
    if to_stdout:
        sys.stdout.flush()
        fd = _stdout_fd()
        assert fd is not None  # _plan saw it
    else:
        fd = _open_through(target)
    try:
        with open(tmp, "rb") as src:
            while chunk := src.read(CHUNK):
                view = memoryview(chunk)
                while view:
                    view = view[os.write(fd, view):]
    finally:
        if not to_stdout:
            os.close(fd)


def write_atomic(target: str | os.PathLike[str],
                 write: Callable[[IO[Any]], object] | bytes | str,
                 binary: bool | None = None) -> Path:
    """Write `write` (bytes, text, or a callable given the open file) atomically.

    Parameters
    ----------
    target
        The file to write (or a device, pipe or standard output, written through).
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
    only after every file is complete, so a failed writer changes nothing; a file of
    `target` that is a device or a named pipe is written through, as `atomic_path` does.

    Parameters
    ----------
    target
        The folder to fill; created with its parents if needed (and removed again, with
        the parents made for it, when the writer fails).

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
    made = make_folders(target, parent)
    try:
        tmp = Path(tempfile.mkdtemp(prefix=_prefix(target), dir=parent))
    except OSError as exc:
        _remove_folders(made)
        raise MbodyError(f"cannot write {str(target)!r}: {exc.strerror or exc}") from None
    os.chmod(tmp, 0o777 & ~_umask())  # mkdtemp makes 0700; give what mkdir() would
    try:
        yield tmp
        if not target.exists():
            os.replace(tmp, target)
        else:
            files = sorted(tmp.iterdir())
            plans = [(f, *_plan(target / f.name)) for f in files]  # refuse before moving
            for f, how, real in plans:
                if how == "rename":
                    os.replace(f, real)
                else:
                    _write_through(f, target / f.name, how == "stdout")
            shutil.rmtree(tmp)
    except BaseException as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        _remove_folders(made)
        if isinstance(exc, OSError):  # one of its files' OutputError too: name the folder
            _release(exc)
            raise OutputError(f"cannot write {str(target)!r}: {exc.strerror or exc}; nothing "
                              "was written (the temporary folder is removed, and "
                              f"{target.name!r} is as it was)", exc, str(target)) from None
        raise


def _release(exc: BaseException) -> None:
    """Free, quietly, what the failed writer's frames still hold: numpy < 2's savez keeps a
    ZipFile on its file, whose __del__ (at exit, the file long closed) would print a
    traceback after the clean message."""
    import gc  # both only here, after a failed write: traceback costs 0.6 ms of every
    import traceback  # start-up, gc 0.05 ms of a simulate's first call (its import)

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
