"""Exports read back as hostile input (review R1, B3/B4 applied to `mbody.load_export`
and `read_generalized`): nesting, declared sizes and compressed bombs in npz, .mat,
JSON and CSV files are refused with an `MbodyError` naming the file and what is wrong,
before anything large is allocated or inflated."""

from __future__ import annotations

import contextlib
import json
import struct
import subprocess
import sys
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

import mbody
from mbody.errors import MbodyError, MbodyTypeError
from mbody.io.export import write_csv, write_export
from mbody.io.export.generalized import read_generalized

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
MIB = 1 << 20
sys.path.insert(0, str(ROOT / "tools"))
from crafted_files import (  # noqa: E402  (the builders the benchmark of refusals uses)
    mat_array,
    mat_bomb,
    mat_file,
    mat_tag,
    npz_bomb,
    npz_with,
)


@pytest.fixture(scope="module")
def exports(tmp_path_factory) -> Path:
    """The pendulum's export in every format, in one folder."""
    out = tmp_path_factory.mktemp("exports")
    asm = mbody.assemble(mbody.load(MODELS / "pendulum.yaml"))
    for suffix in (".npz", ".json", ".mat"):
        write_export(asm, out / f"p{suffix}")
    write_csv(asm, out / "p_csv")
    return out


def refused(path: Path, *words: str, **kw) -> str:
    """The message of `load_export(path)`'s MbodyError: it names `path` and `words`."""
    with pytest.raises(MbodyError) as exc:
        mbody.load_export(path, **kw)
    text = str(exc.value)
    assert text.startswith(f"{path}"), text
    for w in words:
        assert w in text, (w, text)
    return text


def peak_bytes(load, *args, **kw) -> int:
    """The most memory Python and numpy held while `load(*args, **kw)` ran."""
    tracemalloc.start()
    with contextlib.suppress(MbodyError):  # the refusal is checked by the caller
        load(*args, **kw)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak


# -- npz ---------------------------------------------------------------------------------


def test_npz_json_nested_too_deeply(exports, tmp_path):
    with np.load(exports / "p.npz") as z:
        data = dict(z)
    data["conventions_json"] = np.array("[" * 10000)
    np.savez(tmp_path / "deep.npz", **data)
    refused(tmp_path / "deep.npz", "nested 10000 deep", "at most 64")


def test_npz_header_claiming_more_than_the_member_holds(exports, tmp_path):
    with np.load(exports / "p.npz") as z:
        data = dict(z)
    path = npz_with(tmp_path / "liar.npz", data, "b",
                    {"descr": "<f8", "fortran_order": False, "shape": (10**15,)}, bytes(16))
    refused(path, "not a readable mbody export", "member b.npy",
            "1,000,000,000,000,000 values", "16 bytes")


def test_npz_bomb_is_refused_before_it_is_inflated(exports, tmp_path):
    """b.npy inflates to 64 MiB from about 64 kB: over a 16 MiB budget, it is refused from
    the zip directory, nothing inflated."""
    with np.load(exports / "p.npz") as z:
        data = dict(z)
    path = npz_bomb(tmp_path / "bomb.npz", data, 8 * MIB, member="b")
    assert path.stat().st_size < MIB
    refused(path, "holds 64 MiB of data once inflated", "at most 16 MiB",
            "max_bytes=N", max_bytes=16 * MIB)
    assert peak_bytes(mbody.load_export, path, max_bytes=16 * MIB) < 4 * MIB


# -- JSON --------------------------------------------------------------------------------


def test_json_nested_too_deeply(tmp_path):
    path = tmp_path / "deep.json"
    path.write_text('{"format": "mbody-export", "version": 2, "x": ' + "[" * 100000
                    + "]" * 100000 + "}")
    refused(path, "nested 100001 deep", "at most 64")


