"""Running a sweep's chunks: on Dask (``dask.distributed``), or in this process.

By default the command starts a local cluster of worker processes (one thread each, one
per core; every server bound to 127.0.0.1, no dashboard) and stops it at the end;
``scheduler="tcp://HOST:PORT"`` sends the same chunks to an existing cluster, whose
workers import the same mbody. ``workers=0`` runs them here, without Dask.

Chunks are sized from a measurement: the first cases are run here first (their rows
kept), and a chunk then holds about `CHUNK_SECONDS` of work, so that scheduling is a
small share, and at most a `CHUNKS_PER_WORKER`-th of a worker's share of the cases, so
that the workers stay busy to the end and a worker lost mid-run costs one chunk: Dask
runs a lost worker's chunk again on another. Each chunk's rows are written once, by the
case numbers they carry (`mbody.sweep.table.Results`), so every case is in the output
exactly once; a chunk that cannot be run at all (its workers died repeatedly) is written
as rows saying so.

This module imports dask only when a cluster is used.
"""

from __future__ import annotations

import logging
import math
import os
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from mbody.errors import MbodyError, option_name, option_setting
from mbody.model.reprs import count
from mbody.sweep.runs import Job, Rows, Sparsest, run_chunk
from mbody.sweep.table import Results

CHUNK_SECONDS = 2.0
"""Work in one chunk, in seconds of one worker (Dask's cost per task is a few
milliseconds: under 1 %)."""
CHUNKS_PER_WORKER = 4
"""At least this many chunks per worker (the load stays balanced to the end)."""
PILOT_SECONDS = 0.3
"""Work measured here before the chunks are sized (its rows are kept)."""
CONNECT_SECONDS = 30.0
"""How long a scheduler and its first worker are waited for."""
HERE = "this process"
"""`Report.where` of cases run in the caller's process."""


def _workers(n: int) -> str:
    return "worker" if n == 1 else "workers"


@dataclass
class Report:
    """How a sweep ran (what `run` returns).

    Parameters
    ----------
    cases : int
        The cases run: the pilot's, then the chunks'.
    chunks : int
        The chunks run.
    chunk : int
        Cases per chunk.
    workers : int
        The worker processes (1: this process).
    where : str
        Where the chunks ran: this process, a local cluster, or an existing one.
    work : float
        The wall-clock seconds the chunks took, added over the workers.
    cpu : float
        The processor seconds the cases took.
    wall : float
        The wall-clock seconds of the whole run.
    start : float
        The seconds of `wall` spent starting (or reaching) the cluster.
    lost : int
        Chunks lost with their workers, their cases written as failed.
    sparse : int
        Cases run whose ``peak:`` columns come from too few samples a revolution
        (`Rows.sparse`).
    sparsest : Sparsest or None
        The one of them with the fewest (`Rows.sparsest`).
    pilot : int
        The cases run first in this process to time them, before the chunks were sized
        (`_pilot`; none when the chunk size is given).
    pilot_wall : float
        The seconds of `wall` the pilot took.
    """

    cases: int = 0
    chunks: int = 0
    chunk: int = 0
    workers: int = 0
    where: str = HERE
    work: float = 0.0
    cpu: float = 0.0
    wall: float = 0.0
    start: float = 0.0
    lost: int = 0
    sparse: int = 0
    sparsest: Sparsest | None = None
    pilot: int = 0
    pilot_wall: float = 0.0

    @property
    def busy(self) -> float:
        """The share of the workers' wall-clock time, while they had chunks, spent on
        cases (the rest: scheduling, moving data, waiting for the last chunks); the
        pilot, run before, and the cluster's start are not theirs."""
        span = (self.wall - self.pilot_wall - self.start) * max(self.workers, 1)
        return self.work / span if span > 0 else 1.0

    def text(self) -> str:
        """The summary line ``mbody sweep`` prints: the cases, and how they ran, the
        pilot's and the chunks' adding up to them.

        Returns
        -------
        str
        """
        here = self.where == HERE
        runs = []
        if self.pilot:  # on a cluster, the pilot ran here, not on the workers
            runs.append(count(self.pilot, "pilot case") + ("" if here else " here"))
        if self.chunks:
            runs.append(f"{count(self.chunks, 'chunk')} of up to {count(self.chunk, 'case')}"
                        + ("" if here else f" on the {_workers(self.workers)}"))
        how = ", then ".join(runs) if runs else "no cases"
        if self.pilot and not self.chunks:
            how += ", no chunks"
        parts = [how]
        if self.chunks:
            who = HERE if here else f"the {_workers(self.workers)}"
            their = "its" if here or self.workers == 1 else "their"
            parts.append(f"{who} spent {100 * min(self.busy, 1.0):.0f}% of {their} time on "
                         f"cases, {self.cpu:.1f} s of processor time"
                         + (f", {self.start:.1f} s starting the cluster" if self.start
                            else ""))
        else:
            parts.append(f"{self.cpu:.1f} s of processor time")
        if self.lost:
            parts.append(f"{count(self.lost, 'chunk')} lost with "
                         f"{'its' if self.lost == 1 else 'their'} "
                         f"{_workers(self.lost)}, written as failed")
        return (f"{count(self.cases, 'case')} in {self.wall:.1f} s on {self.where} "
                f"({'; '.join(parts)})")


