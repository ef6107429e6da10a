"""Shared fixtures: the default config, loaded once per test session."""
from __future__ import annotations

import copy

import pytest

from pa10_dnbs.config import default_config_path, load_config


@pytest.fixture(scope="session")
def _default_cfg():
    return load_config(default_config_path())


@pytest.fixture
def cfg(_default_cfg):
    """A fresh deep copy of the validated default config (tests may edit it)."""
    return copy.deepcopy(_default_cfg)
