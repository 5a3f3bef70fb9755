from __future__ import annotations

import re
import sys
import textwrap

import numpy as np
import pytest

from swarmshape import strategies
from swarmshape.errors import InputError
from swarmshape.swarm import Swarm
from tests.conftest import grid_from, make_swarm

SHAPE = grid_from("""
###.
#.##
""")


def docstring_example() -> str:
    block = strategies.__doc__.split("::", 1)[1]
    return textwrap.dedent(block)


def test_the_docstring_example_is_short_and_forms_a_shape(monkeypatch):
    code = docstring_example()
    assert len([line for line in code.splitlines() if line.strip()]) < 20
    monkeypatch.setattr(strategies, "REGISTRY", dict(strategies.REGISTRY))
    exec(compile(code, "docstring example", "exec"), {})
    assert "nearest-first" in strategies.available()
    swarm = make_swarm(SHAPE, seed=2, strategy="nearest-first")
    swarm.run(5_000)
    assert swarm.complete and swarm.overlap_total == 0


def test_a_class_is_reachable_as_module_colon_class(tmp_path, monkeypatch):
    module = tmp_path / "my_strategies.py"
    module.write_text(docstring_example().replace("@register\n", ""))
    monkeypatch.syspath_prepend(str(tmp_path))
    cls = strategies.get("my_strategies:NearestFirst")
    assert cls.name == "nearest-first"
    assert "nearest-first" not in strategies.REGISTRY


def test_installed_packages_offer_strategies_through_entry_points(tmp_path, monkeypatch):
    (tmp_path / "plugin_pkg.py").write_text(docstring_example().replace("@register\n", ""))
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
        ("swarmshape.motion:Nothing", "has no Nothing"),
        ("swarmshape.motion:Limits", "lacks start and on_settled"),
    ],
)
def test_bad_strategy_names_are_clear(name, message):
    with pytest.raises(InputError, match=re.escape(message)):
        strategies.get(name)


def test_options_go_only_to_strategies_that_take_them():
    assert strategies.create("paper", order="random").order == "random"
    assert strategies.create("optimal", order="random").concurrent


def test_every_builtin_has_a_description_and_a_mode():
    for name, cls in strategies.available().items():
        assert cls.name == name and cls.description
        assert isinstance(cls.concurrent, bool)


def test_concurrent_strategies_move_many_agents_at_once():
    for name in ("optimal", "greedy", "random"):
        swarm: Swarm = make_swarm(SHAPE, seed=1, strategy=name)
        assert (swarm.state == 1).sum() == len(swarm.world.targets)
        assert np.unique(swarm.target[swarm.state == 1]).size == len(swarm.world.targets)
