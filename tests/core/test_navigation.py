"""The paper's navigator: its distance fields are the shortest paths on the grid."""

from __future__ import annotations

import numpy as np
import scipy
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from swarmshape.core.navigation import FieldPlanner


def graph_steps(goal: np.ndarray, passable: np.ndarray) -> np.ndarray:
    """The oracle: unweighted shortest paths to `goal` in the graph whose edges join side
    neighbours that are both passable, by scipy's graph search."""
    ids = np.arange(passable.size).reshape(passable.shape)
    pairs = [(ids[:-1], ids[1:]), (ids[:, :-1], ids[:, 1:])]
    tail = np.concatenate([a.ravel() for a, _ in pairs])
    head = np.concatenate([b.ravel() for _, b in pairs])
    both = passable.ravel()[tail] & passable.ravel()[head]
    graph = scipy.sparse.csr_matrix(
        (np.ones(both.sum()), (tail[both], head[both])), shape=(passable.size, passable.size)
    )
    steps = scipy.sparse.csgraph.shortest_path(
        graph, directed=False, unweighted=True, indices=ids[goal[0], goal[1]]
    )
    return steps.reshape(passable.shape)


@settings(deadline=None)  # the first example compiles the kernel
@given(
    hnp.arrays(bool, st.tuples(st.integers(1, 24), st.integers(1, 24))),
    st.integers(0, 10**6),
    st.integers(0, 10**6),
    st.booleans(),
)
def test_a_field_is_the_shortest_path_to_its_goal(passable, x, y, strided):
    """Of every cell, whatever blocks the way (the goal too: then only it is 0), and of a
    window cut from a larger arena as the planner searches one."""
    goal = np.array([x % passable.shape[0], y % passable.shape[1]])
    if strided:  # a view into a larger array, as the planner's window is
        arena = np.ones((passable.shape[0] + 2, 2 * passable.shape[1]), dtype=bool)
        arena[1:-1, ::2] = passable
        passable = arena[1:-1, ::2]
    assert np.array_equal(FieldPlanner.field(goal, passable), graph_steps(goal, passable))