def test_json_whole_number_of_millions_of_digits(exports, tmp_path):
    """Python converts at most 4300 digits of a whole number by default (the time grows as
    their square); beyond that the message says so in its own words (review R5-9), not
    Python's advice to raise the interpreter's limit, which stays as it was."""
    from mbody.util import jsontext

    limit = sys.get_int_max_str_digits()
    assert limit == 4300  # Python's default (PYTHONINTMAXSTRDIGITS not set)
    path = tmp_path / "bigint.json"
    path.write_text('{"format": "mbody-export", "version": 2, "M": ' + "9" * 5_000_000 + "}")
    text = refused(path, "not a readable mbody export",
                   "a whole number of 5 000 000 digits; at most 4 300 are read")
    assert "sys." not in text and "set_int_max_str_digits" not in text
    assert sys.get_int_max_str_digits() == limit
    assert jsontext.loads("[-" + "9" * 4300 + "]") == [-int("9" * 4300)]  # at the bound


def test_json_version_of_thousands_of_digits_is_named_by_its_size(exports, tmp_path):
    """A version past a float's range: the message gives its power of ten, not its 4000
    digits (nor an OverflowError converting it)."""
    doc = json.loads((exports / "p.json").read_text())
    path = tmp_path / "future.json"
    path.write_text(json.dumps(doc).replace('"version": ' + str(doc["version"]),
                                            '"version": 1' + "0" * 3999, 1))
    text = refused(path, "export format version about 1e3999 is newer than this mbody")
    assert len(text) < 400


def test_json_matrix_shape_is_checked_before_the_matrix_is_made(exports, tmp_path):
    """A shape of 10^12 x 10^12 with no entries: its column pointers alone were 8 TB (a
    MemoryError)."""
    doc = json.loads((exports / "p.json").read_text())
    doc["M"]["shape"] = [10**12, 10**12]
    path = tmp_path / "big.json"
    path.write_text(json.dumps(doc))
    refused(path, "M is 1000000000000 x 1000000000000", "expected 3 x 3")
    doc = json.loads((exports / "p.json").read_text())
    doc["G"]["shape"] = [3, 10**12]
    path.write_text(json.dumps(doc))
    refused(path, "G is 3 x 1000000000000", "expected 3 x 2")


def test_json_larger_than_the_budget_is_refused_unread(exports):
    size = (exports / "p.json").stat().st_size
    refused(exports / "p.json", f"holds {size / 1024:.3g} KiB ({size:,} bytes) of data",
            "at most 1 KiB", max_bytes=1024)


# -- .mat --------------------------------------------------------------------------------


def test_the_mat_writer_of_these_tests_writes_what_scipy_reads(tmp_path):
    import scipy.io

    ones = mat_array(6, (2, 1), mat_tag(9, struct.pack("<2d", 1.0, 2.0)), b"x")
    got = scipy.io.loadmat(mat_file(tmp_path / "ok.mat", ones))["x"]
    np.testing.assert_array_equal(got, [[1.0], [2.0]])


def test_mat_cells_nested_too_deeply(tmp_path):
    """scipy's reader recurses once a level, in C: 20 000 cells in cells crashed the
    process (a segmentation fault), so the file is read in a child process here."""
    inner = mat_array(6, (0, 0), mat_tag(9, b""))
    flags_shape_name = (mat_tag(6, struct.pack("<II", 1, 0)) + mat_tag(5, struct.pack("<2i", 1, 1))
                        + mat_tag(1, b""))
    depth = 20_000
    heads = [struct.pack("<II", 14, len(inner) + k * (8 + len(flags_shape_name))
                         + len(flags_shape_name)) + flags_shape_name
             for k in range(depth - 1, -1, -1)]  # the outermost first, each around the next
    path = mat_file(tmp_path / "deep.mat", b"".join([*heads, inner]))
    child = subprocess.run(
        [sys.executable, "-c", "import sys, mbody\ntry:\n mbody.load_export(sys.argv[1])\n"
         "except mbody.MbodyError as e:\n print(e)", str(path)],
        capture_output=True, text=True, timeout=120)
    assert child.returncode == 0, child.stderr
    assert child.stdout.startswith(f"{path}: damaged or truncated .mat export")
    assert "nested over 64 deep" in child.stdout


