"""Build of mbody's compiled core (the C extension `mbody.kernel._core`); everything
else about the package is in pyproject.toml."""

from pathlib import Path

from setuptools import Extension, setup

SRC = Path("mbody/kernel/src")

setup(ext_modules=[Extension(
    "mbody.kernel._core",
    sources=sorted(str(p) for p in SRC.glob("*.c")),
    depends=sorted(str(p) for p in SRC.glob("*.h")),
    # no fused multiply-add: the same numbers on every x86-64 and arm64 machine; -O3
    # vectorises the loops that run down columns (the small QR of the generalized
    # equations) without reordering any sum (no -ffast-math), so the numbers are those
    # of -O2 bit for bit
    extra_compile_args=["-std=c99", "-O3", "-ffp-contract=off", "-fno-math-errno",
                        "-Wall", "-Wextra", "-Wno-unused-parameter"],
)])
