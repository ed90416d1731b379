"""Sizes in messages (review R3 B8, Y1): one wording, `mbody.util.formatting.size_text`,
for a model file's size, a run's, an export's and their budgets.

Before, two functions (the model loader's and the data files') differed ("1 byte" and
"1 bytes", "1.0 MiB" and "1 MiB") and both printed 1000 to 1023.99 KiB (and MiB, GiB)
with an exponent: '1.01e+03 KiB'.
"""

from __future__ import annotations

import re

import pytest

import mbody
from mbody.cli.app import main
from mbody.util.formatting import size_text, sizes_apart
from mbody.util.npzfile import over_budget

KIB, MIB, GIB = 2**10, 2**20, 2**30


@pytest.mark.parametrize(("n", "text"), [
    (0, "0 bytes"), (1, "1 byte"), (2, "2 bytes"), (1023, "1,023 bytes"),
    (1024, "1 KiB (1,024 bytes)"), (1536, "1.5 KiB (1,536 bytes)"),
    (1_023_475, "999 KiB (1,023,475 bytes)"),          # 999.49 KiB: still KiB
    (1_023_488, "0.976 MiB (1,023,488 bytes)"),        # 999.5 KiB rounds to 1000: MiB
    (1_024_000, "0.977 MiB (1,024,000 bytes)"),        # 1000 KiB
    (1_048_575, "1 MiB (1,048,575 bytes)"),            # 1023.999 KiB, the exact count kept
    (1_048_576, "1 MiB"), (200 * MIB, "200 MiB"),
    (1_073_741_823, "1 GiB"),                          # 1023.999999 MiB
    (GIB, "1 GiB"), (2**31, "2 GiB"), (8 * 10**15, "7.11 PiB"),
    (2**70, "1,024 EiB")])                             # past the last unit: whole, no exponent
def test_sizes_read_as_people_write_them(n, text):
    assert size_text(n) == text


@pytest.mark.parametrize("n", [KIB * k + d for k in (999, 1000, 1023) for d in (-1, 0, 512)]
                         + [MIB * k + d for k in (999, 1000, 1023, 1024) for d in (-1, 0)]
                         + [GIB * k - 1 for k in (1000, 1024)])
def test_no_size_prints_with_an_exponent_or_a_figure_of_1000(n):
    figure = size_text(n).split()[0]
    assert "e" not in figure and float(figure.replace(",", "")) < 1000, size_text(n)


def test_two_sizes_that_round_alike_are_told_apart_in_bytes():
    assert sizes_apart(GIB - 1, GIB) == ("1,073,741,823 bytes", "1,073,741,824 bytes")
    assert sizes_apart(3 * MIB, GIB) == ("3 MiB", "1 GiB")
    assert sizes_apart(GIB, GIB) == ("1 GiB", "1 GiB")


def test_a_model_file_over_its_budget_in_the_one_wording(tmp_path, capsys):
    """The reviewer's case: a 1,030,000-byte file against --max-bytes 1024000 printed
    '1.01e+03 KiB ... at most 1e+03 KiB'."""
    path = tmp_path / "big.yaml"
    path.write_text("dimension: 2\n" + "#" * (1_030_000 - 14) + "\n")
    assert path.stat().st_size == 1_030_000
    assert main(["check", str(path), "--max-bytes", "1024000"]) == 2
    err = capsys.readouterr().err
    assert (f"{path}: the file is 0.982 MiB (1,030,000 bytes); mbody reads at most "
            "0.977 MiB (1,024,000 bytes) (") in err, err
    (tmp_path / "two.yaml").write_bytes(b"{}")
    with pytest.raises(mbody.ModelError, match=re.escape(
            "the file is 2 bytes; mbody reads at most 1 byte (")):
        mbody.load(tmp_path / "two.yaml", max_bytes=1)


def test_a_data_file_over_a_budget_of_one_byte_says_byte():
    """Before: 'at most 1 bytes is read'."""
    assert over_budget("r.npz", 2, 2, 1, "more") == ("r.npz: holds 2 bytes of data; at most "
                                                     "1 byte is read (more)")


@pytest.mark.parametrize("sign, power, text", [(1, 400, "about 1e400"),
                                               (-1, 5000, "-about 1e5000"),
                                               (1, 299, "1e299"), (1, 2, "100")])
def test_a_count_past_a_floats_range_prints_its_power_of_ten(sign, power, text):
    """`formatting.number` of an int beyond 1e308 (a count from a huge quotient, a file's
    version): no OverflowError from float(), no thousands of digits."""
    from mbody.util.formatting import number

    assert number(sign * 10**power) == text
