"""How well and how fast a run formed its shape, as plain data for JSON, CSV and the HUD.

- ``steps``: steps until the last target cell was filled (None if it never was).
- ``coverage``: filled target cells / target cells, 0..1 (Sun et al. 2023's coverage rate).
- ``entering``: robots whose centre lies on their group's shape / robots present, 0..1 (Sun et
  al. 2023's entering rate: below 1 for good when there are spares).
- ``uniformity``: how unevenly the robots on the shape are spaced (Sun et al. 2023's distance
  variance): the variance of each one's distance to its nearest neighbour, taken as the sensing
  radius when none is within it; 0 when all are evenly spaced, as on a formed lattice shape.
  The authors' code sums the squares over the whole swarm; the mean keeps swarms of different
  sizes comparable, and only robots on the shape count, which is the same once all have
  entered. None while no robot is on the shape.
- ``iou``: intersection over union of the target cells and the cells holding the group's
  agents, counted inside the shape's bounding box; stray agents lying on the picture lower it.
- ``total_distance``: cells travelled by all agents of the group.
- ``overlaps``: overlapping pairs of squares, summed over every step (always 0 when correct).
- ``makespan_lower_bound``: no run can finish sooner, in steps: the time a robot takes from
  rest to rest under the speed and acceleration limits (`bounds.travel_steps`) over
  ``makespan_bound_cells``, the longest trip (lattice cells) of a bottleneck-optimal
  assignment from the start cells (`bounds.bottleneck_bound`).
- ``distance_lower_bound``: the least total lattice distance of any assignment
  (`bounds.distance_bound`).
- ``makespan_ratio``, ``distance_ratio``: what the run achieved over those bounds (>= 1).
- ``makespan_bound_method``, ``makespan_bound_exact``, ``distance_bound_method``,
  ``distance_bound_exact``: how each bound was obtained and whether it is the optimum itself
  ("exact") or only a proved lower bound ("hall", "hall+cut", "dual", "dual+ascent": see
  `bounds.Bound`). Each is computed within an estimated `BOUND_SECONDS`, so the result depends
  on the run only.
- ``robots_lost``: robots a fault removed; ``robots_stalled``: robots stopped for good where
  they stand; ``cells_lost_to_stalls``: targets a stalled robot holds or cuts off, which no
  robot can fill (they count against ``coverage``; a run ends when every other target is filled).
- ``cells_left_open``: targets neither filled nor lost to stalls at the end. A shape that
  keeps its size when faults leave it fewer robots than cells (``on_loss = "keep"``, the
  default) is formed once every robot that can move rests on it, with these cells open; with
  ``on_loss = "rescale"`` it is re-formed smaller instead, and a formed run leaves none.
- ``faults``: one entry per fault event (`swarmshape.core.faults.LOG_KEYS`): its ``step``,
  ``kind``, ``robots``, ``coverage_before`` and ``coverage_after`` it, ``recovered_at`` (the
  step every target the survivors can reach was filled again, or every survivor rests on the
  shape when they are too few to fill it, or None) and ``recovery_steps``,
  and the ``scale`` after it (below the one before when the survivors were too few).
- ``scale``: the final scale (smaller than at the start when a fault left too few robots).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from swarmshape.core.bounds import Bound, bottleneck_bound, distance_bound, travel_steps
from swarmshape.core.states import STALLED
from swarmshape.core.swarm import Swarm

DIGITS = 6

BOUND_SECONDS = 2.0
"""Estimated time each lower bound may take (see `bounds.FLOW_SECONDS`): the bottleneck is
exact up to about 10,000 robots, Hall's bound above."""


def coverage(swarm: Swarm, group: int | None = None) -> float:
    """Filled target cells over target cells, of one group or of all."""
    filled = swarm.filled if group is None else swarm.filled[swarm.world.target_group == group]
    return round(float(filled.mean()), DIGITS)


def entering(swarm: Swarm, group: int | None = None) -> float:
    """Robots on their group's shape over robots present, of one group or of all."""
    members = _members(swarm, group)
    return round(float(_on_shape(swarm)[members].mean()), DIGITS) if members.any() else 0.0


