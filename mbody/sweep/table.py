"""A sweep's results file: one row per case, ``case``, the varied paths (named as given),
the outputs (``<quantity>:<label>``), ``error`` (empty, or why the case has no numbers),
then ``settings`` (how the row was computed: `mbody.sweep.record`), sorted by case. CSV
(numbers as Python writes them: read back, each is the same double; a yes-or-no column,
`mbody.sweep.modes.FLAGS`, as ``true`` or ``false``) or Parquet (``.parquet``, its
yes-or-no columns boolean; needs pyarrow, in the ``sweep`` extra).

Nothing is lost on the way: rows are appended, as chunks finish, to a journal beside
the output (``<out>.partial``, CSV, flushed per chunk), and the output itself is written
once, at the end, through a temporary file renamed into place; then the journal goes.
A sweep started again with the same output resumes: the cases already in the output or
its journal are not run again. An earlier row is reused only when it is this sweep's:
the same columns, the same values under its case number, the same settings. A file
holding anything else (another sweep's rows, rows of other settings, a file of an mbody
that did not record the settings) is refused, naming what differs, or with ``force``
those rows are run again and replaced.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from mbody.errors import MbodyError, OutputError, option_name, option_setting
from mbody.sweep.grid import Grid
from mbody.sweep.modes import FLAGS
from mbody.sweep.record import SETTINGS, differences
from mbody.sweep.runs import Rows
from mbody.util.atomic import ensure_writable, make_folders, refuse_special, write_atomic

FORMATS = {".csv": "csv", ".parquet": "parquet"}
"""The output's formats, by its extension."""
JOURNAL = ".partial"
"""The journal's suffix, after the output's name."""
ERROR = "error"
"""The column of each case's error (empty when it has its numbers)."""


def again() -> str:
    """What to do with an output that holds rows that are not this sweep's, as the caller
    names the arguments (`mbody.errors.option_name`): ``--out``, ``--force`` on the
    command line; ``out=...``, ``force=True`` in Python."""
    return (f"give another {option_name('out', '...')} to keep it, or "
            f"{option_setting('force', True)} to run those cases again and replace their "
            "rows")


def output_format(path: str | os.PathLike[str]) -> str:
    """``csv`` or ``parquet`` from the output's extension (anything else refused)."""
    ext = Path(path).suffix.lower()
    if ext not in FORMATS:
        raise MbodyError(f"{path}: the results are written as .csv or .parquet; got "
                         f"{ext or 'no extension'}")
    return FORMATS[ext]


def journal_of(path: str | os.PathLike[str]) -> Path:
    return Path(f"{path}{JOURNAL}")


def cell(value: Any) -> str:
    """A value as the CSV holds it: a number as Python writes it (exact), NaN empty, a
    bool ``true`` or ``false``."""
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float | np.floating):
        x = float(value)
        return "" if math.isnan(x) else repr(x)
    if isinstance(value, int | np.integer):
        return str(int(value))
    return "" if value is None else str(value)


