"""Shared test fixtures: the real data in ``../shared/data``.

Tests that use the ``shared_data`` or ``kitti_root`` fixture, or carry the ``shared_data`` marker,
are skipped when ``../shared/data`` is absent (a fresh clone), and fail instead when the
environment variable ``FLIC_REQUIRE_SHARED_DATA=1`` is set (CI).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

SHARED_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def _require_shared_data() -> None:
    if SHARED_DATA.is_dir():
        return
    if os.environ.get("FLIC_REQUIRE_SHARED_DATA") == "1":
        pytest.fail(f"{SHARED_DATA} is missing and FLIC_REQUIRE_SHARED_DATA=1")
    pytest.skip("../shared/data not present")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Mark every test that uses the real data, so that ``-m "not shared_data"`` works."""
    for item in items:
        if "shared_data" in getattr(item, "fixturenames", ()):
            item.add_marker(pytest.mark.shared_data)


def pytest_runtest_setup(item: pytest.Item) -> None:
    """Skip (or, with FLIC_REQUIRE_SHARED_DATA=1, fail) a ``shared_data`` test without the data."""
    if item.get_closest_marker("shared_data") is not None:
        _require_shared_data()


@pytest.fixture
def shared_data() -> Path:
    """``../shared/data`` (relative to the project root)."""
    return SHARED_DATA


@pytest.fixture
def kitti_root(shared_data: Path) -> Path:
    """The SemanticKITTI root of the real data (``../shared/data/semantickitti``)."""
    return shared_data / "semantickitti"


@pytest.fixture(scope="session")
def small_sample(tmp_path_factory: pytest.TempPathFactory):
    """A 3-frame synthetic sample (SemanticKITTI sequence + Moosmann log), written once."""
    from flic_cli.sample import write_sample

    return write_sample(tmp_path_factory.mktemp("sample"), frames=3)


@pytest.fixture(scope="session")
def sample_root(small_sample) -> Path:
    """The SemanticKITTI root of the 3-frame synthetic sample."""
    return small_sample.kitti_root


@pytest.fixture(autouse=True)
def _pin_thread_env(monkeypatch: pytest.MonkeyPatch) -> None:
    """Worker code run in this process (dask with processes=False) sets the thread-pool
    variables; pin them per test so that no test leaks them into the next."""
    from flic_cli.runs.environment import THREAD_ENV_VARS

    for name in THREAD_ENV_VARS:
        monkeypatch.setenv(name, "1")
