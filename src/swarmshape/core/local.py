"""Local programs: one program runs on every robot and sees only what that robot can sense.

A `Program` is the second plug-in kind beside central strategies. Each step it is given a
`Perception` (its neighbours within the sensing radius, their last messages, its odometry and
the shape's bitmap in its seed frame) and its own `Memory` (arrays it declared), and returns
every robot's move (0 stay, or a direction index of `swarmshape.core.motion.STEPS`, in seed-frame
axes) and the message it broadcasts. It never receives the `Swarm`, so it cannot cheat.

`LocalControl` is the swarm's driver for it: it builds the perception, turns moves into claims
(a move into a taken cell simply does not happen, and the robot's odometry shows it next step),
keeps the broadcasts, and marks a target filled while a robot of its group rests on it.

Faults: a removed robot is gone from every perception (it neither senses nor is sensed); a
stalled one is still sensed where it stands, but it is silent (its messages are never heard)
and does not act. Arrays keep one row per robot throughout, so a program's memory stays valid.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from swarmshape.core.motion import RIGHT, STEPS
from swarmshape.core.perception import (
    Blueprint,
    Perception,
    neighbours,
    quarter_turns,
    turn,
)
from swarmshape.core.plugin import Plugin
from swarmshape.core.snapshot import Snapshot
from swarmshape.core.states import STALLED
from swarmshape.core.swarm import Shown
from swarmshape.errors import InputError

if TYPE_CHECKING:
    from swarmshape.core.swarm import Swarm

QUIET = 200
"""Steps without any robot moving or any broadcast changing after which a local run has come
to rest for good (a program that builds an imperfect shape stops there)."""


@dataclass(frozen=True)
class Slot:
    """One array of per-robot memory a program declares: its dtype, starting value, and width
    (None: one value per robot; k: ``(n, k)``), and whether a program added it after runs were
    saved without it (`added`: a state file that lacks it restores it as a new robot's; one
    that lacks any other slot is damaged)."""

    dtype: type
    fill: Any = 0
    width: int | None = None
    added: bool = False


class Schema:
    """What a program broadcasts, as named fields declared once, each one or more integers
    wide: ``Schema(state=1, position=2)``. `pack` lays a message out from its fields by name,
    `read` gives the fields of messages heard (views, a field of width 1 as a vector)."""

    def __init__(self, **widths: int) -> None:
        self.widths = widths
        ends = np.cumsum(list(widths.values()))
        self.slices = {
            name: slice(int(end) - width, int(end))
            for (name, width), end in zip(widths.items(), ends, strict=True)
        }

    def __len__(self) -> int:
        return sum(self.widths.values())

    def pack(self, **fields: np.ndarray) -> np.ndarray:
        """A message per robot ``(n, len(self))`` from every field, by name."""
        if set(fields) != set(self.widths):
            raise TypeError(f"a message has exactly the fields {', '.join(self.widths)}")
        n = len(next(iter(fields.values())))
        columns = [np.asarray(fields[name]).reshape(n, w) for name, w in self.widths.items()]
        return np.concatenate(columns, axis=1).astype(np.int64, copy=False)

    def read(self, message: np.ndarray) -> SimpleNamespace:
        """The fields of messages ``(m, len(self))``, by name."""
        return SimpleNamespace(
            **{
                name: message[:, part.start] if self.widths[name] == 1 else message[:, part]
                for name, part in self.slices.items()
            }
        )


class Memory:
    """A program's per-robot arrays, by the names it declared (``memory.goal`` and so on)."""

    def __init__(self, slots: dict[str, Slot], robots: int) -> None:
        self.slots = slots
        self.robots = robots
        for name, slot in slots.items():
            shape = (robots,) if slot.width is None else (robots, slot.width)
            setattr(self, name, np.full(shape, slot.fill, dtype=slot.dtype))

    if TYPE_CHECKING:  # the slots a program declared, set in __init__ and `restore`

        def __getattr__(self, name: str) -> np.ndarray: ...

    def __len__(self) -> int:
        return self.robots

    def arrays(self) -> dict[str, np.ndarray]:
        return {name: getattr(self, name) for name in self.slots}


class ProgramError(InputError):
    """A program returned something the core cannot act on; the message says what."""


