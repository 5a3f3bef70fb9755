"""swarmshape: a swarm of square robots organises itself into a shape given as a bitmap.

The library API, in the order a script uses it::

    import swarmshape

    config = swarmshape.configure("shapes/star.png", seed=1, strategy="optimal")
    swarm = swarmshape.build(config)
    swarmshape.run(swarm, max_steps=config.max_steps)
    print(swarmshape.run_metrics(swarm)["steps"])

Names are imported on first use, so ``import swarmshape`` stays fast and never loads pygame.
"""

from __future__ import annotations

import importlib
import os
from typing import Any

os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")  # keep pygame's banner off our output

__all__ = [
    "Blueprint", "GroupSpec", "InputError", "Motion", "Observer", "Perception", "Pose", "Program",
    "RunConfig", "Runner", "Senses", "Shape", "Slot", "State", "Strategy", "Swarm", "SwarmView",
    "World", "available", "build", "build_world",
    "check_strategy", "configure", "load_grid", "register", "resume", "run", "run_metrics",
    "save", "start_swarm",
]  # fmt: skip

_HOMES = {
    "swarmshape.config": ("RunConfig", "configure"),
    "swarmshape.runs": ("build", "start_swarm", "run", "Runner", "Observer", "save", "resume"),
    "swarmshape.core.swarm": ("Swarm",),
    "swarmshape.core.world": ("World", "GroupSpec", "build_world"),
    "swarmshape.core.shape": ("Shape", "Pose"),
    "swarmshape.core.states": ("State",),
    "swarmshape.core.steering": ("Strategy", "SwarmView"),
    "swarmshape.core.local": ("Program", "Slot"),
    "swarmshape.core.perception": ("Perception", "Senses", "Blueprint"),
    "swarmshape.core.motion": ("Motion",),
    "swarmshape.strategies": ("register", "available"),
    "swarmshape.core.metrics": ("run_metrics",),
    "swarmshape.check": ("check_strategy",),
    "swarmshape.io.bitmap": ("load_grid",),
    "swarmshape.errors": ("InputError",),
}  # fmt: skip
"""Where each public name lives; it is imported from there on first use."""

_HOME_OF = {name: module for module, names in _HOMES.items() for name in names}


def __getattr__(name: str) -> Any:
    if name not in _HOME_OF:
        raise AttributeError(f"module 'swarmshape' has no attribute {name!r}")
    value = getattr(importlib.import_module(_HOME_OF[name]), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return __all__
