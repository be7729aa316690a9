"""Shared inputs: the repository's data fixtures and the command-line tools built by
`cargo test --profile testing` (which .ci/run runs first)."""

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
FIXTURES = REPO / "data-fixtures"


@pytest.fixture
def icosphere_path():
    """icosphere(2), 162 vertices, 320 triangles, written by trimesh."""
    return FIXTURES / "peer" / "icosphere_trimesh.obj"


@pytest.fixture
def creature_path():
    """The README's example: a closed 89 196-face creature."""
    return FIXTURES / "examples" / "creature.ply"


@pytest.fixture
def cli():
    """Path of a workspace command-line tool, built in the `testing` (or `release`) profile."""

    def find(name):
        target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
        for profile in ("testing", "release"):
            path = target / profile / name
            if path.exists():
                return path
        pytest.fail(f"{name} is not built: run `cargo test --profile testing` first")

    return find
