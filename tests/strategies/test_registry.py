from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pytest

from swarmshape import strategies
from swarmshape.config import configure, plugin_options
from swarmshape.core.local import Program
from swarmshape.core.motion import Motion
from swarmshape.core.swarm import Swarm
from swarmshape.errors import InputError, SettingError
from swarmshape.runs import run
from tests.conftest import SHAPES, grid_from, make_swarm

SHAPE = grid_from("""
###.
#.##
""")


README = Path(__file__).resolve().parents[2] / "README.md"


def readme_example() -> str:
    """The code block of the README's "Writing a strategy" section."""
    section = README.read_text().split("## Writing a strategy", 1)[1]
    return section.split("```python\n", 1)[1].split("```", 1)[0]


def test_the_readme_example_is_short_and_forms_a_shape(monkeypatch):
    code = readme_example()
    assert len([line for line in code.splitlines() if line.strip()]) < 20
    monkeypatch.setattr(strategies, "REGISTRY", dict(strategies.REGISTRY))
    exec(compile(code, "README example", "exec"), {})
    assert "nearest-first" in strategies.available()
    swarm = make_swarm(SHAPE, seed=2, strategy="nearest-first")
    run(swarm, max_steps=5_000)
    assert swarm.complete and swarm.overlap_total == 0


def test_a_class_is_reachable_as_module_colon_class(tmp_path, monkeypatch):
    module = tmp_path / "my_strategies.py"
    module.write_text(readme_example().replace("@register\n", ""))
    monkeypatch.syspath_prepend(str(tmp_path))
    cls = strategies.get("my_strategies:NearestFirst")
    assert cls.name == "nearest-first"
    assert "nearest-first" not in strategies.REGISTRY


def test_code_that_takes_a_builtin_name_is_refused_and_a_builtin_by_its_module_is_not(
    tmp_path, monkeypatch
):
    """A user's class called "optimal" ran, and its summary, metrics and sweep rows said
    optimal: results that claim another algorithm's name."""
    module = tmp_path / "clash.py"
    module.write_text(
        readme_example().replace("@register\n", "").replace("nearest-first", "optimal")
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(InputError, match="calls itself 'optimal', a built-in strategy's name"):
        strategies.get("clash:NearestFirst")
    assert strategies.get("swarmshape.strategies.concurrent:Optimal").name == "optimal"


def test_installed_packages_offer_strategies_through_entry_points(tmp_path, monkeypatch):
    (tmp_path / "plugin_pkg.py").write_text(readme_example().replace("@register\n", ""))
    info = tmp_path / "plugin_pkg-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: plugin-pkg\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(
        "[swarmshape.strategies]\nnearest-first = plugin_pkg:NearestFirst\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    assert strategies.get("nearest-first").__module__ == "plugin_pkg"
    sys.modules.pop("plugin_pkg", None)


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("nope", "unknown strategy 'nope'; choose one of"),
        ("no_such_module_xyz:Thing", "cannot import"),
        ("swarmshape.core.motion:Nothing", "has no Nothing"),
        ("swarmshape.core.motion:Limits", "is not a subclass of swarmshape.Strategy"),
    ],
)
def test_bad_strategy_names_are_clear(name, message):
    with pytest.raises(InputError, match=re.escape(message)):
        strategies.get(name)


def test_a_plug_in_gets_its_own_options_and_no_other():
    paper = configure(SHAPES / "square.png", strategy="paper", options={"order": "random"})
    assert strategies.create("paper", plugin_options(paper)).options.order == "random"
    with pytest.raises(SettingError, match="order is an option of paper, not of optimal"):
        configure(SHAPES / "square.png", strategy="optimal", options={"order": "random"})
    with pytest.raises(SettingError, match="orde is not an option of paper; paper takes order"):
        configure(SHAPES / "square.png", strategy="paper", options={"orde": "random"})


def test_every_builtin_has_a_description_and_a_mode():
    for name, cls in strategies.available().items():
        assert cls.name == name and cls.description
        if issubclass(cls, Program):
            assert cls.kind == "local" and cls.message_size >= 0
        else:
            assert cls.kind == "central" and isinstance(cls.motion, Motion)


def test_concurrent_strategies_move_many_agents_at_once():
    for name in ("optimal", "greedy", "random"):
        swarm: Swarm = make_swarm(SHAPE, seed=1, strategy=name)
        assert (swarm.state == 1).sum() == len(swarm.world.targets)
        assert np.unique(swarm.driver.target[swarm.state == 1]).size == len(swarm.world.targets)
