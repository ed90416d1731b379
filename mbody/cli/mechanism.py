"""jacobian: the joints' constraint Jacobian Gᵀ with labelled rows and columns."""

from __future__ import annotations

import argparse
import sys

from mbody.cli.common import EXIT_OK, MODEL_HELP, load_model
from mbody.util.formatting import num


def register(sub: argparse._SubParsersAction) -> None:
    s = sub.add_parser("jacobian", help="the constraint Jacobian G^T with labelled rows",
                       description="Print the velocity-level constraint Jacobian G^T of the "
                       "joints at the model's state: one row per reaction component (the "
                       "constraint it enforces), one column per coordinate, with gamma "
                       "(G^T v_dot = gamma) and the position errors phi.")
    s.add_argument("model", metavar="MODEL", help=MODEL_HELP)
    s.add_argument("--json", action="store_true", help="machine-readable output")
    s.set_defaults(run=jacobian)


def _n(x: float) -> str:
    return num(x)


def jacobian(a: argparse.Namespace) -> int:
    import numpy as np

    from mbody.equations.assemble import assemble
    from mbody.util import jsontext

    model = load_model(a.model)
    J = assemble(model).jacobian()
    A = J.matrix.tocsr()
    if a.json:
        rows = []
        for k, label in enumerate(J.rows):
            lo, hi = A.indptr[k], A.indptr[k + 1]
            rows.append({"constraint": label, "gamma": float(J.gamma[k]),
                         "phi": float(J.phi[k]),
                         "entries": {J.columns[c]: float(v)
                                     for c, v in zip(A.indices[lo:hi], A.data[lo:hi],
                                                     strict=True)}})
        jsontext.dump({"model": model.name, "shape": list(A.shape), "columns": J.columns,
                       "rows": rows}, sys.stdout)
        return EXIT_OK
    print(f"constraint Jacobian G^T of {model.name!r}: {A.shape[0]} constraints x "
          f"{A.shape[1]} coordinates (G^T v = relative velocity each joint forbids; "
          "G^T v_dot = gamma)")
    if not J.rows:
        print("no joints: nothing is constrained")
        return EXIT_OK
    width = max(len(r) for r in J.rows)
    for k, label in enumerate(J.rows):
        lo, hi = A.indptr[k], A.indptr[k + 1]
        order = np.argsort(A.indices[lo:hi])
        terms = " ".join(f"{'+' if v >= 0 else '-'} {_n(abs(v))} {J.columns[c]}"
                         for c, v in zip(A.indices[lo:hi][order], A.data[lo:hi][order],
                                         strict=True) if abs(v) > 1e-12)
        print(f"  {label:<{width}}  {terms or '0'}   gamma {_n(J.gamma[k])}  "
              f"phi {_n(J.phi[k])}")
    return EXIT_OK
