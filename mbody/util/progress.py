"""What a long computation is doing, on standard error: one tqdm bar per step (``modes
chain-2000: stiffness K = -df/dq: 40%|████ | 800/2000``), shown only once the
computation has taken `DELAY` seconds, so that a quick one prints nothing. The same bars
as ``mbody simulate --progress`` draws over simulated time and ``mbody sweep`` over cases;
the compiled core's long loops report through `Progress.core` (kernel.h: ``mb_progress``).

    with Progress(enabled, "modes chain-2000") as bar:
        bar.step("choosing the coordinates")          # a step without a count
        ...
        bar.step("writing the equations", total=k)    # then bar.update(done)
        core.linearize(..., bar.core)                 # the core's stages
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from types import TracebackType
from typing import Any

DELAY = 1.0
"""Seconds a computation runs before its bars appear (a step that starts later shows at
once)."""


class Progress:
    """Bars over the steps of one computation (module doc); a no-op when not `enabled`.

    Parameters
    ----------
    enabled : bool
        Draw the bars (the CLI: standard error is a terminal, or ``--progress``).
    label : str
        What is computed, before each step's words (``modes chain-2000``).
    stages : mapping of int to str, optional
        The words of the compiled core's stages, for `core` (``{STAGE_SCHUR:
        "eigenvalues"}``); a stage without words keeps the step before it.
    """

    def __init__(self, enabled: bool, label: str, stages: Mapping[int, str] | None = None):
        self.enabled = enabled
        self.label = label
        self.stages = dict(stages or {})
        self.start = time.perf_counter()
        self.what: str | None = None
        self.context = ""
        """Words before the core's stages' (``Newton step 3: ``)."""
        self._bar: Any = None

    def step(self, what: str, total: int | None = None) -> None:
        """Start the step `what` (`total` units of work, or None: not counted)."""
        if not self.enabled or what == self.what:
            return
        from tqdm import tqdm  # type: ignore[import-untyped]  # tqdm ships no types

        self._close_bar()
        self.what = what
        elapsed = time.perf_counter() - self.start
        self._bar = tqdm(total=total, desc=f"{self.label}: {what}", file=sys.stderr,
                         leave=True, dynamic_ncols=True, mininterval=0.25,
                         delay=max(0.0, DELAY - elapsed),
                         bar_format=None if total is not None else "{desc} [{elapsed}]")

    def update(self, done: int) -> None:
        """`done` units of the current step are done."""
        if self._bar is not None and done > self._bar.n:
            self._bar.update(done - self._bar.n)

    def core(self, stage: int, done: int, total: int) -> None:
        """The compiled core's report (kernel.h: ``mb_progress``): stage `stage` is at
        `done` of `total`."""
        what = self.stages.get(stage)
        if what is not None:
            self.step(self.context + what, total)
        self.update(done)

    @property
    def callback(self) -> Callable[[int, int, int], None] | None:
        """`core` when enabled, else None (the core then only watches for Ctrl-C)."""
        return self.core if self.enabled else None

    def _close_bar(self, finished: bool = True) -> None:
        if self._bar is not None:
            if finished and self._bar.total is not None:
                self.update(self._bar.total)
            self._bar.close()
            self._bar = None

    def close(self, finished: bool = True) -> None:
        """End the last step's bar (`finished`: drawn full)."""
        self._close_bar(finished)
        self.what = None

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, kind: type[BaseException] | None, value: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close(finished=kind is None)


@contextmanager
def progress_of(progress: bool | Progress, label: str,
                stages: Mapping[int, str] | None = None) -> Iterator[Progress]:
    """The bars of a public function's ``progress`` argument: a new `Progress` (True: drawn;
    False: not), closed at the end; or the caller's own `Progress` (a command that has
    more steps of its own), given these `stages` too, and left open."""
    if isinstance(progress, Progress):
        progress.stages.update(stages or {})
        yield progress
        return
    with Progress(bool(progress), label, stages) as bar:
        yield bar
