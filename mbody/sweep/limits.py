"""The ranges of a sweep's numeric arguments, in one place: `mbody.run_sweep` checks its
keywords against them (`Limit.check`), and ``mbody sweep`` builds its options' argparse
types from them (`mbody.cli.sweep`), so that the command and the function take the same
numbers and say the same range when they refuse one.

This module is imported when the command line starts (every command registers its
options then): it needs nothing but the errors and the number format.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Any

from mbody.errors import MbodyError, option_name
from mbody.util.formatting import number


@dataclass(frozen=True)
class Limit:
    """The range of one numeric argument.

    Parameters
    ----------
    option : str
        The command's option (``--steps``), whose argparse type is built from this.
    keyword : str
        `run_sweep`'s keyword (``steps``); a message names the argument as the caller
        does (`mbody.errors.option_name`: ``--steps`` on the command line).
    what : str
        What the number is (``"a number of instants"``).
    lo, hi : float
        Its bounds, both included unless `lo_open`.
    integer : bool
        A whole number.
    lo_open : bool
        `lo` itself excluded (a time above 0).
    """

    option: str
    keyword: str
    what: str
    lo: float
    hi: float
    integer: bool = False
    lo_open: bool = False

    @property
    def span(self) -> str:
        """The range in words: ``from 2 to 1 000 000``, ``above 0 up to 1e9``."""
        lo, hi = (number(int(x)) if self.integer else number(x) for x in (self.lo, self.hi))
        return f"above {lo} up to {hi}" if self.lo_open else f"from {lo} to {hi}"

    def takes(self, value: Any) -> bool:
        """Whether `value` is in the range (and a number of the right kind: not a bool)."""
        x: float  # numpy's numbers too (they register as numbers.Integral, .Real)
        if isinstance(value, bool):
            return False
        if isinstance(value, numbers.Integral):
            x = int(value)
        elif isinstance(value, numbers.Real) and not self.integer:
            x = float(value)
        else:
            return False
        return ((isinstance(x, int) or math.isfinite(x)) and x <= self.hi
                and (x > self.lo if self.lo_open else x >= self.lo))

    def check(self, value: Any) -> None:
        """Refuse `value` outside the range (or not a number), naming the option."""
        if not self.takes(value):
            raise MbodyError(f"{option_name(self.keyword)}: expected {self.what} {self.span}"
                             f"{' (a whole number)' if self.integer else ''}, got {value!r}")


LIMITS = {
    "samples": Limit("--samples", "samples", "a number of cases", 1, 1e8, integer=True),
    "seed": Limit("--seed", "seed", "a seed", 0, 2**63 - 1, integer=True),
    "t_end": Limit("--t-end", "t_end", "a time in seconds", 0.0, 1e9, lo_open=True),
    "revolutions": Limit("--t-end", "revolutions", "a number of turns", 0.0, 1e6,
                         lo_open=True),
    "steps": Limit("--steps", "steps", "a number of instants", 2, 1e6, integer=True),
    "fps": Limit("--fps", "fps", "samples per second", 0.0, 1e6, lo_open=True),
    "workers": Limit("--workers", "workers", "a number of worker processes", 0, 4096,
                     integer=True),
    "chunk": Limit("--chunk", "chunk", "a number of cases", 1, 1e8, integer=True),
}
"""`run_sweep`'s numeric keywords, by name, and the command's options built from them."""