def run(job: Job, todo: Sequence[int], results: Results, *, scheduler: str | None = None,
        workers: int | None = None, chunk: int | None = None, progress: bool = True,
        on_chunk: Callable[[Rows], None] | None = None) -> Report:
    """Run cases `todo` of `job` (module doc), their rows into `results`.

    Parameters
    ----------
    job : Job
        The sweep.
    todo : sequence of int
        The cases to run (those not in the output yet).
    results : Results
        Where each chunk's rows go as it finishes.
    scheduler : str, optional
        An existing cluster's scheduler (``tcp://HOST:PORT``).
    workers : int, optional
        The local cluster's worker processes (default: one per core); 0: no cluster.
    chunk : int, optional
        Cases per chunk (default: measured).
    progress : bool
        A progress bar on standard error.
    on_chunk : callable, optional
        Called with each chunk's rows after they are written.

    Returns
    -------
    Report
    """
    from tqdm import tqdm  # type: ignore[import-untyped]  # tqdm ships no types

    todo = list(todo)
    if needs_cluster(todo, scheduler, workers, chunk):  # before any case, or any file
        require_dask()
    begin = time.perf_counter()
    report = Report()
    bar = tqdm(total=len(results.done) + len(todo), initial=len(results.done), unit="case",
               disable=not progress, file=sys.stderr, mininterval=0.5, smoothing=0.1,
               dynamic_ncols=True)

    def take(rows: Rows) -> None:
        results.add(rows)
        report.cases += len(rows.indices)
        report.cpu += rows.cpu
        report.sparse += rows.sparse
        if rows.sparsest is not None:
            report.sparsest = (rows.sparsest if report.sparsest is None
                               else min(report.sparsest, rows.sparsest))
        bar.update(len(rows.indices))
        if on_chunk is not None:
            on_chunk(rows)

    try:
        before = len(todo)
        per_case, todo = _pilot(job, todo, take, chunk)
        report.pilot = before - len(todo)
        report.pilot_wall = time.perf_counter() - begin
        if workers == 0 and scheduler is None:
            size = chunk or max(1, min(len(todo), round(CHUNK_SECONDS / per_case)))
            report.chunk = size
            for part in _chunks(todo, size):
                rows = run_chunk(job, part)
                report.work += rows.seconds
                report.chunks += 1
                take(rows)
            report.workers = 1
        elif todo:
            _on_dask(job, todo, per_case, chunk, scheduler, workers, take, report,
                     time.perf_counter(), len(results.outputs))
    finally:
        bar.close()
        results.close()
        report.wall = time.perf_counter() - begin
    return report


def needs_cluster(todo: Sequence[int], scheduler: str | None, workers: int | None,
                  chunk: int | None) -> bool:
    """Whether `run` will send chunks to a Dask cluster: not with ``workers=0`` (and no
    `scheduler`), nor when the one case left is the pilot's (`_pilot` runs at least
    one case here unless the `chunk` size is given)."""
    if workers == 0 and scheduler is None:
        return False
    return len(todo) > (0 if chunk is not None else 1)


def require_dask() -> None:
    """Refuse a sweep that needs Dask where ``dask.distributed`` cannot be imported (the
    ``sweep`` extra not installed): said before any case runs, so that nothing is
    computed or journalled for a command that fails."""
    try:
        import dask.distributed  # noqa: F401  # what `_on_dask` imports
    except ImportError:
        raise MbodyError(_no_dask()) from None


