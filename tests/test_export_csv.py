"""The CSV export's reader finds columns by their header names: reordered columns, or an
extra one, read the same, bit for bit; a missing column is one message naming the file and
the column."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.io.export import csvfolder, exported, write_csv

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"


def _rows(path: Path) -> list[list[str]]:
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.reader(fh))


def _save(path: Path, rows: list[list[str]]) -> None:
    with open(path, "w", newline="", encoding="utf-8") as fh:
        csv.writer(fh, lineterminator="\n").writerows(rows)


def _shuffle_columns(path: Path, rng: np.random.Generator, extra: bool) -> None:
    """A random order of the columns (never the same order), and optionally a notes
    column, holding a comma and a number, in the middle."""
    rows = _rows(path)
    n = len(rows[0])
    order = rng.permutation(n)
    while n > 1 and np.array_equal(order, np.arange(n)):
        order = rng.permutation(n)
    rows = [[r[k] for k in order] for r in rows]
    if extra:
        at = len(rows[0]) // 2
        rows = [r[:at] + (["notes"] if i == 0 else [f"note {i}, 3.5"]) + r[at:]
                for i, r in enumerate(rows)]
    _save(path, rows)


def _shuffle_rows(path: Path, rng: np.random.Generator) -> None:
    rows = _rows(path)
    body = rows[1:]
    _save(path, [rows[0], *(body[k] for k in rng.permutation(len(body)))])


@pytest.fixture(params=["heavy_top", "slider_crank", "double_pendulum"])
def asm(request):
    return mbody.assemble(mbody.load(MODELS / f"{request.param}.yaml"))


@pytest.mark.parametrize("extra", [False, True], ids=["reordered", "reordered+extra"])
def test_reordered_columns_read_the_same(tmp_path, asm, extra):
    want = exported(asm, {asm.reactions[0]: 2.5})
    folder = write_csv(want, tmp_path / "eqs")
    rng = np.random.default_rng(7)
    for name in csvfolder.FILES:
        _shuffle_columns(folder / name, rng, extra and name not in ("M.csv", "G.csv"))
    # The matrices' rows are matched by label too (vectors.csv's row order is the
    # coordinates' order, columns.csv's the reactions': those are data, not layout).
    for name in ("M.csv", "G.csv"):
        _shuffle_rows(folder / name, rng)
    assert _rows(folder / "columns.csv")[0] != list(csvfolder.COLUMNS)  # really moved
    back = mbody.load_export(folder)
    assert want.differences(back) == []
    assert back.known == {asm.reactions[0]: 2.5}


def test_reordered_triplet_tables_read_the_same(tmp_path, asm, monkeypatch):
    monkeypatch.setattr(csvfolder, "CSV_DENSE_LIMIT", 0)
    want = exported(asm)
    folder = write_csv(want, tmp_path / "eqs")
    assert _rows(folder / "G.csv")[0] == ["row", "column", "value"]
    rng = np.random.default_rng(3)
    for name in ("M.csv", "G.csv"):
        _shuffle_columns(folder / name, rng, extra=True)
        _shuffle_rows(folder / name, rng)
    assert want.differences(mbody.load_export(folder)) == []


@pytest.mark.parametrize("name, column", [
    ("columns.csv", "gamma"), ("columns.csv", "sign"), ("columns.csv", "label"),
    ("bodies.csv", "qw"), ("bodies.csv", "J23"), ("vectors.csv", "Q"),
    ("info.csv", "value"), ("M.csv", "coordinate"),
])
def test_a_missing_column_is_an_error_naming_file_and_column(tmp_path, name, column):
    folder = write_csv(mbody.assemble(mbody.load(MODELS / "pendulum.yaml")), tmp_path / "e")
    rows = _rows(folder / name)
    k = rows[0].index(column)
    _save(folder / name, [r[:k] + r[k + 1:] for r in rows])
    with pytest.raises(mbody.MbodyError) as err:
        mbody.load_export(folder)
    assert str(folder / name) in str(err.value)
    assert f"no column {column!r}" in str(err.value)


def test_a_missing_matrix_label_column_is_an_error(tmp_path):
    folder = write_csv(mbody.assemble(mbody.load(MODELS / "pendulum.yaml")), tmp_path / "e")
    rows = _rows(folder / "G.csv")
    _save(folder / "G.csv", [r[:-1] for r in rows])  # drops O.Fy
    with pytest.raises(mbody.MbodyError, match=r"G\.csv: .*no column 'O\.Fy'"):
        mbody.load_export(folder)


def test_a_matrix_column_of_no_label_is_an_error(tmp_path):
    """In M.csv and G.csv every header names a column of the matrix: an unknown one means
    the tables disagree, and is not silently dropped."""
    folder = write_csv(mbody.assemble(mbody.load(MODELS / "pendulum.yaml")), tmp_path / "e")
    rows = _rows(folder / "G.csv")
    _save(folder / "G.csv", [r + (["P.Fx"] if i == 0 else ["1.0"]) for i, r in enumerate(rows)])
    with pytest.raises(mbody.MbodyError, match=r"G\.csv: its labels do not match.*'P\.Fx'"):
        mbody.load_export(folder)


def test_a_cell_that_is_not_a_number_names_file_line_and_column(tmp_path):
    folder = write_csv(mbody.assemble(mbody.load(MODELS / "pendulum.yaml")), tmp_path / "e")
    rows = _rows(folder / "bodies.csv")
    rows[1][rows[0].index("mass")] = "two"
    _save(folder / "bodies.csv", rows)
    with pytest.raises(mbody.MbodyError, match=r"bodies\.csv, line 2, column 'mass': 'two' "
                                                "is not a number"):
        mbody.load_export(folder)


def test_a_short_row_or_missing_file_is_one_message(tmp_path):
    folder = write_csv(mbody.assemble(mbody.load(MODELS / "pendulum.yaml")), tmp_path / "e")
    rows = _rows(folder / "vectors.csv")
    rows[2] = rows[2][:2]
    _save(folder / "vectors.csv", rows)
    with pytest.raises(mbody.MbodyError, match=r"vectors\.csv, line 3: 2 cells, but the "
                                                "header has 3"):
        mbody.load_export(folder)
    (folder / "vectors.csv").unlink()
    with pytest.raises(mbody.MbodyError, match=r"vectors\.csv: no such file"):
        mbody.load_export(folder)