def test_mat_cell_shape_beyond_its_bytes(tmp_path):
    """A cell array declaring 2^24 slots in no bytes: scipy allocated the 128 MiB of
    their pointers (and 2^28 slots, 2 GiB) before it found nothing to put in them."""
    path = mat_file(tmp_path / "cells.mat", mat_array(1, (2**24, 1), name=b"c"))
    refused(path, "a cell array of shape (16777216, 1) in 0 bytes")
    assert peak_bytes(mbody.load_export, path) < 4 * MIB


def refused_by_both(path: Path, *words: str) -> None:
    """`load_export` and `read_generalized` each refuse `path` with an MbodyError that
    names it and `words`."""
    refused(path, *words)
    with pytest.raises(MbodyError) as exc:
        read_generalized(path)
    assert str(exc.value).startswith(f"{path}: ") and all(w in str(exc.value) for w in words)


def test_mat_struct_without_the_width_of_its_field_names(tmp_path):
    """Review R3, B1: the width's element held 0 bytes, and reading its 4 was a
    struct.error from both readers."""
    path = mat_file(tmp_path / "s.mat", mat_array(2, (1, 1), mat_tag(5, b""), b"x"))
    refused_by_both(path, "damaged or truncated .mat export", "a struct without the width "
                    "of its field names")


def test_mat_compressed_variable_that_does_not_inflate(tmp_path):
    """Review R3, B1: a zlib header and then no deflate stream was a zlib.error."""
    garbage = struct.pack("<II", 15, 32) + b"\x78\x9c" + b"\xff" * 30
    path = mat_file(tmp_path / "z.mat", garbage, compress=False)
    refused_by_both(path, "damaged or truncated .mat export", "the compressed variable "
                    "at byte 128 does not inflate")


def sparse(shape: tuple[int, int], rows: list[int], columns: list[int], values: list[float],
           name: bytes, row_type: int = 5) -> bytes:
    """A sparse miMATRIX: row indices (of MAT type `row_type`), column pointers, values."""
    return mat_array(5, shape, mat_tag(row_type, struct.pack(f"<{len(rows)}i", *rows))
                     + mat_tag(5, struct.pack(f"<{len(columns)}i", *columns))
                     + mat_tag(9, struct.pack(f"<{len(values)}d", *values)), name)


def test_what_scipy_reads_unchecked_is_checked_first(exports, tmp_path):
    """Found while fuzzing the fixes of review R3, B1 (byte flips in real exports):
    scipy's compiled reader, and scipy.sparse's routines after it, trust a file's types
    and indices. A sparse matrix whose row indices were of MAT type 5637 crashed the
    process (a bus error); a row index outside the matrix crashed it in
    `eliminate_zeros` (a segmentation fault), from a .mat or an npz export. Each file is
    read in a child process: a crash there is a failure here, not the end of the run."""
    files = {
        "type.mat": (sparse((2, 2), [0, 1], [0, 1, 2], [1.0, 2.0], b"M", row_type=5637),
                     "a sparse array whose data at byte 64 is of MAT type 5637, not "
                     "numbers"),
        "name.mat": (mat_tag(14, mat_tag(6, struct.pack("<II", 6, 0)) + mat_tag(5, struct.pack(
            "<2i", 1, 1)) + mat_tag(7, b"x") + mat_tag(9, bytes(8))),  # a name of MAT type 7
            "an array whose name at byte 48 is of MAT type 7, expected text (miINT8)"),
        "pointers.mat": (sparse((2, 2), [0, 1], [0, 1, -5], [1.0, 2.0], b"M"),
                         "damaged or truncated .mat export (scipy cannot read it"),
    }
    for name, (variable, _) in files.items():
        mat_file(tmp_path / name, variable)
    with np.load(exports / "p.npz") as z:  # the stacked export, M's row indices moved out
        data = dict(z)
    np.savez(tmp_path / "rows.npz", **{**data, "M_indices": data["M_indices"] + 10**8})
    import scipy.io
    import scipy.sparse as sp

    raw = scipy.io.loadmat(exports / "p.mat")
    M = raw["M"].tocsc()
    raw["M"] = sp.csc_matrix((M.data, M.indices + 10**8, M.indptr), shape=M.shape)
    scipy.io.savemat(tmp_path / "rows.mat", {k: v for k, v in raw.items()
                                            if not k.startswith("__")})
    files["rows.npz"] = (b"", "the sparse matrix M is damaged")
    files["rows.mat"] = (b"", "the sparse matrix M is damaged")
    script = ("import sys, mbody\nfrom mbody.io.export.generalized import read_generalized"
              "\nfor path in sys.argv[1:]:\n for read in (mbody.load_export, read_generalized):"
              "\n  try:\n   read(path)\n   print('read', path)\n  except mbody.MbodyError as e:"
              "\n   print(str(e).replace(chr(10), ' '))")
    child = subprocess.run([sys.executable, "-c", script,
                            *(str(tmp_path / name) for name in files)],
                           capture_output=True, text=True, timeout=300)
    assert child.returncode == 0, child.stderr
    lines = child.stdout.splitlines()
    assert len(lines) == 2 * len(files), child.stdout
    for k, (name, (_, words)) in enumerate(files.items()):
        load, generalized = lines[2 * k:2 * k + 2]
        assert load.startswith(f"{tmp_path / name}: ") and words in load, load
        if name == "rows.npz":  # the stacked equations' export: its tag is read first
            words = "an export of the stacked equations (mbody export)"
        assert generalized.startswith(f"{tmp_path / name}: ") and words in generalized


