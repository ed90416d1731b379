"""Build of mbody's compiled core (the C extension `mbody.kernel._core`); everything
else about the package is in pyproject.toml."""

from pathlib import Path

from setuptools import Extension, setup

SRC = Path("mbody/kernel/src")

setup(ext_modules=[Extension(
    "mbody.kernel._core",
    sources=sorted(str(p) for p in SRC.glob("*.c")),
    depends=sorted(str(p) for p in SRC.glob("*.h")),
    # no fused multiply-add: the same numbers on every x86-64 and arm64 machine
    extra_compile_args=["-std=c99", "-O2", "-ffp-contract=off", "-fno-math-errno",
                        "-Wall", "-Wextra", "-Wno-unused-parameter"],
)])
