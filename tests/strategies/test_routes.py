"""Routes round a known shape: shortest, outside the shape where they can be, and through as
few of its cells as they must."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import scipy
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmshape.core.perception import Blueprint
from swarmshape.strategies import routes
from tests.conftest import grid_from


def blueprint_of(text: str) -> Blueprint:
    """The shape drawn in `text` ('#' ink), its first row at frame y = 0."""
    grid = grid_from(text).T  # rows of text are y, columns x
    return Blueprint.of([np.argwhere(grid)])


def walk(blueprint: Blueprint, start, target, limit: int = 200) -> list[tuple[int, int]]:
    """Cells visited by following one-step waypoints from `start` to `target`."""
    at, path = np.array([start]), [tuple(start)]
    for _ in range(limit):
        cell, found = routes.waypoints(blueprint, np.zeros(1, int), at, np.array([target]), 1)
        assert found[0]
        at = cell
        path.append(tuple(int(v) for v in cell[0]))
        if path[-1] == tuple(target):
            return path
    raise AssertionError(f"no arrival in {limit} steps: {path[-5:]}")


U = """
##...##
##...##
##...##
#######
"""


def test_a_route_goes_round_the_shape_and_ends_on_its_target():
    shape = blueprint_of(U)
    inside = {tuple(c) for c in shape.cells[0].tolist()}
    start, target = (3, 5), (1, 1)  # below the U's floor; the target faces only its bay
    path = walk(shape, start, target)
    assert all(cell not in inside for cell in path[:-1])
    steps = [abs(a[0] - b[0]) + abs(a[1] - b[1]) for a, b in itertools.pairwise(path)]
    assert steps == [1] * len(steps)
    # right: over to x 7, up to y -1, back to x 2, down the bay to y 1, and in; the seeds (an
    # L at (-1..1, -1) and (-1, 0)) make the way round the left arm two steps longer
    assert len(path) - 1 == 4 + 6 + 5 + 2 + 1


def test_a_robot_beside_the_box_steps_in_and_one_farther_out_costs_no_field():
    """A robot one move off the box round the shape steps onto it; one farther out has no
    way (it walks straight in), and no field is worked out for it: at 10,000 robots nine in
    ten of local-swap's fields were for such robots, and went unused."""
    shape = blueprint_of(U)
    low, _ = routes._box(shape, 0)
    beside, beyond = (low[0] - 1, 2), (low[0] - 2, 2)
    pool = routes._fields(shape, 0)
    cells, found = routes.waypoints(
        shape, np.zeros(2, int), np.array([beside, beyond]), np.array([(1, 1), (5, 1)]), 3
    )
    assert found.tolist() == [True, False]
    assert cells[0, 0] >= low[0] and tuple(cells[1]) == (5, 1)
    assert (1, 1) in pool.slot and (5, 1) not in pool.slot
    walked, _ = routes.ways(shape, np.zeros(1, int), np.array([beyond]), np.array([(5, 1)]))
    assert np.isinf(walked[0]) and (5, 1) not in pool.slot


def test_a_route_into_a_walled_in_cell_crosses_the_fewest_shape_cells():
    shape = blueprint_of("#####\n#####\n#####\n#####\n#####")
    inside = {tuple(c) for c in shape.cells[0].tolist()}
    path = walk(shape, (8, 2), (2, 2))  # the centre of a 5 by 5 block, from the east
    assert sum(cell in inside for cell in path) == 3  # (4, 2), (3, 2) and the target
    assert len(path) - 1 == 6


def test_a_robot_far_off_the_map_has_no_route():
    shape = blueprint_of(U)
    _, found = routes.waypoints(
        shape, np.zeros(1, int), np.array([[60, 60]]), np.array([[0, 0]]), 3
    )
    assert not found[0]


def test_a_routes_cost_falls_by_one_a_step_along_it_and_counts_the_shape_cells_it_crosses():
    shape = blueprint_of(U)
    start, target = (3, 5), (1, 1)
    path = np.array(walk(shape, start, target))
    cost = routes.costs(shape, np.zeros(1, int), path[None], np.array([target]))[0]
    outside = cost[:-1]
    assert (np.diff(outside) == -1).all()
    assert cost[-1] < outside[-1]  # the last step, onto the target
    assert cost[-1] > len(path)  # a shape cell costs more than any walk round the shape
    off = routes.costs(shape, np.zeros(1, int), np.array([[[60, 60]]]), np.array([target]))
    assert np.isinf(off).all()


def test_route_fields_given_up_for_room_are_worked_out_again(monkeypatch):
    """With room for two fields, a robot's target whose field was given up gets it worked
    out again, and every robot reads its own target's field, whatever the order of use."""
    blueprint = blueprint_of(U)
    cells = int(routes._box(blueprint, 0)[1].prod())
    monkeypatch.setattr(routes, "FIELD_BYTES", 8 * cells * 2)
    pool = routes._Fields(blueprint, 0)
    a, b, c = (0, 0), (6, 3), (3, 3)
    for targets in ([a, b], [c], [a, c, b], [b], [c, a]):
        rows = pool.slots(np.array(targets))
        for target, row in zip(targets, rows.tolist(), strict=True):
            assert np.array_equal(pool.fields[row], routes._field(blueprint, 0, *target).ravel())
        assert len(pool.slot) == max(2, len(targets))