def uniformity(swarm: Swarm, group: int | None = None) -> float | None:
    """The variance of nearest-neighbour distances (at most the sensing radius) over the robots
    on their shape, of one group or of all; None while none is on it."""
    from scipy.spatial import cKDTree

    members = _members(swarm, group)
    inside = members & _on_shape(swarm)
    if not inside.any():
        return None
    radius = swarm.params.senses.radius
    points = swarm.positions()
    nearest, _ = cKDTree(points[members]).query(points[inside], k=[2], distance_upper_bound=radius)
    return round(float(np.minimum(nearest[:, 0], radius).var()), DIGITS)


def _members(swarm: Swarm, group: int | None) -> np.ndarray:
    present = swarm.present
    return present if group is None else present & (swarm.group == group)


def _on_shape(swarm: Swarm) -> np.ndarray:
    """Whether each robot's centre lies on a target cell of its own group."""
    cells = swarm.cells_under()
    at = swarm.target_at[cells[:, 0], cells[:, 1]]
    return (at >= 0) & (swarm.world.target_group[np.maximum(at, 0)] == swarm.group)


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
        "entering": entering(swarm, group),
        "uniformity": uniformity(swarm, group),
        "iou": iou(swarm, group),
        "total_distance": round(float(swarm.distance[members].sum()), DIGITS),
        "overlaps": int(swarm.overlaps[group]),
        **_against_bounds(swarm, members, placed.targets, swarm.completed_at[group]),
    }


def _against_bounds(
    swarm: Swarm, members: np.ndarray, targets: np.ndarray, steps: int | None
) -> dict[str, Any]:
    starts = swarm.start_cell[members]
    longest = bottleneck_bound(starts, targets, budget_seconds=BOUND_SECONDS)
    total = distance_bound(starts, targets, budget_seconds=BOUND_SECONDS)
    makespan = int(travel_steps(int(longest.value), swarm.params.limits))
    return {
        "makespan_lower_bound": makespan,
        "makespan_bound_cells": int(longest.value),
        **_how("makespan", longest),
        "distance_lower_bound": int(total.value),
        **_how("distance", total),
        "makespan_ratio": _ratio(steps, makespan),
        "distance_ratio": _ratio(float(swarm.distance[members].sum()), total.value),
    }


def _how(name: str, bound: Bound) -> dict[str, Any]:
    return {f"{name}_bound_method": bound.method, f"{name}_bound_exact": bound.exact}


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


LOCAL_FIGURES = {
    "messages_lost": 0,
    "localisation_error_mean": None,
    "localisation_error_max": None,
    "localised": None,
}
"""What local programs add to the metrics (these values for a central strategy), so that every
run's metrics have the same fields."""


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
        "entering": entering(swarm),
        "uniformity": uniformity(swarm),
        "iou": iou(swarm),
        "total_distance": round(float(swarm.distance.sum()), DIGITS),
        "overlaps": int(swarm.overlap_total),
        "messages": swarm.driver.messages_sent,
        **LOCAL_FIGURES,
        **swarm.figures(),
        "robots_lost": swarm.faults.lost,
        "robots_stalled": int((swarm.state == STALLED).sum()),
        "cells_lost_to_stalls": int(swarm.dead.sum()),
        "cells_left_open": int((~swarm.filled & ~swarm.dead).sum()),
        "faults": [dict(entry) for entry in swarm.faults.log],
        **_totals_against_bounds(groups, steps),
        "groups": groups,
    }


def _totals_against_bounds(groups: list[dict[str, Any]], steps: list[int | None]) -> dict[str, Any]:
    """Groups move in parallel: the run's makespan bound is the largest, distances add up.
    Exact only when every group's is (a loose bound in one group might hide a larger
    optimum); the method lists every group's."""
    makespan = max(g["makespan_lower_bound"] for g in groups)
    total = sum(g["distance_lower_bound"] for g in groups)
    moved = sum(g["total_distance"] for g in groups)
    finished = [s for s in steps if s is not None]
    return {
        "makespan_lower_bound": makespan,
        "makespan_bound_cells": max(g["makespan_bound_cells"] for g in groups),
        **_combined(groups, "makespan"),
        "distance_lower_bound": total,
        **_combined(groups, "distance"),
        "makespan_ratio": _ratio(max(finished) if len(finished) == len(steps) else None, makespan),
        "distance_ratio": _ratio(moved, total),
    }


def _combined(groups: list[dict[str, Any]], name: str) -> dict[str, Any]:
    methods = dict.fromkeys(g[f"{name}_bound_method"] for g in groups)
    return {
        f"{name}_bound_method": ", ".join(methods),
        f"{name}_bound_exact": all(g[f"{name}_bound_exact"] for g in groups),
    }
