"""Shared test options: ``--run-slow`` enables tests marked ``slow`` (``make test-slow``)."""

import os

import pytest

os.environ.setdefault("MS_SKIP_ASSET_DOWNLOAD_PROMPT", "1")


def pytest_addoption(parser):
    parser.addoption("--run-slow", action="store_true", default=False, help="run tests marked slow")


def pytest_collection_modifyitems(config, items):
    if config.getoption("--run-slow"):
        return
    skip = pytest.mark.skip(reason="slow: run with `make test-slow` (pytest --run-slow)")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)