class Program(Plugin):
    """Base class of local programs. Subclass it, give it a ``name``, a one-line
    ``description``, the ``message_size`` (ints per broadcast), the ``memory`` it keeps, and
    write `act`. Randomness comes only from the `rng` passed in. A broadcast field added later
    goes at the end: a run saved before restores it as 0."""

    kind: ClassVar[str] = "local"
    message_size: ClassVar[int] = 0
    memory: ClassVar[dict[str, Slot]] = {}
    states: ClassVar[tuple[str, ...]] = ()
    """Names of the values of ``memory.state``, if the program keeps one (the viewer colours
    robots by it)."""
    shown: ClassVar[str | None] = None
    """The integer memory slot the viewer can print on each robot (a gradient, a hop count), so
    a program's field can be seen without a debugger; values 0 to 998 are printed, others
    (999 or more, negative) mean "unknown" and are left blank."""

    def act(
        self, sense: Perception, memory: Memory, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        """Every robot's move ``(n,)`` and broadcast ``(n, message_size)``."""
        raise NotImplementedError(f"program {self.name!r} must define act(sense, memory, rng)")

    def estimate(self, memory: Memory) -> tuple[np.ndarray, np.ndarray] | None:
        """Robots that believe they know where they are, and their frame cells ``(n, 2)``, for
        the localisation error in the metrics. Default: the program does not localise."""
        return None

    def finished(self, memory: Memory) -> np.ndarray | None:
        """Robots that are done for good and never move again: settled, they fill the targets
        they rest on (``swarmshape check`` sees that they stay). Default: None, the program does
        not say; then a target is filled while a robot of its group rests on it, unsettled."""
        return None

    def drive(self, swarm: Swarm) -> LocalControl:
        return LocalControl(swarm, self)


def _link_up(a: np.ndarray, b: np.ndarray, salt: int, loss: float) -> np.ndarray:
    """Whether the link between robots `a` and `b` works this step: the same answer from both
    ends, drawn by hashing the pair with a salt from the run's generator (splitmix64)."""
    with np.errstate(over="ignore"):
        x = np.minimum(a, b).astype(np.uint64) * np.uint64(0x9E3779B97F4A7C15)
        x ^= np.maximum(a, b).astype(np.uint64) + np.uint64(salt)
        x ^= x >> np.uint64(30)
        x *= np.uint64(0xBF58476D1CE4E5B9)
        x ^= x >> np.uint64(27)
        x *= np.uint64(0x94D049BB133111EB)
        x ^= x >> np.uint64(31)
    return (x >> np.uint64(11)).astype(np.float64) / float(1 << 53) >= loss


class LocalControl:
    """Runs one `Program` on every robot of a swarm (the `Driver` of local programs)."""

    def __init__(self, swarm: Swarm, program: Program) -> None:
        self.swarm = swarm
        self.program = program
        n = len(swarm.cell)
        self.memory = Memory(program.memory, n)
        self.broadcast = np.zeros((n, program.message_size), dtype=np.int64)
        self.last_cell = swarm.cell.copy()
        self.reach = swarm.params.senses.reach()
        self.sent = 0
        self.lost = 0
        self.refused = 0
        """Moves asked for that claimed no cell: into a taken cell, or lost to another robot
        claiming the same one (the collisions the lattice refused)."""
        self.quiet_steps = 0
        self.links: tuple[np.ndarray, np.ndarray] | None = None
        """The last perception's heard links, ``(owner, other)`` (other ``>= n``: a seed), kept
        for the viewer to draw: perceiving again would draw from the run's generator."""
        self.number = np.zeros(n, dtype=np.int64)
        for group in range(len(swarm.world.groups)):
            mine = swarm.group == group
            self.number[mine] = np.arange(mine.sum())

    @property
    def messages_sent(self) -> int:
        return self.sent

    @property
    def quiet(self) -> bool:
        return self.quiet_steps >= QUIET

    def figures(self) -> dict[str, Any]:
        """Messages lost, and how far robots' own position estimates are off (cells)."""
        figures: dict[str, Any] = {"messages_lost": self.lost}
        believes = self._believes()
        if believes is not None and believes[0].any():
            localised, cells = believes
            error = np.hypot(*(cells[localised] - self.swarm.cell[localised]).T)
            figures["localisation_error_mean"] = round(float(error.mean()), 4)
            figures["localisation_error_max"] = round(float(error.max()), 4)
            figures["localised"] = int(localised.sum())
        return figures

    def shown(self) -> Shown:
        program, memory = self.program, self.memory
        return Shown(
            plugin=program.name,
            states=program.states,
            state=np.asarray(memory.state, dtype=np.int64) if program.states else None,
            values_of=program.shown,
            values=None if program.shown is None else np.asarray(getattr(memory, program.shown)),
            links=self.links,
            believes=self._believes(),
        )

    def _believes(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Which present robots know where they are, and the world cell each believes it is on
        (None: the program does not localise)."""
        estimate = self.program.estimate(self.memory)
        if estimate is None:
            return None
        localised, frame = estimate
        cells = np.zeros_like(self.swarm.cell)
        for group, g in enumerate(self.swarm.world.groups):
            mine = self.swarm.group == group
            cells[mine] = g.pose.to_world(np.asarray(frame)[mine])
        return np.asarray(localised, dtype=bool) & self.swarm.present, cells

    def index_world(self) -> None:
        world = self.swarm.world
        self.blueprint = Blueprint.of([g.frame_cells for g in world.groups])
        self.turns = quarter_turns([g.pose for g in world.groups])
        self.seed_group = np.repeat(
            np.arange(len(world.groups)), [len(g.seeds) for g in world.groups]
        )
        frames = [g.pose.to_frame(g.seeds) for g in world.groups]
        self.seed_frame = np.concatenate(frames) if frames else np.zeros((0, 2), dtype=np.int64)
        self.frame_directions = _turned_directions()

    def start(self) -> None:
        self._note_filled()

    def decide(self) -> None:
        swarm = self.swarm
        sense = self.perceive()
        moves, messages = self.program.act(sense, self.memory, swarm.rng)
        moves, messages = self._checked(moves, messages)
        changed = not np.array_equal(messages, self.broadcast)
        self.broadcast = messages
        self.sent += len(messages) if self.program.message_size else 0
        # at rest a robot may start any way; under way it may only go on straight ahead
        going = (moves > 0) & (sense.ready | (sense.cruising & (moves == sense.heading)))
        robots = np.flatnonzero(going)
        directions = self.frame_directions[self.turns[swarm.group[robots]], moves[robots]]
        ahead = swarm.ahead[robots, None]
        keys = swarm.lattice.key(swarm.cell[robots] + STEPS[swarm.direction[robots]] * ahead)
        entering = keys + swarm.lattice.offsets[directions]
        allowed = swarm.enterable(entering, swarm.group[robots], directions)
        won = swarm.claim(robots[allowed], directions[allowed], keys[allowed])
        self.refused += len(robots) - len(won)
        still = not (swarm.ahead > 0).any() and not changed
        self.quiet_steps = self.quiet_steps + 1 if still else 0

    def perceive(self) -> Perception:
        """What every robot senses now. (1) `np.take` gathers rows many times faster than
        indexing ``array[rows]`` of a narrow 2-D array (numpy 2.4: 7 us against 190 us for
        5,000 rows of two). (2) A program reads the messages a field at a time; laid out
        row by row, every field read strides over all the others (local-swap at 10,000 robots:
        240 to 255 ms a step, against 161 ms field by field)."""
        swarm = self.swarm
        n, senses = len(swarm.cell), swarm.params.senses
        seeds = swarm.world.seeds
        present = swarm.present
        start, owner, other = neighbours(swarm.cell, seeds, swarm.world.size, self.reach, present)
        seed = other >= n
        centres = np.concatenate([swarm.positions(), seeds + 0.5])
        offset = np.take(centres, other, axis=0) - np.take(centres, owner, axis=0)  # (1)
        if senses.distance_noise > 0:
            offset = offset + swarm.rng.normal(0.0, senses.distance_noise, offset.shape)
        group = np.concatenate([swarm.group, self.seed_group])
        if self.turns.any():  # some seed frame is turned from the world's axes
            offset = turn(offset, (-self.turns[group[owner]]) % 4)
        heard = np.ones(len(owner), dtype=bool)
        if senses.msg_loss > 0:
            salt = int(swarm.rng.integers(2**62))
            heard = _link_up(owner, other, salt, senses.msg_loss)
        self.lost += int((~heard & ~seed).sum())
        silent = np.concatenate([swarm.state == STALLED, np.zeros(len(seeds), dtype=bool)])
        heard &= ~silent[other]
        self.links = (owner[heard], other[heard])
        # gather every entry's row, seeds' and robots' alike, then blank the few unheard (1)
        unheard = np.flatnonzero(~heard)
        said = np.zeros((len(seeds), self.program.message_size), dtype=np.int64)
        # column by column, so each field of `message` lies contiguous (Fortran order) (2)
        message = np.take(np.concatenate([self.broadcast, said]).T, other, axis=1).T
        message[unheard] = 0
        frames = np.concatenate([np.zeros((n, 2), dtype=np.int64), self.seed_frame])
        seed_frame = np.take(frames, other, axis=0)
        seed_frame[unheard] = 0
        back = (-self.turns[swarm.group]) % 4
        moved = turn(swarm.cell - self.last_cell, back)
        self.last_cell = swarm.cell.copy()
        acting = present & (swarm.state != STALLED)
        return Perception(
            number=self.number,
            group=swarm.group,
            ready=(swarm.ahead == 0) & acting,
            heading=np.where(swarm.ahead > 0, self.frame_directions[back, swarm.direction], 0),
            cruising=(swarm.ahead == 1) & acting,
            progress=np.where(swarm.ahead > 0, swarm.offset, 0.0),
            moved=moved,
            start=start,
            owner=owner,
            offset=offset,
            seed=seed,
            kin=group[other] == group[owner],
            heard=heard,
            message=message,
            seed_frame=seed_frame,
            blueprint=self.blueprint,
            step=swarm.step_count,
            radius=senses.radius,
        )

    def _checked(self, moves: Any, messages: Any) -> tuple[np.ndarray, np.ndarray]:
        n, size, name = len(self.swarm.cell), self.program.message_size, self.program.name
        moves, messages = np.asarray(moves), np.asarray(messages)
        if moves.shape != (n,) or not np.issubdtype(moves.dtype, np.integer):
            raise ProgramError(f"program {name!r}: act must return {n} integer moves")
        if ((moves < 0) | (moves >= len(STEPS))).any():
            raise ProgramError(f"program {name!r}: a move is not 0 (stay) to 4 (a direction)")
        if messages.shape != (n, size) or not np.issubdtype(messages.dtype, np.integer):
            raise ProgramError(f"program {name!r}: act must return messages of shape ({n}, {size})")
        return moves.astype(np.int64), messages.astype(np.int64)

    def arrived(self) -> None:
        self._note_filled()

    def _note_filled(self) -> None:
        """Robots the program calls finished that rest on a target of their group are settled
        (a shape change can leave a finished robot off the new shape; it is not settled
        there); the swarm fills the targets they rest on. A program that does not say which
        are finished has a target filled while a robot of its group rests on it, unsettled."""
        swarm = self.swarm
        at = swarm.target_at[swarm.cell[:, 0], swarm.cell[:, 1]]
        on_target = (at >= 0) & (swarm.world.target_group[np.maximum(at, 0)] == swarm.group)
        resting = (swarm.ahead == 0) & on_target
        said = self.program.finished(self.memory)
        if said is None:
            swarm.settle_exactly(np.zeros_like(resting), filling=resting)
        else:
            swarm.settle_exactly(said & resting)

    def completed(self, group: int) -> None:
        """Nothing to hand over: the program keeps running as it is."""

    def reshaped(self, renumber: np.ndarray) -> None:
        """The robots learn the new bitmap at `index_world`; what they do with it is theirs."""

    def hand_out(self, group: int) -> None:
        self._note_filled()

    def removed(self, robots: np.ndarray, stalled: bool) -> None:
        """Fallen robots go silent; the others notice only through what they sense, and regrow
        the gaps as their program does. The run is not at rest any more."""
        self.broadcast[robots] = 0
        self.quiet_steps = 0
        self._note_filled()

    def snapshot(self) -> dict[str, Any]:
        values = {f"memory.{name}": array for name, array in self.memory.arrays().items()}
        return values | {
            "broadcast": self.broadcast,
            "last_cell": self.last_cell,
            "sent": self.sent,
            "lost": self.lost,
            "refused": self.refused,
            "quiet_steps": self.quiet_steps,
        }

    def restore(self, saved: Snapshot) -> None:
        n = len(self.swarm.cell)
        for name, slot in self.program.memory.items():
            if slot.added and not saved.has(f"memory.{name}"):  # saved before: as new
                continue
            shape = (n,) if slot.width is None else (n, slot.width)
            value = saved.array(f"memory.{name}", slot.dtype, shape, finite=None)
            setattr(self.memory, name, value)
        broadcast = saved.array("broadcast", np.int64, (n, None))
        width = self.program.message_size
        if broadcast.shape[1] > width:
            raise saved.error("broadcast", f"has {broadcast.shape[1]} fields, expected {width}")
        # fields are only appended: one added since the file was saved reads 0 (see `Program`)
        self.broadcast = np.pad(broadcast, ((0, 0), (0, width - broadcast.shape[1])))
        self.last_cell = saved.array("last_cell", np.int64, (n, 2))
        self.sent = saved.integer("sent", 0)
        self.lost = saved.integer("lost", 0)
        # counted since state version 4 began: older files of that version lack it
        self.refused = saved.integer("refused", 0) if saved.has("refused") else 0
        self.quiet_steps = saved.integer("quiet_steps", 0)


def _turned_directions() -> np.ndarray:
    """``[turns, direction]``: the `STEPS` index of a direction turned by quarter turns."""
    table = np.zeros((4, len(STEPS)), dtype=np.int64)
    table[0] = np.arange(len(STEPS))
    for turns in range(1, 4):
        table[turns] = RIGHT[table[turns - 1]]
    return table
