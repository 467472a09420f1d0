"""Fixtures shared by the workbook tests."""

import pytest


@pytest.fixture
def workbook(tmp_path, monkeypatch):
    """An empty checkout for ``reproduce``: a ``notebooks/`` folder, PIEZOLIB_ROOT set to it."""
    (tmp_path / "notebooks").mkdir()
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    return tmp_path