def _no_dask() -> str:  # a message, built when said (in the caller's names)
    return ("sweeps run on Dask (dask.distributed): pip install 'mbody[sweep]' "
            f"(or {option_setting('workers', 0)} to run them in this process)")


def _chunks(todo: Sequence[int], size: int) -> list[list[int]]:
    return [list(todo[i:i + size]) for i in range(0, len(todo), size)]


def _pilot(job: Job, todo: list[int], take: Callable[[Rows], None], chunk: int | None
           ) -> tuple[float, list[int]]:
    """Run the first cases here, doubling until `PILOT_SECONDS` of work (or a fiftieth of
    the cases): the seconds one case takes, and the cases left."""
    if chunk is not None or not todo:
        return 1.0, todo
    cap = max(1, len(todo) // 50)
    n, done, per_case = 1, 0, 0.0
    while done < len(todo):
        part = todo[done:done + n]
        rows = run_chunk(job, part)
        take(rows)
        done += len(part)
        if done > 1:  # the first case also built the model: not counted
            per_case = max(rows.seconds / len(part), 1e-6)
        if rows.seconds >= PILOT_SECONDS or done >= cap:
            break
        n *= 2
    return (per_case or 1e-3), todo[done:]


def _on_dask(job: Job, todo: list[int], per_case: float, chunk: int | None,
             scheduler: str | None, workers: int | None, take: Callable[[Rows], None],
             report: Report, begin: float, width: int) -> None:
    try:
        from dask.distributed import Client, LocalCluster, as_completed
    except ImportError:  # `require_dask` said so first; kept for a direct call
        raise MbodyError(_no_dask()) from None
    cluster = None
    try:
        if scheduler is None:
            n = workers or os.cpu_count() or 1
            # every server on the loopback: the scheduler's HTTP routes (no dashboard) at a
            # free port, the workers and their nannies; their shutdown chatter silenced
            try:
                cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                       host="127.0.0.1", dashboard_address="127.0.0.1:0",
                                       worker_dashboard_address=None,
                                       scheduler_kwargs={"dashboard": False},
                                       silence_logs=logging.CRITICAL)
                client = Client(cluster, set_as_default=False)
            except (RuntimeError, OSError, TimeoutError) as exc:  # a worker that never came up
                raise MbodyError(
                    f"could not start a local Dask cluster of {n} worker process(es) ({exc}); "
                    "the machine may be short of memory or busy: give fewer "
                    f"{option_name('workers')}, or {option_setting('workers', 0)} to run the "
                    "cases in this process (the same sweep resumes)") from None
            report.where = ("a local cluster of "
                            f"{count(n, 'worker process', 'worker processes')}")
        else:
            try:
                client = Client(scheduler, timeout=CONNECT_SECONDS, set_as_default=False)
                client.wait_for_workers(1, timeout=CONNECT_SECONDS)
            except (OSError, TimeoutError) as exc:
                raise MbodyError(f"{option_setting('scheduler', scheduler)}: no cluster "
                                 f"answered ({exc})") from None
            n = len(client.scheduler_info()["workers"])
            report.where = f"the cluster at {scheduler} ({count(n, 'worker')})"
        report.workers = n
        report.start = time.perf_counter() - begin
        size = chunk or max(1, min(round(CHUNK_SECONDS / per_case),
                                   math.ceil(len(todo) / (CHUNKS_PER_WORKER * n))))
        report.chunk = size
        parts = _chunks(todo, size)
        futures = {client.submit(run_chunk, job, part, pure=False,
                                 key=f"mbody-sweep-{job.key[:12]}-{i}"): part
                   for i, part in enumerate(parts)}
        for fut in as_completed(futures, loop=client.loop):
            part = futures[fut]
            try:
                rows = fut.result()
            except Exception as exc:  # noqa: BLE001 - the chunk's cases say so, not lost
                report.lost += 1
                why = (f"not run: the chunk's workers were lost ({type(exc).__name__}: "
                       f"{exc}); run the sweep again to run these cases")
                rows = Rows(part, np.full((len(part), width), np.nan), [why] * len(part))
            report.work += rows.seconds
            report.chunks += 1
            take(rows)
        client.close()
    finally:
        if cluster is not None:
            cluster.close()
