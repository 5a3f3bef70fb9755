"""How well and how fast a run formed its shape, as plain data for JSON, CSV and the HUD.

- ``steps``: steps until the last target cell was filled (None if it never was).
- ``coverage``: filled target cells / target cells, 0..1.
- ``iou``: intersection over union of the target cells and the cells holding the group's
  agents, counted inside the shape's bounding box; stray agents lying on the picture lower it.
- ``total_distance``: cells travelled by all agents of the group.
- ``overlaps``: overlapping pairs of squares, summed over every step (always 0 when correct).
- ``makespan_lower_bound``: no run can finish sooner: the longest lattice distance in a
  bottleneck-optimal assignment from the start cells, divided by the maximum speed, in steps.
- ``distance_lower_bound``: the least total lattice distance of any assignment.
- ``makespan_ratio``, ``distance_ratio``: what the run achieved over those bounds (>= 1).
- ``lower_bounds_exact``: False above 1,500 x 1,500, where each target's nearest-agent
  distance stands in (still a bound, only looser).
- ``robots_lost``: robots a fault removed; ``robots_stalled``: robots stopped for good where
  they stand; ``cells_lost_to_stalls``: targets a stalled robot holds or cuts off, which no
  robot can fill (they count against ``coverage``; a run ends when every other target is filled).
- ``faults``: one entry per fault event (`swarmshape.core.faults.LOG_KEYS`): its ``step``,
  ``kind``, ``robots``, ``coverage_before`` and ``coverage_after`` it, ``recovered_at`` (the
  step every target the survivors can reach was filled again, or None) and ``recovery_steps``,
  and the ``scale`` after it (below the one before when the survivors were too few).
- ``scale``: the final scale (smaller than at the start when a fault left too few robots).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from swarmshape.core.assignment import manhattan_lower_bounds
from swarmshape.core.states import STALLED
from swarmshape.core.swarm import Swarm

DIGITS = 6


def coverage(swarm: Swarm, group: int | None = None) -> float:
    """Filled target cells over target cells, of one group or of all."""
    filled = swarm.filled if group is None else swarm.filled[swarm.world.target_group == group]
    return round(float(filled.mean()), DIGITS)


def iou(swarm: Swarm, group: int | None = None) -> float:
    """The picture's match with the shape, of one group or averaged over all."""
    if group is None:
        groups = range(len(swarm.world.groups))
        return round(float(np.mean([_iou_of(swarm, g) for g in groups])), DIGITS)
    return round(_iou_of(swarm, group), DIGITS)


def _iou_of(swarm: Swarm, group: int) -> float:
    occupied = np.floor(swarm.positions()[(swarm.group == group) & swarm.present]).astype(int)
    return _iou(swarm.world.groups[group].targets, occupied)


def group_metrics(swarm: Swarm, group: int) -> dict[str, Any]:
    placed = swarm.world.groups[group]
    members = swarm.group == group
    return {
        "name": placed.name,
        "agents": placed.agents,
        "targets": len(placed.targets),
        "scale": round(placed.shape.scale, DIGITS),
        "steps": swarm.completed_at[group],
        "coverage": coverage(swarm, group),
        "iou": iou(swarm, group),
        "total_distance": round(float(swarm.distance[members].sum()), DIGITS),
        "overlaps": int(swarm.overlaps[group]),
        **_against_bounds(swarm, members, placed.targets, swarm.completed_at[group]),
    }


def _against_bounds(
    swarm: Swarm, members: np.ndarray, targets: np.ndarray, steps: int | None
) -> dict[str, Any]:
    longest, total, exact = manhattan_lower_bounds(swarm.start_cell[members], targets)
    makespan = longest / swarm.params.limits.max_speed
    return {
        "makespan_lower_bound": round(makespan, DIGITS),
        "distance_lower_bound": round(total, DIGITS),
        "makespan_ratio": _ratio(steps, makespan),
        "distance_ratio": _ratio(float(swarm.distance[members].sum()), total),
        "lower_bounds_exact": exact,
    }


def _ratio(achieved: float | None, bound: float) -> float | None:
    if achieved is None or bound <= 0:
        return None
    return round(achieved / bound, DIGITS)


def _iou(targets: np.ndarray, occupied: np.ndarray) -> float:
    low, high = targets.min(axis=0), targets.max(axis=0)
    occupied = occupied[((occupied >= low) & (occupied <= high)).all(axis=1)]
    target_set = {tuple(c) for c in targets.tolist()}
    occupied_set = {tuple(c) for c in occupied.tolist()}
    return len(target_set & occupied_set) / len(target_set | occupied_set)


def run_metrics(swarm: Swarm) -> dict[str, Any]:
    """The metrics file's content: the run's identity, totals, and the same per group."""
    groups = [group_metrics(swarm, g) for g in range(len(swarm.world.groups))]
    steps = [g["steps"] for g in groups]
    targets = sum(g["targets"] for g in groups)
    return {
        "shape": swarm.world.name,
        "strategy": swarm.plugin.name,
        "seed": swarm.seed,
        "arena": list(swarm.world.size),
        "agents": swarm.world.agents,
        "targets": targets,
        "scale": min(g["scale"] for g in groups),
        "steps": None if None in steps else max(steps),
        "steps_run": swarm.step_count,
        "coverage": coverage(swarm),
        "iou": iou(swarm),
        "total_distance": round(float(swarm.distance.sum()), DIGITS),
        "overlaps": int(swarm.overlap_total),
        "messages": swarm.driver.messages_sent,
        "robots_lost": swarm.faults.lost,
        "robots_stalled": int((swarm.state == STALLED).sum()),
        "cells_lost_to_stalls": int(swarm.dead.sum()),
        "faults": [dict(entry) for entry in swarm.faults.log],
        **_totals_against_bounds(groups, steps),
        "groups": groups,
    }


def _totals_against_bounds(groups: list[dict[str, Any]], steps: list[int | None]) -> dict:
    """Groups move in parallel: the run's makespan bound is the largest, distances add up."""
    makespan = max(g["makespan_lower_bound"] for g in groups)
    total = sum(g["distance_lower_bound"] for g in groups)
    moved = sum(g["total_distance"] for g in groups)
    return {
        "makespan_lower_bound": makespan,
        "distance_lower_bound": round(total, DIGITS),
        "makespan_ratio": _ratio(None if None in steps else max(steps), makespan),
        "distance_ratio": _ratio(moved, total),
        "lower_bounds_exact": all(g["lower_bounds_exact"] for g in groups),
    }


def _versus(metrics: dict[str, Any]) -> str:
    ratio = metrics["makespan_ratio"]
    return "" if ratio is None else f", {ratio:.2f}x the makespan lower bound"


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
        f"{metrics['overlaps']} overlaps, seed {metrics['seed']}{_versus(metrics)}"
    )
