"""Shared fixtures of the Python package's tests (run by tools/test.sh after
the cargo tests; torch and ray are required, never skipped)."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DATA = Path(__file__).resolve().parent / "data"


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT


@pytest.fixture(scope="session")
def data() -> Path:
    return DATA


@pytest.fixture(scope="session")
def cli() -> Path:
    """The `sdrs` binary of this checkout (release): `$SDRS_CLI` when set
    (`tools/test.sh` sets it to the binary its `cargo test` just built: a
    `cargo build -p sdrs-cli` here resolves that package's features alone
    and rebuilt the core, 118 s of CI), else built here."""
    given = os.environ.get("SDRS_CLI")
    if given:
        exe = Path(given)
        assert exe.is_file(), f"SDRS_CLI={given} is not a file"
        return exe
    subprocess.run(
        ["cargo", "build", "--release", "--quiet", "-p", "sdrs-cli", "--bin", "sdrs"],
        cwd=ROOT,
        check=True,
    )
    exe = ROOT / os.environ.get("CARGO_TARGET_DIR", "target") / "release" / "sdrs"
    assert exe.is_file(), exe
    return exe


def rel_err(a, b, floor: float) -> float:
    """|a − b| / max(|a|, |b|, floor)."""
    return abs(a - b) / max(abs(a), abs(b), floor)
