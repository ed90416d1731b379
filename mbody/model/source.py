"""Where a model came from, kept with it so that it can be read again with some values
changed (`Model.with_values`, ``--set PATH=VALUE``): the YAML text (or, for a large
file, its name and digest, read again on use), or the document of a dictionary or of an
MJCF or URDF import (the plain values its YAML form parses to, located at the XML's
lines), the values set since, and the step `mbody.load` took after building (moving the
bodies onto their joints and drivers).

A `Source` holds data only (and a reference to a module-level function), so it pickles:
a sweep sends it to the processes that evaluate the cases.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import hashlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from mbody.errors import MbodyError
from mbody.model.loader import Document, load_text, read_file
from mbody.util.budget import MAX_BYTES

if TYPE_CHECKING:
    from mbody.model.model import Model

KEEP_TEXT = 1 << 20
"""A YAML file up to this many characters keeps its text with the model (every hand-written
model; a 1 000-body one is about 800 kB); a larger one keeps its name and digest and is
read again when values are set (a 100 000-body model's text is 80 MB)."""


@dataclass(frozen=True, eq=False)
class Source:
    """What a model was read from, to read it again with values changed.

    Parameters
    ----------
    file : str
        The file's name as given (``<string>``, ``<dict>``).
    text : str or None
        The YAML text (files up to `KEEP_TEXT` characters, and texts given to `loads`).
    digest : str
        The SHA-256 of a larger file's text, which is read again on use ('' otherwise).
    size : int
        That file's size in bytes (the read limit when it is read again).
    document : Document or None
        The document of a dictionary, or of an MJCF or URDF import (its YAML form).
    values : tuple of (str, value)
        Values set since the file was read (`Model.with_values`), in order.
    finish : callable or None
        What `mbody.load` did to the built model (`mbody.solve.kinematics.assembled`),
        done again to a model built with values set.
    """

    file: str
    text: str | None = None
    digest: str = ""
    size: int = 0
    document: Document | None = None
    values: tuple[tuple[str, Any], ...] = ()
    finish: Callable[[Model], Model] | None = None

    @classmethod
    def of_text(cls, text: str, file: str, *, from_file: bool = True) -> Source:
        """The source of a YAML text (read from `file` when `from_file`): the text kept,
        or, for a large file, its digest."""
        if len(text) <= KEEP_TEXT or not from_file:
            return cls(file, text=text)
        return cls(file, digest=_digest(text), size=len(text.encode("utf-8")))

    def read(self) -> Document:
        """A fresh copy of the document (its values copied, its line marks shared), as the
        file gave it: the values set since are not applied (`values` lists them)."""
        if self.document is not None:
            doc = self.document
        elif self.text is not None:
            doc = _parsed(self.text, self.file)
        else:
            text = read_file(self.file, max(MAX_BYTES, self.size + 1))
            if _digest(text) != self.digest:
                raise MbodyError(f"{self.file} changed since the model was read from it; "
                                 "load it again to set values on what it says now")
            doc = load_text(text, self.file)
        return dataclasses.replace(doc, data=copy.deepcopy(doc.data))

    def with_values(self, values: tuple[tuple[str, Any], ...]) -> Source:
        """This source with `values` set after those set already."""
        return dataclasses.replace(self, values=self.values + values)


def _digest(text: str) -> str:
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


@functools.lru_cache(maxsize=8)
def _parsed(text: str, file: str) -> Document:
    """The located document of a kept text, parsed once (a sweep sets values on one model
    thousands of times; Python keeps a string's hash, so the look-up is cheap)."""
    return load_text(text, file)


def with_finish(model: Model, finish: Callable[[Model], Model]) -> Model:
    """`model` whose source records `finish` as the step taken after building it."""
    if model.source is None:
        return model
    return dataclasses.replace(model, source=dataclasses.replace(model.source,
                                                                 finish=finish))
