"""Shared fixtures: the repository root and the `vcm` command-line binary the equality tests
compare against (VCM_BIN, else target/release/vcm; `.ci/run` builds it)."""

import os
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def vcm_bin():
    path = pathlib.Path(os.environ.get("VCM_BIN", ROOT / "target" / "release" / "vcm"))
    if not path.is_file():
        pytest.fail(f"the vcm binary {path} is missing: build it with `cargo build --release -p vcm` or set VCM_BIN")
    return path


@pytest.fixture(scope="session")
def root():
    return ROOT
