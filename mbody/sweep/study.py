"""A whole sweep from Python: `run_sweep`, what ``mbody sweep`` runs (the command calls
it), and the table it returns (`SweepResult`).

The steps are the command's: the arguments checked (`check_request`, then the numbers),
the output checked not to be the model file (`check_outputs`), the model read (or taken
as given), its fixed values set, every varied path checked against the file before any
case runs, the settings checked against the model, the rows of an earlier run of the same
sweep with the same settings kept (`mbody.sweep.table.Results`), the other cases run
(`mbody.sweep.cluster.run`), the output written, and what the rows need said (a modes
run's states that are not equilibria, peaks sampled too sparsely).
"""

from __future__ import annotations

import os
import uuid
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mbody.errors import MbodyError, not_found, option_name, option_names
from mbody.loading import load
from mbody.model.model import Model
from mbody.model.values import edits, entry_names
from mbody.sweep import cluster
from mbody.sweep.grid import Grid, grid_of
from mbody.sweep.limits import LIMITS
from mbody.sweep.modes import not_steady_warning
from mbody.sweep.record import record
from mbody.sweep.runs import (
    Job,
    Settings,
    check_run,
    check_settings,
    columns,
    sampling_warning,
)
from mbody.sweep.table import ERROR, Results, journal_of, output_format
from mbody.util.atomic import refuse_overwriting_inputs


class SweepInterrupted(KeyboardInterrupt):
    """A sweep stopped by an interruption (Ctrl-C): the rows of the cases run so far are
    kept in the journal beside the output, and the same sweep again resumes from them.

    Parameters
    ----------
    kept : int
        The cases that have a row.
    cases : int
        The sweep's cases.
    journal : Path
        Where the rows are kept (``<out>.partial``).
    """

    def __init__(self, kept: int, cases: int, journal: Path):
        super().__init__(f"{kept} of {cases} cases kept in {journal}; the same sweep "
                         "resumes")
        self.kept, self.cases, self.journal = kept, cases, journal


_YES_NO = {"true": 1.0, "false": 0.0}
"""A yes-or-no cell's number (`SweepResult.column`)."""


