"""A sweep's results file: one row per case, ``case``, the varied paths (named as given),
the outputs (``<quantity>:<label>``), then ``error`` (empty, or why the case has no
numbers), sorted by case. CSV (numbers as Python writes them: read back, each is the
same double) or Parquet (``.parquet``; needs pyarrow, in the ``sweep`` extra).

Nothing is lost on the way: rows are appended, as chunks finish, to a journal beside
the output (``<out>.partial``, CSV, flushed per chunk), and the output itself is written
once, at the end, through a temporary file renamed into place; then the journal goes.
A sweep started again with the same output resumes: the cases already in the output or
its journal are not run again (a file of another sweep, whose case numbers do not hold
the same values, is refused).
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

from mbody.errors import MbodyError
from mbody.sweep.grid import Grid
from mbody.sweep.runs import Rows
from mbody.util.atomic import write_atomic

FORMATS = {".csv": "csv", ".parquet": "parquet"}
"""The output's formats, by its extension."""
JOURNAL = ".partial"
"""The journal's suffix, after the output's name."""


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
    """A value as the CSV holds it: a number as Python writes it (exact), NaN empty."""
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
    """

    def __init__(self, path: str | os.PathLike[str], outputs: Sequence[str], grid: Grid):
        self.path = Path(path)
        self.format = output_format(path)
        if self.format == "parquet":  # refused before any case runs, not after them all
            import importlib.util

            if importlib.util.find_spec("pyarrow") is None:
                raise MbodyError(_NO_PYARROW)
        self.grid = grid
        self.outputs = list(outputs)
        self.header = ["case", *grid.paths, *outputs, "error"]
        self.rows: dict[int, list[str]] = {}
        self.journal = journal_of(path)
        self._resume()
        self._out: io.TextIOWrapper | None = None
        self._writer: Any = None

    @property
    def done(self) -> set[int]:
        """The cases that have a row (from an earlier run, or this one)."""
        return set(self.rows)

    # -- resuming ------------------------------------------------------------------------
    def _resume(self) -> None:
        if self.path.exists():
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
        header = next(lines, None)
        if header is None:
            return
        if header != self.header:
            raise MbodyError(f"{where} holds another sweep's results (its columns differ "
                             "from this sweep's); remove it or give another --out")
        width = len(self.header)
        for n, row in enumerate(lines, 2):
            if len(row) != width:
                if journal:  # a row cut short by an interruption: run that case again
                    continue
                raise MbodyError(f"{where}:{n}: {len(row)} cells, expected {width}")
            try:
                case = int(row[0])
            except ValueError:
                raise MbodyError(f"{where}:{n}: case {row[0]!r} is not a case number") from None
            if not 0 <= case < len(self.grid):
                raise MbodyError(f"{where}:{n}: case {case} is not a case of this sweep "
                                 f"(it has {len(self.grid)}); remove the file or give "
                                 "another --out")
            want = [cell(x) for x in self.grid.numbers(case)]
            got = row[1:1 + len(want)]
            if not all(map(_same, got, want)):
                bad = next(i for i, (a, b) in enumerate(zip(got, want, strict=True))
                           if not _same(a, b))
                raise MbodyError(f"{where}:{n}: case {case} has {self.header[1 + bad]} = "
                                 f"{row[1 + bad]} there but {want[bad]} in this sweep: the file "
                                 "holds another sweep's results; remove it or give another "
                                 "--out")
            self.rows[case] = row

    # -- adding and writing ----------------------------------------------------------------
    def add(self, rows: Rows) -> None:
        """A chunk's rows, kept and appended to the journal (flushed)."""
        if self._out is None:
            fresh = not self.journal.exists() or self.journal.stat().st_size == 0
            self._out = open(self.journal, "a", newline="", encoding="utf-8")  # noqa: SIM115
            self._writer = csv.writer(self._out)
            if fresh:
                self._writer.writerow(self.header)
        for case, out, err in zip(rows.indices, rows.outputs, rows.errors, strict=True):
            if case in self.rows:  # a chunk run twice (a worker lost after it finished)
                continue
            row = [str(case), *(cell(x) for x in self.grid.numbers(case)),
                   *(cell(x) for x in out.tolist()), err or ""]
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
        elif name == "error":
            columns[name] = pa.array(texts, pa.string())
        else:
            try:
                columns[name] = pa.array([float(x) if x else math.nan for x in texts],
                                         pa.float64())
            except ValueError:  # listed values of text (units, expressions)
                columns[name] = pa.array(texts, pa.string())
    pq.write_table(pa.table(columns), fh)