class Results:
    """The rows of one sweep, kept until `finish` writes them (module doc).

    Parameters
    ----------
    path : str or path-like
        The output (``.csv`` or ``.parquet``).
    outputs : sequence of str
        The output columns.
    grid : Grid
        The sweep's cases (their values are the path columns).
    settings : str
        This sweep's record (`mbody.sweep.record.record`), every row's ``settings`` cell.
    force : bool
        Earlier rows that are not this sweep's are dropped (their cases run again), not
        refused.
    """

    def __init__(self, path: str | os.PathLike[str], outputs: Sequence[str], grid: Grid,
                 settings: str, *, force: bool = False):
        self.path = Path(path)
        self.format = output_format(path)
        if self.format == "parquet":  # refused before any case runs, not after them all
            import importlib.util

            if importlib.util.find_spec("pyarrow") is None:
                raise MbodyError(_NO_PYARROW)
        self.grid = grid
        self.outputs = list(outputs)
        self.settings = settings
        self.force = force
        self.header = ["case", *grid.columns, *outputs, ERROR, SETTINGS]
        self._flags = [name in FLAGS for name in outputs]
        self.rows: dict[int, list[str]] = {}
        self.journal = journal_of(path)
        ensure_writable(self.path)  # a folder, a socket: refused before any case runs
        refuse_special(self.journal, "the journal beside --out")
        ensure_writable(self.journal)
        self._dropped: set[object] = set()
        self._stale_journal = False
        self._resume()
        self.replaced = len({d for d in self._dropped if d not in self.rows})
        """The earlier rows dropped, with `force`, as not this sweep's (their cases run
        again, and this sweep's rows replace them)."""
        self._out: io.TextIOWrapper | None = None
        self._writer: Any = None

    @property
    def done(self) -> set[int]:
        """The cases that have a row (from an earlier run, or this one)."""
        return set(self.rows)

    # -- resuming ------------------------------------------------------------------------
    def _resume(self) -> None:
        # an output that is a device or a named pipe is written through, never read back:
        # a pipe's reader would wait for a writer, a terminal for its user
        if self.path.is_file():
            self._take(self._read_output(), str(self.path))
        if self.journal.exists():
            self._take(_read_csv(self.journal), str(self.journal), journal=True)

    def _read_output(self) -> Iterator[list[str]]:
        if self.format == "csv":
            yield from _read_csv(self.path)
            return
        try:
            import pyarrow.parquet as pq
        except ImportError:
            raise MbodyError(_NO_PYARROW) from None
        try:
            table = pq.read_table(self.path)
        except Exception as exc:  # noqa: BLE001 - pyarrow's many errors: one message
            raise MbodyError(f"{self.path}: cannot read it as Parquet ({exc}); remove it or "
                             "give another --out") from None
        yield list(table.column_names)
        cols = [table.column(c).to_pylist() for c in table.column_names]
        for values in zip(*cols, strict=True):
            yield [cell(v) for v in values]

    def _take(self, lines: Iterator[list[str]], where: str, journal: bool = False) -> None:
        """Keep the rows of `lines` (a file's, its header first) that are this sweep's;
        refuse the file at the first that is not, or with `force` drop that row."""
        header = next(lines, None)
        if header is None:
            return
        problem = self._header_problem(header, where)
        if problem:
            if not self.force:
                raise MbodyError(problem)
            for n, row in enumerate(lines, 2):  # every row dropped
                self._drop(row, where, n, journal)
            return
        width = len(self.header)
        for n, row in enumerate(lines, 2):
            if len(row) != width and journal:  # cut short by an interruption: run it again
                continue
            problem = self._row_problem(row, where, n)
            if problem:
                if not self.force:
                    raise MbodyError(problem)
                self._drop(row, where, n, journal)
                continue
            self.rows[int(row[0])] = row

    def _header_problem(self, header: list[str], where: str) -> str:
        """Why the rows under `header` cannot be this sweep's, or ''."""
        if header == self.header:
            return ""
        if header == self.header[:-1]:
            return (f"{where} was written by an earlier mbody, which did not record the "
                    "settings its rows were computed with (the run's "
                    f"{option_name('t_end')}, {option_name('steps')} or {option_name('fps')}, "
                    "the model): they cannot be told to be this sweep's; " + again())
        return (f"{where} holds another sweep's results (its columns differ from this "
                f"sweep's); {again()}")

    def _row_problem(self, row: list[str], where: str, n: int) -> str:
        """Why `row` (line `n` of `where`) is not a row of this sweep, or ''."""
        width = len(self.header)
        if len(row) != width:
            return f"{where}:{n}: {len(row)} cells, expected {width}"
        try:
            case = int(row[0])
        except ValueError:
            return f"{where}:{n}: case {row[0]!r} is not a case number"
        if not 0 <= case < len(self.grid):
            return (f"{where}:{n}: case {case} is not a case of this sweep (it has "
                    f"{len(self.grid)}): the file holds another sweep's results; {again()}")
        want = [cell(x) for x in self.grid.numbers(case)]
        got = row[1:1 + len(want)]
        if not all(map(_same, got, want)):
            bad = next(i for i, (a, b) in enumerate(zip(got, want, strict=True))
                       if not _same(a, b))
            return (f"{where}:{n}: case {case} has {self.header[1 + bad]} = {row[1 + bad]} "
                    f"there but {want[bad]} in this sweep: the file holds another sweep's "
                    f"results; {again()}")
        if row[-1] != self.settings:
            said = " and ".join(differences(row[-1], self.settings)) or "other settings"
            return (f"{where}:{n}: case {case} was computed with {said}: the file holds "
                    f"the results of other settings, which are not this sweep's; {again()}")
        return ""

    def _drop(self, row: list[str], where: str, n: int, journal: bool) -> None:
        """Forget an earlier row that is not this sweep's (`force`): its case runs again,
        and a journal holding it is written anew."""
        try:
            self._dropped.add(int(row[0]))
        except (ValueError, IndexError):
            self._dropped.add((where, n))
        if journal:
            self._stale_journal = True

    # -- adding and writing ----------------------------------------------------------------
    def add(self, rows: Rows) -> None:
        """A chunk's rows, kept and appended to the journal (flushed)."""
        try:
            self._append(rows)
        except OutputError:
            raise
        except OSError as exc:  # a full disk, a quota: the journal beside --out
            raise OutputError(f"cannot write {str(self.journal)!r}, the journal beside "
                              f"the output {self.path}: {exc.strerror or exc}", exc,
                              str(self.journal)) from None

    def _append(self, rows: Rows) -> None:
        if self._out is None:
            # the output's folder, as writing the output would make it: a folder that
            # cannot be made is the output's problem, and named so
            make_folders(self.path, self.journal.parent)
            # a journal holding rows of another sweep (dropped with force) is begun anew,
            # with the rows kept so far: it never holds two sweeps' rows
            fresh = (self._stale_journal or not self.journal.exists()
                     or self.journal.stat().st_size == 0)
            self._out = open(self.journal, "w" if fresh else "a", newline="",  # noqa: SIM115
                             encoding="utf-8")
            self._writer = csv.writer(self._out)
            if fresh:
                self._writer.writerow(self.header)
                if self._stale_journal:
                    self._writer.writerows(self.rows[k] for k in sorted(self.rows))
                self._stale_journal = False
        for case, out, err in zip(rows.indices, rows.outputs, rows.errors, strict=True):
            if case in self.rows:  # a chunk run twice (a worker lost after it finished)
                continue
            row = [str(case), *(cell(x) for x in self.grid.numbers(case)),
                   *(flag(x) if yes_no else cell(x)
                     for x, yes_no in zip(out.tolist(), self._flags, strict=True)),
                   err or "", self.settings]
            self.rows[case] = row
            self._writer.writerow(row)
        self._out.flush()

    def close(self) -> None:
        if self._out is not None:
            self._out.close()
            self._out = None

    def finish(self) -> Path:
        """Write the output (every row, by case) in place of any earlier one, then remove
        the journal."""
        self.close()
        ordered = [self.rows[k] for k in sorted(self.rows)]
        if self.format == "csv":
            def write(fh: Any) -> None:
                w = csv.writer(fh, lineterminator="\n")
                w.writerow(self.header)
                w.writerows(ordered)

            write_atomic(self.path, write, binary=False)
        else:
            write_atomic(self.path, lambda fh: _write_parquet(fh, self.header, ordered),
                         binary=True)
        self.journal.unlink(missing_ok=True)
        return self.path