def test_mat_bomb_is_refused_before_it_is_inflated(tmp_path):
    path = mat_bomb(tmp_path / "bomb.mat", 8 * MIB)
    assert path.stat().st_size < MIB
    refused(path, "holds 64 MiB of data once inflated", "at most 16 MiB",
            max_bytes=16 * MIB)
    assert peak_bytes(mbody.load_export, path, max_bytes=16 * MIB) < 4 * MIB


def test_mat_files_of_other_versions_are_refused(tmp_path):
    """A v7.3 (HDF5) file made scipy raise NotImplementedError (not an MbodyError)."""
    path = mat_file(tmp_path / "v73.mat", mat_array(6, (0, 0), mat_tag(9, b""), b"x"),
                    version=b"7.3")
    refused(path, "not a MATLAB 5 .mat file as mbody writes it")


def test_a_good_mat_export_reads_back_as_the_npz_one(exports):
    a, b = mbody.load_export(exports / "p.mat"), mbody.load_export(exports / "p.npz")
    assert (a.M != b.M).nnz == 0 and (a.G != b.G).nnz == 0
    assert a.coordinates == b.coordinates and a.conventions == b.conventions


# -- CSV ---------------------------------------------------------------------------------


def csv_copy(exports: Path, tmp_path: Path) -> Path:
    out = tmp_path / "csv"
    out.mkdir()
    for f in (exports / "p_csv").iterdir():
        (out / f.name).write_bytes(f.read_bytes())
    return out


def test_csv_info_value_nested_too_deeply(exports, tmp_path):
    folder = csv_copy(exports, tmp_path)
    info = folder / "info.csv"
    info.write_text(info.read_text() + 'deep,"' + "[" * 10000 + '"\n')
    text = refused(folder, "info.csv, line", "the value of 'deep'", "nested 10000 deep")
    assert str(info) in text


def test_csv_field_over_the_csv_limit_names_file_and_line(exports, tmp_path):
    """A cell longer than csv's field limit (128 kB) was a csv.Error (not an MbodyError)."""
    folder = csv_copy(exports, tmp_path)
    bodies = folder / "bodies.csv"
    lines = bodies.read_text().splitlines()
    bodies.write_text("\n".join([*lines, '"' + "x" * 200_000 + '"']) + "\n")
    text = refused(folder, "a cell longer than 131,072 characters")
    assert f"{bodies}, line {len(lines) + 1}: " in text


