"""The window's tests keep out of the user's own data folder (the editor autosaves there)."""

from __future__ import annotations

import pytest


@pytest.fixture(autouse=True)
def data_home(tmp_path_factory, monkeypatch):
    """A fresh XDG_DATA_HOME for every test: `editor.data_folder` lies under it."""
    home = tmp_path_factory.mktemp("data-home")
    monkeypatch.setenv("XDG_DATA_HOME", str(home))
    return home
