"""Train the benchmark's learned baseline with plain numpy: the cross-entropy method over the
15 weights of `swarmshape.env.benchmark.learned`, one policy shared by every robot, on 100
robots and on shapes the benchmark never tests (horseshoe, letter K, letter S), then save them.

    python examples/learn_benchmark.py --out learned.json        (about 8 minutes, one core)
    python examples/learn_benchmark.py --tiny                    (seconds: what the tests run)

A candidate's score is the coverage averaged over every step of its episodes (a shape formed
early counts as full to the end), so both forming more and forming sooner pay. Each
generation draws new seeds, the same for all its candidates. The parameters the leaderboard
uses are `swarmshape/env/benchmark/learned.json`, written by the full run with seed 0.
"""

import argparse
import json
import time
from pathlib import Path

import numpy as np

from swarmshape.env.benchmark import Learned, Task
from swarmshape.env.benchmark.learned import WEIGHTS
from swarmshape.env.benchmark.score import environment, play
from swarmshape.io.files import write_text

FULL = dict(generations=20, population=16, elite=4, robots=100, steps=400)
TINY = dict(generations=2, population=4, elite=2, robots=20, steps=40)


def training_tasks(robots: int, steps: int) -> list[Task]:
    """Three worlds unlike the benchmark's: other shapes, every start layout, some noise."""
    return [
        Task("train-horseshoe", "horseshoe.png", robots, steps, ()),
        Task("train-letter-k", "letter-k.png", robots, steps, (), start="packed"),
        Task("train-letter-s", "letter-s.png", robots, steps, (), distance_noise=0.1,
             msg_loss=0.1),
    ]  # fmt: skip


def score(weights: np.ndarray, task: Task, seed: int, env) -> float:
    """Coverage averaged over the episode's steps."""
    total = 0.0
    for step, formed in enumerate(play(Learned(weights), task, seed, env)):
        total += env.coverage()
        if formed:
            return (total + task.steps - step - 1) / task.steps
    return total / task.steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("learned.json"))
    parser.add_argument("--force", action="store_true", help="replace --out if it exists")
    parser.add_argument("--tiny", action="store_true", help="a few seconds, for the tests")
    args = parser.parse_args()
    if args.out.exists() and not args.force:
        parser.exit(2, f"{args.out} exists; --force replaces it\n")
    size = TINY if args.tiny else FULL
    started = time.perf_counter()
    print(f"seed {args.seed}; {size['generations']} generations of {size['population']}, "
          f"{size['robots']} robots, {size['steps']} steps an episode")  # fmt: skip
    rng = np.random.default_rng(args.seed)
    tasks = training_tasks(size["robots"], size["steps"])
    envs = [environment(Learned(np.zeros(len(WEIGHTS))), task) for task in tasks]
    mean, spread = np.zeros(len(WEIGHTS)), np.ones(len(WEIGHTS))
    for generation in range(size["generations"]):
        seed = 1_000 + generation
        candidates = mean + spread * rng.normal(size=(size["population"], len(WEIGHTS)))
        scores = np.array(
            [
                np.mean([score(w, t, seed, e) for t, e in zip(tasks, envs, strict=True)])
                for w in candidates
            ]
        )
        elite = candidates[np.argsort(scores)[-size["elite"] :]]
        mean, spread = elite.mean(axis=0), elite.std(axis=0) + 0.05
        print(f"generation {generation}: mean {scores.mean():.1%}, best {scores.max():.1%}, "
              f"{time.perf_counter() - started:.0f} s")  # fmt: skip
    final = np.mean([score(mean, t, 999, e) for t, e in zip(tasks, envs, strict=True)])
    saved = {
        "weights": dict(zip(WEIGHTS, np.round(mean, 6).tolist(), strict=True)),
        "trained": {"seed": args.seed, **size, "tasks": [t.name for t in tasks],
                    "score": round(float(final), 6)},
    }  # fmt: skip
    write_text(args.out, json.dumps(saved, indent=2) + "\n")
    wall, cpu = time.perf_counter() - started, time.process_time()
    print(f"trained in {wall:.0f} s ({cpu:.0f} s of CPU), seed {args.seed}: coverage {final:.1%} "
          f"averaged over a new episode of each training task; weights in {args.out}")  # fmt: skip


if __name__ == "__main__":
    main()
