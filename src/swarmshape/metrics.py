"""How well and how fast a run formed its shape, as plain data for JSON, CSV and the HUD.

- ``steps``: steps until the last target cell was filled (None if it never was).
- ``coverage``: filled target cells / target cells, 0..1.
- ``iou``: intersection over union of the target cells and the cells holding the group's
  agents, counted inside the shape's bounding box; stray agents lying on the picture lower it.
- ``total_distance``: cells travelled by all agents of the group.
- ``overlaps``: overlapping pairs of squares, summed over every step (always 0 when correct).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from swarmshape.swarm import Swarm

DIGITS = 6


def group_metrics(swarm: Swarm, group: int) -> dict[str, Any]:
    placed = swarm.world.groups[group]
    mine = swarm.world.target_group == group
    members = swarm.group == group
    return {
        "name": placed.name,
        "agents": placed.agents,
        "targets": len(placed.targets),
        "scale": round(placed.shape.scale, DIGITS),
        "steps": swarm.completed_at[group],
        "coverage": round(float(swarm.filled[mine].mean()), DIGITS),
        "iou": round(
            _iou(placed.targets, np.floor(swarm.positions()[members]).astype(int)), DIGITS
        ),
        "total_distance": round(float(swarm.distance[members].sum()), DIGITS),
        "overlaps": int(swarm.overlaps[group]),
    }


def _iou(targets: np.ndarray, occupied: np.ndarray) -> float:
    low, high = targets.min(axis=0), targets.max(axis=0)
    occupied = occupied[((occupied >= low) & (occupied <= high)).all(axis=1)]
    target_set = {tuple(c) for c in targets.tolist()}
    occupied_set = {tuple(c) for c in occupied.tolist()}
    return len(target_set & occupied_set) / len(target_set | occupied_set)


def run_metrics(swarm: Swarm, shape: str, strategy: str) -> dict[str, Any]:
    """The metrics file's content: the run's identity, totals, and the same per group."""
    groups = [group_metrics(swarm, g) for g in range(len(swarm.world.groups))]
    steps = [g["steps"] for g in groups]
    targets = sum(g["targets"] for g in groups)
    filled = int(swarm.filled.sum())
    return {
        "shape": shape,
        "strategy": strategy,
        "seed": swarm.seed,
        "arena": list(swarm.world.size),
        "agents": swarm.world.agents,
        "targets": targets,
        "scale": min(g["scale"] for g in groups),
        "steps": None if None in steps else max(steps),
        "steps_run": swarm.step_count,
        "coverage": round(filled / targets, DIGITS),
        "iou": round(float(np.mean([g["iou"] for g in groups])), DIGITS),
        "total_distance": round(float(swarm.distance.sum()), DIGITS),
        "overlaps": int(swarm.overlap_total),
        "messages": len(swarm.queue.log),
        "groups": groups,
    }


def summary_line(metrics: dict[str, Any]) -> str:
    """One human line for the terminal."""
    formed = (
        f"formed in {metrics['steps']} steps"
        if metrics["steps"] is not None
        else f"not formed after {metrics['steps_run']} steps"
    )
    return (
        f"{metrics['shape']}: {metrics['strategy']}, {metrics['agents']} agents, "
        f"{metrics['targets']} targets, scale {metrics['scale']:.2f}: {formed}, "
        f"coverage {100 * metrics['coverage']:.1f}%, iou {metrics['iou']:.3f}, "
        f"{metrics['overlaps']} overlaps, seed {metrics['seed']}"
    )