@dataclass(frozen=True)
class SweepResult:
    """A sweep's rows, as its output file holds them (what `run_sweep` returns).

    Parameters
    ----------
    path : Path
        The output written (``.csv`` or ``.parquet``).
    header : list of str
        The columns: ``case``, the varied paths as given, the outputs
        ``<quantity>:<label>``, ``error``, then ``settings``.
    rows : list of list of str
        One row per case, by case number, each cell as the CSV holds it: a number as
        Python writes it (read back, the same double), an empty cell where a case has no
        number, ``error`` empty or why the case failed, ``settings`` how the row was
        computed (`settings`).
    ran : int
        The cases run by this call; the others were kept from an earlier run of the same
        sweep, with the same settings, into the same output.
    report : mbody.sweep.cluster.Report
        How the cases ran: where, in how many chunks, how long, and the cases whose
        ``peak:`` columns come from too few samples a revolution.
    warnings : list of str
        What the rows need said (the command prints each as ``mbody: warning: ...``):
        a model file's own warnings when `run_sweep` read it, then a ``modes`` run's
        cases linearised about a state that is not an equilibrium
        (`mbody.sweep.modes.not_steady_warning`), and ``peak:`` columns sampled too
        sparsely (`mbody.sweep.runs.sampling_warning`).
    settings : str
        What every row's ``settings`` cell records: the run, those of its settings that
        change its numbers, and the model's digest (`mbody.sweep.record`).
    replaced : int
        The earlier rows that were not this sweep's (other settings, other values),
        replaced by this call's as ``force=True`` asks.
    """

    path: Path
    header: list[str]
    rows: list[list[str]]
    ran: int
    report: cluster.Report
    warnings: list[str] = field(default_factory=list)
    settings: str = ""
    replaced: int = 0

    def __len__(self) -> int:
        return len(self.rows)

    @property
    def kept(self) -> int:
        """The cases whose rows were kept from an earlier run (not run by this call)."""
        return len(self.rows) - self.ran

    @property
    def errors(self) -> list[str | None]:
        """Each case's error, by case (None where it has its numbers)."""
        at = self.header.index(ERROR)
        return [r[at] or None for r in self.rows]

    @property
    def failed(self) -> int:
        """How many cases have no numbers (their ``error`` says why)."""
        return sum(1 for e in self.errors if e)

    def column(self, name: str) -> np.ndarray:
        """One column's numbers, by case (NaN where a case has none; a yes-or-no column,
        ``steady`` or ``stable``, as 1.0 for true and 0.0 for false).

        Parameters
        ----------
        name : str
            A column of `header` (``frequency:1``, ``peak:motor.M``, a varied path); a
            varied path whose values were given in a unit is found without it too
            (``drivers.motor.speed`` for ``drivers.motor.speed [rpm]``).

        Returns
        -------
        (cases,) float array

        Raises
        ------
        KeyError
            No such column.
        MbodyError
            The column holds text (``error``, ``settings``, values listed that are not
            numbers in one unit: expressions, units that differ): read it from `rows`.
        """
        at = self._index(name)
        out = np.full(len(self.rows), np.nan)
        for k, row in enumerate(self.rows):
            cell = row[at]
            if not cell:
                continue
            try:
                out[k] = _YES_NO[cell] if cell in _YES_NO else float(cell)
            except ValueError:
                raise MbodyError(f"column {name!r} holds text ({cell!r} in case {row[0]}), "
                                 "not numbers: read it from rows") from None
        return out

    def _index(self, name: str) -> int:
        """Where column `name` is in `header` (a varied path also without its unit)."""
        if name in self.header:
            return self.header.index(name)
        with_unit = [k for k, h in enumerate(self.header)
                     if h.startswith(f"{name} [") and h.endswith("]")]
        if len(with_unit) == 1:
            return with_unit[0]
        raise not_found("column", name, self.header, "columns")

    def __repr__(self) -> str:
        failed = self.failed
        return (f"<SweepResult {self.path}: {len(self)} cases, {self.ran} run now"
                + (f", {self.kept} kept from an earlier run" if self.kept else "")
                + (f", {self.replaced} earlier rows replaced" if self.replaced else "")
                + (f", {failed} failed" if failed else "")
                + (f", {len(self.warnings)} warning(s)" if self.warnings else "")
                + "; .header, .rows, .column(name), .errors, .report, .warnings>")


def check_request(values: Mapping[str, Any] | Sequence[str] | str, out: str | os.PathLike[str],
                  samples: int | None = None, seed: int = 0) -> Grid:
    """The checks of a sweep that need no model, made first (a bad output name or grid is
    refused before a model file is read): the output's format, the grid, the seed.

    Parameters
    ----------
    values : mapping, sequence of str, or str
        The varied values (`run_sweep`).
    out : str or path-like
        The output.
    samples : int, optional
        Random cases instead of the grid.
    seed : int
        Their seed.

    Returns
    -------
    Grid
        The sweep's cases.

    Raises
    ------
    MbodyError
        Any of them wrong.
    """
    if not isinstance(out, str | os.PathLike) or not str(out):
        raise MbodyError(f"the output: expected a file name ending in .csv or .parquet, got "
                         f"{out!r}")
    output_format(out)
    for name, value in (("samples", samples), ("seed", seed)):
        if value is not None:
            LIMITS[name].check(value)
    grid = grid_of(values, samples, seed)
    if samples is None and seed:
        raise MbodyError(f"{option_name('seed')} goes with {option_name('samples')} (a grid "
                         "has no randomness)")
    return grid


JOURNAL_OPTION = "--out's journal"
"""How a message names the journal beside the output (``<out>.partial``)."""


def check_outputs(out: str | os.PathLike[str], model_file: str | os.PathLike[str] | None
                  ) -> None:
    """Refuse an output of the sweep that is its model file, however named (a link,
    another spelling of the path, a hard link): the results (`out`) and their journal
    beside it (``<out>.partial``), which a rerun reads back to resume, and which needs the
    model as it was (`mbody.util.atomic.refuse_overwriting_inputs`, the check of every
    command; ``force`` cannot pass it). The journal is not the output either.

    Parameters
    ----------
    out : str or path-like
        The output.
    model_file : str, path-like or None
        The model's file (None: a model without one, from a dictionary or text).

    Raises
    ------
    MbodyError
        Naming the output, the input and the file they both are.
    """
    resumed = ("--out", JOURNAL_OPTION)
    inputs = [("the model", os.fspath(model_file))] if model_file is not None else []
    refuse_overwriting_inputs([("--out", os.fspath(out))], inputs, resumed=resumed)
    refuse_overwriting_inputs([(JOURNAL_OPTION, str(journal_of(out)))],
                              [*inputs, ("the output", os.fspath(out))], resumed=resumed)


