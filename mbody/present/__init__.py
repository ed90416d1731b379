"""What people read and look at: `text` (what the CLI prints), `latex`, `draw` (free-body
diagrams and the graph, with matplotlib), `report` (one HTML page per model), `plot`
(a trajectory's plots) and `animate` (meshcat: an HTML page or the live viewer)."""

from mbody._moved import submodule as _submodule


def __getattr__(name: str):
    return _submodule(__name__, name)
