"""A benchmark of shape formation for multi-agent learning: the versioned task suite
``shape-formation-v1`` (`suite`), one scoring function for any policy over batched
observations (`score.evaluate`), and the leaderboard's baselines (`baselines`: random, the
built-in local programs driven through the environment, and a learned policy in `learned`).

    from swarmshape.env.benchmark import evaluate, policy, tasks, to_markdown
    results = evaluate(policy("random"), tasks("star-100"), seeds=[0, 1])
    print(to_markdown(results))

From the shell: ``swarmshape benchmark POLICY --tasks star-100 --seeds 0-2``; docs/benchmark.md
holds the suite's definition and the leaderboard.
"""

from swarmshape.env.benchmark.baselines import Random, Scripted, local_programs, policy
from swarmshape.env.benchmark.learned import Learned
from swarmshape.env.benchmark.score import (
    Context,
    Policy,
    evaluate,
    leaderboard,
    to_json,
    to_markdown,
)
from swarmshape.env.benchmark.suite import SUITE, TASKS, Task, tasks

__all__ = [
    "SUITE", "TASKS", "Context", "Learned", "Policy", "Random", "Scripted", "Task", "evaluate",
    "leaderboard", "local_programs", "policy", "tasks", "to_json", "to_markdown",
]  # fmt: skip
