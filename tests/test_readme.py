"""The README's table of run settings is the one the code declares (it cannot drift)."""

from __future__ import annotations

import re
from pathlib import Path

from swarmshape.cli import settings_table

README = Path(__file__).resolve().parent.parent / "README.md"


def test_the_readme_lists_every_run_setting_as_declared():
    found = re.search(
        r"<!-- settings:[^>]*-->\n(.*?)\n<!-- /settings -->", README.read_text(), re.S
    )
    assert found, "the README has no settings table between its markers"
    assert found.group(1) == settings_table()
