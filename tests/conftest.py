"""Shared fixtures. Plain helper functions live in ``_helpers.py`` (import them from there)."""

from __future__ import annotations

import pytest
from _helpers import quintic


@pytest.fixture
def quintic_traj():
    return quintic()
