"""The equations: each body's Newton-Euler pair and the stacked ``M v̇ + b = Q + G λ``.

`spatial` (rotations and frame helpers), `loads` (applied loads -> net force and moment),
`joints` (reaction components -> the columns of G), `constraints` (Gᵀ, φ and γ),
`pack` and `workspace` (a model packed for the compiled core, `mbody.kernel`, which
computes all of these), `solution` (what a solve returns), `fbd` (one body's free body
and equations as data) and `assemble` (the `Assembly`).
"""

from mbody._moved import submodule as _submodule


def __getattr__(name: str):
    return _submodule(__name__, name)