def test_csv_folder_larger_than_the_budget(exports, tmp_path):
    refused(exports / "p_csv", "at most 1 KiB", "max_bytes=N", max_bytes=1024)


# -- the generalized equations' exports ----------------------------------------------------


def test_read_generalized_is_bounded_the_same_way(tmp_path):
    deep = tmp_path / "g.json"
    deep.write_text("[" * 10000)
    with pytest.raises(MbodyError, match="nested 10000 deep"):  # a ValueError before R3
        read_generalized(deep)
    liar = npz_with(tmp_path / "g.npz", {"q": np.zeros(2)}, "q",
                    {"descr": "<f8", "fortran_order": False, "shape": (10**15,)}, bytes(16))
    with pytest.raises(MbodyError, match="member q.npy"):
        read_generalized(liar)


# -- every reader's max_bytes, checked by one function (review R3 B3) -------------------------


@pytest.fixture(scope="module")
def readers(exports) -> dict[str, tuple]:
    """Each public reader with a budget, beside a file it reads."""
    from mbody.equations.generalized import generalized
    from mbody.io.export.generalized import write_generalized
    from mbody.simulate.trajectory import Trajectory

    model = mbody.load(MODELS / "pendulum.yaml")
    run = exports / "run.npz"
    mbody.simulate(model, t_end=0.1, fps=10).save(run)
    equations = write_generalized(generalized(model), exports / "g.json")
    return {"mbody.load": (mbody.load, MODELS / "pendulum.yaml"),
            "Trajectory.load": (Trajectory.load, run),
            "load_export npz": (mbody.load_export, exports / "p.npz"),
            "load_export mat": (mbody.load_export, exports / "p.mat"),
            "load_export csv": (mbody.load_export, exports / "p_csv"),
            "read_generalized": (read_generalized, equations)}


READERS = ["mbody.load", "Trajectory.load", "load_export npz", "load_export mat",
           "load_export csv", "read_generalized"]


@pytest.mark.parametrize("reader", READERS)
@pytest.mark.parametrize(("given", "shown"), [
    ("1G", "str '1G'"), (1.5, "float 1.5"), (True, "bool True"), ([10], "list"),
    (float("nan"), "float nan")])
def test_max_bytes_that_is_not_a_whole_number_is_refused_by_name(readers, reader, given,
                                                                  shown):
    """Before: '1G' a raw ValueError (Trajectory.load) or blamed on the file (load_export),
    1.5 and True read as a budget of 1 byte."""
    load, path = readers[reader]
    with pytest.raises(MbodyTypeError) as exc:
        load(path, max_bytes=given)
    text = str(exc.value)
    assert text.startswith("max_bytes must be a whole number of bytes (such as 200 * 2**20), "
                           f"got {shown}"), text
    assert str(path) not in text  # the argument is at fault, not the file
    if isinstance(given, str):
        assert "2**30" in text and "--max-bytes" in text


@pytest.mark.parametrize("reader", READERS)
@pytest.mark.parametrize("given", [0, -5])
def test_max_bytes_below_one_byte_is_refused_by_every_reader(readers, reader, given):
    """Before: Trajectory.load(..., max_bytes=-5) said 'at most -5 bytes is read'."""
    load, path = readers[reader]
    with pytest.raises(MbodyError) as exc:
        load(path, max_bytes=given)
    assert str(exc.value) == f"max_bytes: expected a size of at least 1 byte, got {given}"


@pytest.mark.parametrize("reader", READERS)
def test_max_bytes_as_a_whole_float_or_numpy_integer_reads(readers, reader):
    load, path = readers[reader]
    assert load(path, max_bytes=float(2**30)) is not None
    assert load(path, max_bytes=np.int64(2**30)) is not None


def test_the_budget_set_around_a_block_is_checked_the_same_way():
    from mbody.util.budget import byte_budget

    with pytest.raises(MbodyTypeError, match="^max_bytes must be a whole number"), \
            byte_budget(True):  # type: ignore[arg-type]
        pass
