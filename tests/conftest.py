"""Shared fixtures: the one GL context (with the GL error flag checked around each test) and scene helpers."""

from __future__ import annotations

import copy
import zlib

import numpy as np
import pytest

MINIMAL_SCENE = {
    "camera": {"position": [0, 3, 4], "look_at": [0, 0, 0], "fov_y": 45, "size": [320, 240]},
    "materials": {"floor": {"type": "lambert", "albedo": [0.8, 0.8, 0.8]}},
    "mesh": [{"shape": "plane", "size": [4, 4], "material": "floor"}],
    "light": [{"type": "point", "position": [0, 2, 0], "intensity": [10, 10, 10]}],
}

MINIMAL_TOML = """\
[camera]
position = [0, 3, 4]
look_at = [0, 0, 0]
fov_y = 45
size = [320, 240]

[materials.floor]
type = "lambert"
albedo = [0.8, 0.8, 0.8]

[[mesh]]
shape = "plane"
size = [4, 4]
material = "floor"

[[light]]
type = "point"
position = [0, 2, 0]
intensity = [10, 10, 10]
"""


@pytest.fixture
def minimal_scene() -> dict:
    """A fresh deep copy of the issue's minimal scene, as a dict (tests may mutate it)."""
    return copy.deepcopy(MINIMAL_SCENE)


@pytest.fixture
def minimal_toml(tmp_path):
    path = tmp_path / "minimal.toml"
    path.write_text(MINIMAL_TOML)
    return path


@pytest.fixture
def ctx():
    """The process-wide GL context; fails a test that leaves the GL error flag set."""
    from reflets.gpu import get_context

    context = get_context()
    assert context.error == "GL_NO_ERROR", f"GL error flag already set before the test: {context.error}"
    yield context
    error = context.error
    assert error == "GL_NO_ERROR", f"the test left the GL error flag set: {error}"


@pytest.fixture
def rng(request) -> np.random.Generator:
    """A generator seeded from the test's name: reproducible, different per test."""
    return np.random.default_rng(zlib.crc32(request.node.name.encode()))
