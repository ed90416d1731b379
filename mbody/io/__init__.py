"""Files out and back in: `export` (the stacked equations to npz, .mat, JSON and CSV, and
`load_export` to read them) and `atomic` (every output written to a temporary file and
renamed into place)."""

from mbody._moved import submodule as _submodule


def __getattr__(name: str):
    return _submodule(__name__, name)