def run_sweep(model: Model | str | os.PathLike[str],
              values: Mapping[str, Any] | Sequence[str] | str,
              out: str | os.PathLike[str], *, run: str = "solve",
              t_end: float | None = None, revolutions: float | None = None,
              steps: int | None = None, fps: float | None = None, equilibrium: bool = False,
              samples: int | None = None, seed: int = 0, workers: int | None = None,
              scheduler: str | None = None, chunk: int | None = None,
              progress: bool = False, force: bool = False) -> SweepResult:
    """Run a model over a grid (or random samples) of values, as ``mbody sweep`` does,
    and write one row per case to `out` (docs/sweeps.md).

    Cases run on a local Dask cluster started for the call (`workers` processes), on an
    existing one (`scheduler`), or with ``workers=0`` in this process, without Dask. An
    output of the same sweep that is already there (or its ``.partial`` journal, left by
    an interrupted run) is resumed: only the cases not in it run. Its rows are reused
    only when they are this sweep's: the same values, and computed with the same
    settings (each row records them in its ``settings`` cell); an output holding other
    rows is refused, naming what differs, unless `force`.

    Parameters
    ----------
    model : Model or path
        The model, or its file (read with `mbody.load`).
    values : mapping, sequence of str, or str
        What varies, and what is set in every case. ``--set`` texts
        (``["bodies.rod.mass=0.3:1.2:10", "gravity=[0, -1.62]"]``: a range
        ``START:STOP:COUNT``, values listed ``a,b,c``, or one value), or a mapping path
        -> values: a list, tuple or array is the values one per case, each as the file
        would hold it (``{"gravity.1": [-9.81, -1.62]}``, ``{"drivers.motor.speed":
        ["300 rpm", "600 rpm"]}``); text is what follows ``PATH=`` in ``--set``
        (``"300 rpm:1200 rpm:4"``; ``"[0, -1.62]"``: one vector for every case); a
        number is one value for every case. The grid is every combination, the last path
        varying fastest.
    out : str or path-like
        The results: ``.csv``, or ``.parquet`` (pyarrow, in the ``sweep`` extra).
    run : {"solve", "kinematics", "simulate", "modes"}
        What each case computes (``--run``): a solve at its initial state; the kinematic
        analysis and a solve at each instant (`steps`); `mbody.simulate`; the natural
        frequencies.
    t_end : float, optional
        ``kinematics`` and ``simulate`` (which need it, or `revolutions`): the end (s).
    revolutions : float, optional
        Or the end in turns of the first driver that turns, at each case's own rate
        (``--t-end "1 rev"`` is ``revolutions=1``).
    steps : int, optional
        ``kinematics``: this many instants evenly spaced from 0 to the end, both
        included. By default each case is sampled as ``mbody kinematics`` samples it:
        360 times a revolution of the first driver at the case's own rate when it turns
        at a constant rate, else 100 times a second
        (`mbody.simulate.kinematic.default_fps`), and at the end itself.
    fps : float, optional
        Samples per second: ``simulate``'s (default 60, as `mbody.simulate`), or
        ``kinematics``' instead of `steps`, k / fps from 0 as ``mbody kinematics --fps``
        samples (and the end itself when they fall short of it).
    equilibrium : bool
        ``modes``: about the static equilibrium nearest each case's initial pose (as
        ``mbody modes --equilibrium``), not about its initial state.
    samples : int, optional
        This many random cases instead of the grid, each value uniform in
        ``START:STOP`` (or drawn from a list).
    seed : int
        The random samples' seed.
    workers : int, optional
        The local cluster's worker processes (default: one per core); 0: the cases run
        in this process, without Dask.
    scheduler : str, optional
        An existing Dask cluster's scheduler, ``tcp://HOST:PORT``.
    chunk : int, optional
        Cases per chunk sent to a worker (default: measured, about 2 s of work).
    progress : bool
        A progress bar on standard error.
    force : bool
        Run again, and replace, the earlier rows of `out` (and its journal) that are not
        this sweep's: computed with other settings (``t_end``, ``steps``, ``fps``, the
        run, the model's content), for other values, or by an mbody that did not record
        the settings (``--force``). Without it such an output is refused.

    Returns
    -------
    SweepResult
        The output's path, its header and rows (every case, by case number), how many
        cases this call ran, the run's `Report`, and its warnings.

    Raises
    ------
    MbodyError
        A bad argument, before any case runs, with the command's message (an entry of
        a `values` mapping named as its key, ``values['bodies.rod.mass']``, where the
        command says ``--set bodies.rod.mass``): the output's extension, a malformed
        range, a value listed that is not finite (NaN, inf), a path given twice, a path
        the model file does not have (located, with a did-you-mean), `equilibrium`,
        `progress` or `force` not True or False, a setting the run does not use
        (`steps` with ``run="simulate"``, `t_end` with ``"solve"``...: refused, not
        ignored), settings the run or the model cannot take (``kinematics`` without an
        end, of a model not fully driven, with both `steps` and `fps`), an output
        that is the model's file (however named) or a folder, an output holding another
        sweep's rows or rows computed with other settings (without `force`); or a
        cluster that cannot be started or reached.
    SweepInterrupted
        An interruption (a `KeyboardInterrupt`): the rows so far are kept, and the same
        call resumes.
    """
    grid = check_request(values, out, samples, seed)
    for name, value in (("t_end", t_end), ("revolutions", revolutions), ("steps", steps),
                        ("fps", fps), ("workers", workers), ("chunk", chunk)):
        if value is not None:
            LIMITS[name].check(value)
    if t_end is not None and revolutions is not None:
        raise MbodyError("give the end in seconds (t_end) or in turns (revolutions), not "
                         "both")
    for keyword, value in (("equilibrium", equilibrium), ("force", force),
                           ("progress", progress)):
        if not isinstance(value, bool | np.bool_):  # 'no' would be taken as True
            raise MbodyError(f"{option_name(keyword)}: expected True or False, got "
                             f"{value!r}")
    if scheduler is not None and not isinstance(scheduler, str):
        raise MbodyError(f"{option_name('scheduler')}: expected an address such as "
                         f"tcp://HOST:PORT, got {scheduler!r}")
    settings = Settings(run, t_end, revolutions, steps, fps, bool(equilibrium))
    check_run(settings)  # a setting the run does not use: before the model is read
    said: list[str] = []
    if not isinstance(model, Model):
        if not isinstance(model, str | os.PathLike):
            raise MbodyError(f"the model: expected a Model or a model file's path, got "
                             f"{type(model).__name__}")
        check_outputs(out, model)  # before the model is even read
        model = load(model)
        said += [str(w) for w in model.warnings]
    elif model.source is not None:
        check_outputs(out, model.source.file)  # '<string>', '<dict>': no such file
    if grid.fixed:
        model = model.with_values(grid.fixed)
    if model.source is None:
        raise MbodyError("this model has no document to set values in")
    # every path names something in the file, before any case runs
    edits(model.source.read(), [(p, None) for p in grid.paths], entry_names(model))
    check_settings(model, settings)
    recorded = record(settings, model)
    results = Results(out, columns(model, settings), grid, recorded, force=bool(force))
    todo = [k for k in range(len(grid)) if k not in results.rows]
    job = Job(model.source, grid, settings, uuid.uuid4().hex, option_names())
    try:
        report = cluster.run(job, todo, results, scheduler=scheduler, workers=workers,
                             chunk=chunk, progress=progress)
    except KeyboardInterrupt:
        raise SweepInterrupted(len(results.rows), len(grid), results.journal) from None
    path = results.finish()
    for warning in (not_steady_warning(results.header, results.rows.values(), equilibrium),
                    sampling_warning(settings, grid, report.sparse, report.cases,
                                     report.sparsest)):
        if warning:
            said.append(warning)
    rows = [results.rows[k] for k in sorted(results.rows)]
    return SweepResult(path, list(results.header), rows, len(todo), report, said, recorded,
                       results.replaced)
