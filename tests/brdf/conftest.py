"""Fixtures for BRDF tests."""

from __future__ import annotations

import pytest
from brdf_helpers import upper_hemisphere


@pytest.fixture
def directions(rng):
    return upper_hemisphere(rng, 2000), upper_hemisphere(rng, 2000)