def test_where_the_system_maps_less_the_fields_keep_less_and_still_route(monkeypatch):
    """Under a limit on address space the whole room (512 MB a group) could not be mapped,
    and a two-group run that needs a few MB stopped with a MemoryError (a review at stop
    64): the room halves until the system maps it. A step that needs more fields than that
    still gets them, copying only the rows written."""
    blueprint = blueprint_of(U)
    cells = int(routes._box(blueprint, 0)[1].prod())
    real = routes.mmap.mmap

    def limited(fileno: int, length: int):
        if length > 8 * cells * 2:
            raise OSError(12, "Cannot allocate memory")
        return real(fileno, length)

    monkeypatch.setattr(routes.mmap, "mmap", limited)
    pool = routes._Fields(blueprint, 0)
    assert pool.room == 2
    targets = [(0, 0), (6, 3), (3, 3)]
    with pytest.raises(OSError):  # three at once need more than the system maps
        pool.slots(np.array(targets))
    monkeypatch.setattr(routes.mmap, "mmap", real)
    rows = pool.slots(np.array(targets))
    for target, row in zip(targets, rows.tolist(), strict=True):
        assert np.array_equal(pool.fields[row], routes._field(blueprint, 0, *target).ravel())


def test_a_new_shape_lets_the_old_shapes_fields_go():
    """A reshape hands robots a new blueprint: the old one's fields are not kept beside the new
    one's, however often a session reshapes."""
    old, new = blueprint_of(U), blueprint_of(U.replace("##...##\n#######", "#######\n#######"))
    kept = routes._fields(old, 0)
    kept.slots(np.array([(0, 0)]))
    assert routes._fields(old, 0) is kept
    routes._fields(new, 0).slots(np.array([(0, 0)]))
    assert routes._fields(old, 0) is not kept


def scipy_field(cost: np.ndarray, seeds: np.ndarray, start: int, columns: int) -> np.ndarray:
    """`routes._cheapest` worked out by scipy's Dijkstra, as the routes were before it: a
    graph of steps between side neighbours, none into or out of a seed, each paying the cost
    of the cell it leaves (from the start outward), plus the cost of the cell reached."""
    index = np.arange(len(cost)).reshape(-1, columns)
    edges = []
    for a, b in ((index[1:], index[:-1]), (index[:, 1:], index[:, :-1])):
        for one, other in ((a.ravel(), b.ravel()), (b.ravel(), a.ravel())):
            ok = ~seeds[one] & ~seeds[other]
            edges.append((one[ok], other[ok], cost[one[ok]]))
    one, other, weight = (np.concatenate(part) for part in zip(*edges, strict=True))
    graph = scipy.sparse.coo_matrix((weight, (one, other)), shape=(len(cost),) * 2).tocsr()
    return scipy.sparse.csgraph.dijkstra(graph, indices=start) + cost


@settings(max_examples=60, deadline=None)
@given(st.integers(3, 9), st.integers(3, 9), st.data())
def test_route_fields_are_what_dijkstras_method_gives_on_the_same_graph(rows, columns, data):
    """Random boxes of free, shape and seed cells, from any start (a seed too)."""
    kinds = data.draw(st.lists(st.sampled_from("..#s"), min_size=rows * columns,
                               max_size=rows * columns))  # fmt: skip
    seeds = np.array([kind == "s" for kind in kinds])
    cost = np.where(np.array([kind == "." for kind in kinds]), 1.0, float(rows * columns))
    start = data.draw(st.integers(0, rows * columns - 1))
    expected = scipy_field(cost, seeds, start, columns)
    field = np.full(rows * columns, -1.0)  # written over whole
    bordered = np.pad(cost.reshape(rows, columns), 1, constant_values=1.0).ravel()
    walls = np.pad(seeds.reshape(rows, columns), 1, constant_values=True).ravel()
    inside = (start // columns + 1) * (columns + 2) + start % columns + 1
    routes._cheapest(bordered, walls, inside, columns + 2, field)
    assert np.array_equal(field, expected)


@given(
    cells=st.lists(st.tuples(st.integers(-40, 40), st.integers(-40, 40)), max_size=30).map(
        lambda cells: np.array(cells, dtype=np.int64).reshape(-1, 2)
    )
)
def test_the_distinct_goal_cells_come_in_the_order_and_with_the_index_of_a_row_wise_unique(
    cells,
):
    """The fields are kept in the order of the distinct goals, so the shortcut through one
    integer a cell must give exactly what `np.unique(axis=0)` gives."""
    ends, which = routes._unique_cells(cells)
    expected, inverse = np.unique(cells, axis=0, return_inverse=True)
    assert np.array_equal(ends, expected) and ends.dtype == expected.dtype
    assert np.array_equal(which.reshape(-1), inverse.reshape(-1))


def test_a_route_round_walls_never_steps_on_them():
    """A robot routes round robots it sees but does not hear (a stalled one stands there for
    good): the way round the U to its floor's middle (below it, straight up through one
    shape cell) goes through the wall there first, and round it with the wall."""
    shape = blueprint_of(U)
    start, target = (3, 5), (3, 3)  # below the U's floor, its middle cell just above
    wall = np.array([(3, 4)])
    straight, _ = routes.waypoints(
        shape, np.zeros(1, int), np.array([start]), np.array([target]), 1
    )
    assert tuple(straight[0]) == (3, 4)
    at, path = np.array(start), [start]
    for _ in range(20):
        at, found = routes.waypoint_round(shape, 0, at, np.array(target), 1, wall)
        assert found
        path.append(tuple(int(v) for v in at))
        if path[-1] == target:
            break
    assert path[-1] == target
    assert (3, 4) not in path
