"""Shape formation as a multi-agent learning environment, after PettingZoo's and Gymnasium's
conventions. Needs the ``learn`` extra: ``pip install 'swarmshape[learn]'``.

Each robot is an agent running the same local program as every other, and the program is the
trainer's policy: the environment drives the swarm through a `Relay` program whose moves and
broadcasts are the actions given, so a robot observes exactly what a local program senses
(`swarmshape.core.perception.Perception`) and nothing else.

- ``parallel_env(shape, **options)``: a PettingZoo `ParallelEnv` (dicts keyed ``robot_0`` ...).
- ``vector_env(shape, **options)``: the batched interface, a Gymnasium `VectorEnv` over the
  robots of one swarm, for one shared policy on stacked numpy arrays.
- ``env`` / ``raw_env``: the AEC versions PettingZoo derives from the parallel one.

`shape` is an image or ``.toml`` scenario path (None: the bundled horseshoe) or a 2-D boolean
grid. Options: the run settings of the command line except ``strategy``, ``order`` and
``seed`` (``agents``, ``cells``, ``max_steps`` (default 1,000 per episode), ``start``,
``sense_radius``, ``distance_noise``, ``msg_loss``, ``speed_variation``, ``arena``, ...), and

- ``neighbours``: ``K``, neighbour slots per observation (default: every cell within the
  sensing radius, 28 at radius 3, so nothing sensed is dropped);
- ``message_size`` (default 0) and ``message_range`` (default ``(0, 255)``, inclusive): the
  integers each robot broadcasts;
- ``reward``: a callable ``reward(swarm) -> (n,) floats`` (default `CoverageShare`);
- ``render_mode``: ``"human"`` (a pygame window) or ``"rgb_array"`` (numpy frames), and
  ``render_size`` in pixels (default ``(640, 400)``).

Observation: a float32 vector of the robot's own state and ``K`` neighbour slots (nearest
first, with a ``present`` mask), described in `swarmshape.env.observe`; `Layout` names every
entry and `perception_of` turns observations back into a `Perception`.

Action: ``Discrete(5)``, a move (0 stay, 1..4 a direction of `swarmshape.core.motion.STEPS`,
in seed-frame axes), when ``message_size`` is 0; otherwise ``MultiDiscrete`` ``[move,
message_0, ...]`` with messages in ``message_range``. A move into a taken cell does not happen,
and a robot under way (``ready`` 0 in its observation) finishes its move before the next.

Episode: every robot terminates when the shape is formed and is truncated at ``max_steps``.
Faults (``faults``, ``failure_rate``): a robot removed or stalled terminates then and leaves
``agents`` (the batched interface keeps it, ignores its actions, and says which robots still act
in ``infos["acting"]``).
``reset(seed=...)`` makes the episode's swarm (start cells, noise) from the seed alone.
"""

from __future__ import annotations

from typing import Any

try:
    import gymnasium  # noqa: F401
    import pettingzoo
except ImportError as error:  # pragma: no cover - the suite installs the extra
    raise ImportError(
        "swarmshape.env needs the learn extra: pip install 'swarmshape[learn]'"
    ) from error

from pettingzoo.utils import wrappers
from pettingzoo.utils.conversions import parallel_to_aec

from swarmshape.env.episode import EPISODE_STEPS, MOVES, Episode
from swarmshape.env.observe import Layout, encode, perception_of
from swarmshape.env.parallel import SwarmEnv, parallel_env
from swarmshape.env.relay import Relay
from swarmshape.env.rewards import CoverageShare, Reward
from swarmshape.env.vector import SwarmVectorEnv, vector_env

__all__ = [
    "EPISODE_STEPS", "MOVES", "CoverageShare", "Episode", "Layout", "Relay", "Reward",
    "SwarmEnv", "SwarmVectorEnv", "encode", "env", "parallel_env", "perception_of", "raw_env",
    "vector_env",
]  # fmt: skip

ID = "swarmshape/Swarm-v0"
"""The name under PettingZoo's registry: ``pettingzoo.make("parallel", ID, shape=...)``."""


def raw_env(**options: Any) -> Any:
    """The AEC version of `parallel_env` (PettingZoo's ``raw_env`` creator)."""
    return parallel_to_aec(parallel_env(**options))


def env(**options: Any) -> Any:
    """The AEC version with PettingZoo's usual checks of actions and call order."""
    return wrappers.OrderEnforcingWrapper(wrappers.AssertOutOfBoundsWrapper(raw_env(**options)))


if hasattr(pettingzoo, "register") and ID not in getattr(pettingzoo, "parallel_registry", {}):
    pettingzoo.register("parallel", ID, entry_point="swarmshape.env:parallel_env")
