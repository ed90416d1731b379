"""meshcat's wire format: a lowered command (a dict) <-> msgpack bytes.

meshcat's viewer decodes each command with msgpack-lite, which turns msgpack extension
type 0x17 into a JavaScript Float32Array (meshcat's own geometry arrays travel this way,
see `meshcat.geometry.pack_numpy_array`). Every numpy array in a command (the keyframe
tracks' times and values) is packed as one such extension, its bytes written by numpy in
one go: umsgpack packs a list one Python float at a time, which for a thousand bodies'
tracks was most of the cost of a page. three.js keeps keyframes in Float32Arrays anyway
(`KeyframeTrack.TimeBufferType`, `ValueBufferType`), so float32 loses nothing the viewer
would have kept.

This module and `mbody.present.animate.live` are the only ones importing meshcat; it is
imported on demand (slow, and it warns about zmq on import).
"""

from __future__ import annotations

import warnings
from types import ModuleType
from typing import Any

import numpy as np
import umsgpack

FLOAT32_ARRAY = 0x17
"""msgpack-lite's extension type for Float32Array (little-endian float32 bytes)."""


def load_meshcat() -> ModuleType:
    """The `meshcat` package with its geometry, commands and path modules loaded.

    Returns
    -------
    ModuleType
        ``meshcat``; its zmq deprecation warning is silenced.
    """
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", "zmq.eventloop.ioloop is deprecated",
                                DeprecationWarning)
        import meshcat.commands
        import meshcat.geometry
        import meshcat.path

    return meshcat


def _float32_ext(array: np.ndarray) -> Any:
    if array.dtype.kind != "f":  # only keyframes travel as arrays; ints would be misread
        raise TypeError(f"cannot send a {array.dtype} array to meshcat as Float32Array")
    return umsgpack.Ext(FLOAT32_ARRAY, np.ascontiguousarray(array, dtype="<f4").tobytes())


def _as_lists(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, dict):
        return {k: _as_lists(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_as_lists(v) for v in value]
    return value


def pack(command: dict[str, Any], *, typed_arrays: bool = True) -> bytes:
    """msgpack bytes of one lowered meshcat command, as its viewer reads them.

    Parameters
    ----------
    command : dict
        A command as in `Scene.commands`; its numpy float arrays become Float32Arrays.
    typed_arrays : bool
        False packs every array as a list of float64 numbers, one at a time (meshcat's
        own way for animations; kept to compare against, see tools/bench_animate.py).

    Returns
    -------
    bytes
        What `viewer.handle_command_bytearray` (or meshcat's server) takes.
    """
    if not typed_arrays:
        return umsgpack.packb(_as_lists(command))
    return umsgpack.packb(command, ext_handlers={np.ndarray: _float32_ext})


def unpack(data: bytes) -> dict[str, Any]:
    """A packed command back as a dict, its Float32Arrays as float32 numpy arrays.

    Parameters
    ----------
    data : bytes
        Output of `pack`.

    Returns
    -------
    dict
        The command; other extension types (meshcat's geometry) stay `umsgpack.Ext`.
    """
    def float32(ext: Any) -> np.ndarray:
        return np.frombuffer(ext.data, dtype="<f4")

    out: dict[str, Any] = umsgpack.unpackb(data, ext_handlers={FLOAT32_ARRAY: float32})
    return out