def flag(value: float) -> str:
    """A yes-or-no output (1.0 or 0.0 in a chunk's rows, NaN for none) as the CSV holds
    it: ``true``, ``false`` or empty."""
    return "" if math.isnan(value) else cell(bool(value))


def _same(a: str, b: str) -> bool:
    """Two cells of one value (a Parquet file reads a listed 0 back as 0.0)."""
    if a == b:
        return True
    try:
        return float(a) == float(b)
    except ValueError:
        return False


def _read_csv(path: Path) -> Iterator[list[str]]:
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            yield from csv.reader(fh)
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise MbodyError(f"{path}: cannot read it as a sweep's CSV results ({exc}); remove "
                         "it or give another --out") from None


_NO_PYARROW = ("Parquet output needs pyarrow: pip install 'mbody[sweep]' (or write .csv)")


def _write_parquet(fh: Any, header: list[str], rows: list[list[str]]) -> None:
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise MbodyError(_NO_PYARROW) from None
    columns: dict[str, Any] = {}
    for i, name in enumerate(header):
        texts = [r[i] for r in rows]
        if name == "case":
            columns[name] = pa.array([int(x) for x in texts], pa.int64())
        elif name in (ERROR, SETTINGS):
            columns[name] = pa.array(texts, pa.string())
        elif name in FLAGS:
            columns[name] = pa.array([None if not x else x == "true" for x in texts],
                                     pa.bool_())
        else:
            try:
                columns[name] = pa.array([float(x) if x else math.nan for x in texts],
                                         pa.float64())
            except ValueError:  # listed values of text (units, expressions)
                columns[name] = pa.array(texts, pa.string())
    pq.write_table(pa.table(columns), fh)
