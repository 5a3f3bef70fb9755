"""Click-to-paint shape editor: pure grid operations (`Canvas`) and their mouse and keys (`Editor`).

The canvas is the arena itself, cell for cell ``[x, y]``, so a user paints right where the swarm
will form the shape; the seed frame is drawn over it and can be dragged or turned, taking the
drawing along. `Editor.shape` turns the painting into a shape in the seed frame.

Saving never replaces a user's file unasked: only the editor's own PNGs (their text chunk says
so, see `is_drawing`) are saved over without a question; anything else, and any existing file
under a typed name, needs a yes in the window, and autosaves always get a fresh name, beside
the user's file or in their data folder, never among the shipped shapes or in the package.
"""

from __future__ import annotations

import dataclasses
import os
import sys
import tempfile
from collections import deque
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pygame
import scipy
from PIL import Image

from swarmshape.config import bundled_shapes
from swarmshape.core.shape import SEED_CELLS, Pose, Shape
from swarmshape.core.world import World
from swarmshape.errors import InputError
from swarmshape.io.bitmap import EDITOR_TAG, save_grid

HISTORY = 200
"""Undo steps kept."""

MAX_BRUSH = 9
PAINT = (240, 170, 40)
CURSOR = (20, 20, 20)
HELP_LINES = (
    "left paint   right erase   [ ] brush   f fill   c clear",
    "Ctrl+Z undo   Ctrl+Y redo   t turn the seeds",
    "drag a green seed: the frame and drawing move",
    "PgUp/PgDn grid size (before a run)",
    "Ctrl+S save   Ctrl+Shift+S save as",
    "Enter or e: hand the shape to the swarm",
    "h hide this help   q or Esc quit",
)


class Canvas:
    """A boolean grid ``[x, y]`` with brush strokes, flood fill, clear and undo/redo.

    Cells in `blocked` (the seeds, other groups' shapes) are never painted.
    """

    def __init__(self, size: tuple[int, int], cells: np.ndarray | None = None) -> None:
        self.grid = np.zeros(size, dtype=bool)
        self.blocked = np.zeros(size, dtype=bool)
        if cells is not None and len(cells):
            self.grid[cells[:, 0], cells[:, 1]] = True
        self._undo: deque[np.ndarray] = deque(maxlen=HISTORY)
        self._redo: list[np.ndarray] = []

    @property
    def size(self) -> tuple[int, int]:
        return self.grid.shape

    @property
    def cells(self) -> np.ndarray:
        return np.argwhere(self.grid)

    def checkpoint(self) -> None:
        """Remember the grid as it is, as one undo step (call before each edit)."""
        self._undo.append(self.grid.copy())
        self._redo.clear()

    def undo(self) -> bool:
        if not self._undo:
            return False
        self._redo.append(self.grid)
        self.grid = self._undo.pop()
        return True

    def redo(self) -> bool:
        if not self._redo:
            return False
        self._undo.append(self.grid)
        self.grid = self._redo.pop()
        return True

    def stroke(self, start: tuple[int, int], end: tuple[int, int], brush: int, ink: bool) -> None:
        """Paint (or erase) every cell a square brush covers on its way from start to end."""
        steps = max(abs(end[0] - start[0]), abs(end[1] - start[1])) + 1
        xs = np.rint(np.linspace(start[0], end[0], steps)).astype(int)
        ys = np.rint(np.linspace(start[1], end[1], steps)).astype(int)
        offsets = np.arange(brush) - (brush - 1) // 2
        dx, dy = (grid.ravel() for grid in np.meshgrid(offsets, offsets, indexing="ij"))
        xs = (xs[:, None] + dx[None, :]).ravel()
        ys = (ys[:, None] + dy[None, :]).ravel()
        inside = (xs >= 0) & (xs < self.size[0]) & (ys >= 0) & (ys < self.size[1])
        xs, ys = xs[inside], ys[inside]
        free = ~self.blocked[xs, ys]
        self.grid[xs[free], ys[free]] = ink

    def fill(self, cell: tuple[int, int]) -> None:
        """Flip the region of equal cells around `cell` (4-connected): ink becomes empty, and
        an empty region becomes ink."""
        same = self.grid == self.grid[cell]
        labels, _ = scipy.ndimage.label(same & ~self.blocked)
        if labels[cell]:
            self.grid[labels == labels[cell]] = not self.grid[cell]

    def clear(self) -> None:
        self.grid[...] = False

    def resize(self, size: tuple[int, int]) -> None:
        """A larger or smaller grid that keeps what fits, anchored top-left."""
        grown = np.zeros(size, dtype=bool)
        width, height = min(size[0], self.size[0]), min(size[1], self.size[1])
        grown[:width, :height] = self.grid[:width, :height]
        self.grid = grown
        self.blocked = np.zeros(size, dtype=bool)

    def remap(self, move: Callable[[np.ndarray], np.ndarray]) -> bool:
        """Move every painted cell with `move`, unless one would leave the grid or land on a
        blocked cell; return whether it moved."""
        moved = move(self.cells)
        inside = (moved >= 0).all(axis=1) & (moved < np.array(self.size)).all(axis=1)
        if not inside.all() or self.blocked[moved[:, 0], moved[:, 1]].any():
            return False
        self.grid = np.zeros(self.size, dtype=bool)
        self.grid[moved[:, 0], moved[:, 1]] = True
        return True


def is_drawing(path: Path) -> bool:
    """Whether `path` is a PNG the editor wrote: the only files saved over without asking."""
    try:
        with Image.open(path) as image:
            return image.format == "PNG" and image.info.get(EDITOR_TAG) == "1"
    except (OSError, ValueError, Image.DecompressionBombError):
        return False


def data_folder() -> Path:
    """The user's own folder for swarmshape's data: ``$XDG_DATA_HOME/swarmshape`` (by default
    ``~/.local/share/swarmshape``) on Linux and other Unixes, ``~/Library/Application
    Support/swarmshape`` on macOS, ``%LOCALAPPDATA%\\swarmshape`` on Windows."""
    home = Path.home()
    if sys.platform == "win32":
        base = os.environ.get("LOCALAPPDATA") or home / "AppData" / "Local"
    elif sys.platform == "darwin":
        base = home / "Library" / "Application Support"
    else:
        base = os.environ.get("XDG_DATA_HOME", "")
        base = base if Path(base).is_absolute() else home / ".local" / "share"  # as XDG says
    return Path(base) / "swarmshape"


def shipped(path: Path) -> bool:
    """Whether `path` is one of the shapes that come with swarmshape, or inside the package:
    places that an update replaces, and no place for a user's work."""
    where = Path(os.path.realpath(path))
    package = Path(os.path.realpath(__file__)).parents[1]
    return any(where.is_relative_to(os.path.realpath(p)) for p in (bundled_shapes(), package))


def fresh_path(path: Path) -> Path:
    """`path` if nothing is there, else the first free NAME-2.png, NAME-3.png, ..."""
    candidate, number = path, 1
    while candidate.exists():
        number += 1
        candidate = path.with_name(f"{path.stem}-{number}{path.suffix}")
    return candidate


class Editor:
    """Mouse and keys on a `Canvas`, the seed pose, and saving; drawn over the arena.

    `path` is the file being edited; Ctrl+S writes straight to it only when it is absent or
    already a drawing, and otherwise offers a fresh ``NAME.shape.png`` beside it.
    """

    def __init__(
        self,
        canvas: Canvas,
        pose: Pose,
        *,
        path: Path | None,
        agents: int | None,
        resizable: bool,
        fixed: np.ndarray,
    ) -> None:
        self.canvas = canvas
        self.pose = pose
        self.source = path
        """The file opened, which names the suggestions; it may be a photo never to replace."""
        ours = path is None or (path.suffix.lower() == ".png" and not path.exists())
        self.path = path if ours or is_drawing(path) else None
        """Where Ctrl+S saves without asking for a name."""
        self.agents = agents
        self.resizable = resizable
        self.fixed = fixed
        """Cells of other groups (shapes and seeds) that this group must keep off."""
        self.brush = 1
        self.cursor: tuple[int, int] | None = None
        self.dirty = False
        self.naming: str | None = None
        """The text typed into "save as", while it is open."""
        self.confirming: Path | None = None
        """An existing file waiting for a yes before it is replaced."""
        self._question = ""
        """What the window asks about `confirming`."""
        self.show_help = False
        self.message = ""
        if path is not None and self.path is None:
            why = "is not a swarmshape drawing" if path.exists() else "is not a PNG name"
            self.message = f"{path.name} {why}: Ctrl+S saves as {self._suggestion().name}"
        self._ink: bool | None = None
        self._last: tuple[int, int] | None = None
        self._dragging_from: tuple[int, int] | None = None
        self._block_seeds()

    # --- reading ------------------------------------------------------------------------

    @property
    def seeds(self) -> np.ndarray:
        return self.pose.to_world(SEED_CELLS)

    def backdrop(self, world: World, group: int) -> World:
        """`world` as the editor shows it: the canvas's size, this group's seeds where they are
        now and none of its old targets (the painting is drawn over it), and the other groups
        only while they are kept out of (a resized grid drops them)."""
        empty = np.zeros((0, 2), dtype=np.int64)
        groups = []
        for index, placed in enumerate(world.groups):
            if index == group:
                placed = dataclasses.replace(
                    placed, pose=self.pose, targets=empty, seeds=self.seeds
                )
            elif not len(self.fixed):
                placed = dataclasses.replace(placed, targets=empty, seeds=empty)
            groups.append(placed)
        return World(self.canvas.size, tuple(groups), world.name)

    def shape(self) -> Shape | None:
        """The painting as a shape in the seed frame (None while nothing is painted)."""
        cells = self.canvas.cells
        return Shape.from_cells(self.pose.to_frame(cells)) if len(cells) else None

    def status(self) -> str:
        width, height = self.canvas.size
        count = int(self.canvas.grid.sum())
        agents = "" if self.agents is None else f"   agents {self.agents}"
        if self.agents is not None and count > self.agents:
            agents += f" (short by {count - self.agents})"
        shown = self.path or self.source
        name = shown.name if shown else "untitled"
        return (
            f"EDIT {name}{'*' if self.dirty else ''}   grid {width}x{height}   "
            f"brush {self.brush}   cells {count}{agents}"
        )

    # --- events -------------------------------------------------------------------------

    def prompt(self) -> str | None:
        """The question the window shows while a save waits for the user, if one does."""
        if self.confirming is not None:
            return self._question
        if self.naming is not None:
            folder = self._folder()
            where = "" if folder == Path() else f"   in {folder}"
            return f"save as: {self.naming}_{where}   (Enter saves, Esc cancels)"
        return None

    def handle(self, event: pygame.event.Event, cell_at: Callable) -> str | None:
        """Apply one event; return "apply" when the user hands the shape over and "quit" when
        they leave (q and Esc, except while a name is typed or a question waits)."""
        if self.confirming is not None:
            return self._confirm(event)
        if self.naming is not None:
            return self._type_name(event)
        if event.type == pygame.MOUSEMOTION:
            self.cursor = cell_at(event.pos)
            if self.cursor is not None:
                self._drag_to(self.cursor)
        elif event.type == pygame.MOUSEBUTTONDOWN and event.button in (1, 3):
            self.cursor = cell_at(event.pos)
            if self.cursor is not None:
                self._press(self.cursor, ink=event.button == 1)
        elif event.type == pygame.MOUSEBUTTONUP and event.button in (1, 3):
            self._ink = self._last = self._dragging_from = None
        elif event.type == pygame.KEYDOWN:
            return self._key(event)
        return None

    def _press(self, cell: tuple[int, int], *, ink: bool) -> None:
        if ink and any(tuple(seed) == cell for seed in self.seeds.tolist()):
            self._dragging_from = cell
            return
        self.canvas.checkpoint()
        self._ink, self._last = ink, cell
        self._paint(cell)

    def _drag_to(self, cell: tuple[int, int]) -> None:
        if self._dragging_from is not None:
            dx, dy = cell[0] - self._dragging_from[0], cell[1] - self._dragging_from[1]
            if dx or dy:
                self._move_frame(Pose(self.pose.x + dx, self.pose.y + dy, self.pose.rotation))
                self._dragging_from = cell
        elif self._ink is not None:
            self._paint(cell)

    def _paint(self, cell: tuple[int, int]) -> None:
        self.canvas.stroke(self._last or cell, cell, self.brush, bool(self._ink))
        self._last = cell
        self.dirty = True

    def _key(self, event: pygame.event.Event) -> str | None:
        key, ctrl, shift = event.key, event.mod & pygame.KMOD_CTRL, event.mod & pygame.KMOD_SHIFT
        if key in (pygame.K_RETURN, pygame.K_KP_ENTER, pygame.K_e):
            return "apply"
        if key in (pygame.K_q, pygame.K_ESCAPE):
            return "quit"
        if ctrl and key == pygame.K_z:
            self.dirty |= self.canvas.undo()
        elif ctrl and key == pygame.K_y:
            self.dirty |= self.canvas.redo()
        elif ctrl and key == pygame.K_s:
            if shift or self.path is None:
                self.naming = (self.path or self._suggestion()).name
            else:
                self._save_asking(self.path, typed=False)
        elif key == pygame.K_LEFTBRACKET:
            self.brush = max(1, self.brush - 1)
        elif key == pygame.K_RIGHTBRACKET:
            self.brush = min(MAX_BRUSH, self.brush + 1)
        elif key == pygame.K_c:
            self._edit(self.canvas.clear)
        elif key == pygame.K_f and self.cursor is not None:
            self._edit(lambda: self.canvas.fill(self.cursor))
        elif key == pygame.K_t:
            self._move_frame(Pose(self.pose.x, self.pose.y, (self.pose.rotation + 90) % 360))
        elif key in (pygame.K_PAGEUP, pygame.K_PAGEDOWN):
            self._resize(4 if key == pygame.K_PAGEUP else -4)
        elif key == pygame.K_h:
            self.show_help = not self.show_help
        return None

    def _edit(self, change: Callable[[], None]) -> None:
        self.canvas.checkpoint()
        change()
        self.dirty = True

    def _move_frame(self, pose: Pose) -> None:
        """Move or turn the seed frame; the drawing goes along with it."""
        seeds = pose.to_world(SEED_CELLS)
        width, height = self.canvas.size
        if (seeds < 0).any() or (seeds >= np.array([width, height])).any():
            self.message = "the seeds must stay inside the grid"
            return
        old = self.pose
        self.canvas.checkpoint()
        self.canvas.blocked[...] = False  # the seeds' own cells move along
        moved = self.canvas.remap(lambda cells: pose.to_world(old.to_frame(cells)))
        if moved:
            self.pose = pose
            self.dirty = True
        self.message = "" if moved else "no room there for the drawing; move the seeds first"
        self._block_seeds()

    def _resize(self, by: int) -> None:
        """Grow or shrink the grid, anchored top-left; never cut painted cells or seeds off."""
        if not self.resizable:
            self.message = "the grid size is fixed while a swarm runs on it"
            return
        width, height = self.canvas.size
        size = (max(8, width + by), max(6, height + round(by * height / width)))
        if size == self.canvas.size:
            self.message = f"the grid is as small as it gets, {width}x{height}"
            return
        cut = (self.canvas.cells >= np.array(size)).any(axis=1).sum()
        if (self.seeds >= np.array(size)).any():
            self.message = f"no room for the seeds in {size[0]}x{size[1]}; drag them in first"
            return
        if cut:
            self.message = (
                f"shrinking to {size[0]}x{size[1]} would cut off {cut} painted cells; "
                "erase or move them first"
            )
            return
        self.message = ""
        self._edit(lambda: self.canvas.resize(size))
        self.fixed = np.zeros((0, 2), dtype=np.int64)
        self._block_seeds()

    def _block_seeds(self) -> None:
        self.canvas.blocked[...] = False
        for cells in (self.seeds, self.fixed):
            inside = (cells >= 0).all(axis=1) & (cells < np.array(self.canvas.size)).all(axis=1)
            self.canvas.blocked[cells[inside, 0], cells[inside, 1]] = True
        self.canvas.grid &= ~self.canvas.blocked

    def _type_name(self, event: pygame.event.Event) -> None:
        """The in-window text field of "save as"; names are taken in the drawing's folder."""
        if event.type != pygame.KEYDOWN:
            return
        if event.key == pygame.K_ESCAPE:
            self.naming = None
        elif event.key in (pygame.K_RETURN, pygame.K_KP_ENTER):
            name, self.naming = self.naming.strip(), None
            if name:
                path = self._folder() / (name if name.lower().endswith(".png") else f"{name}.png")
                self._save_asking(path, typed=True)
        elif event.key == pygame.K_BACKSPACE:
            self.naming = self.naming[:-1]
        elif event.unicode and event.unicode.isprintable():
            self.naming += event.unicode

    def _confirm(self, event: pygame.event.Event) -> None:
        """y or Enter replaces the file waiting for an answer; n or Esc keeps it."""
        if event.type != pygame.KEYDOWN:
            return
        path = self.confirming
        if event.key in (pygame.K_y, pygame.K_RETURN, pygame.K_KP_ENTER):
            self.confirming = None
            self.save(path)
        elif event.key in (pygame.K_n, pygame.K_ESCAPE):
            self.confirming = None
            self.message = f"not saved: {path.name} kept as it was"

    # --- files --------------------------------------------------------------------------

    def _folder(self) -> Path:
        shown = self.path or self.source
        return shown.parent if shown else Path()

    def _suggestion(self) -> Path:
        """A PNG name that replaces nothing: NAME.shape.png beside the file opened (NAME.png
        for a new file named otherwise), or shape.png."""
        source = self.source
        stem = "shape" if source is None else source.stem
        if source is not None and source.exists():
            stem += ".shape"
        return fresh_path(self._folder() / f"{stem}.png")

    def _save_asking(self, path: Path, *, typed: bool) -> None:
        """Save to `path`, first asking in the window when that would replace a file that is
        not a drawing, or any existing file the user typed the name of."""
        if path.is_dir():
            self.message = f"not saved: {path} is a folder; type a file name"
            return
        drawing = is_drawing(path)
        if path.exists() and (not drawing or (typed and path != self.path)):
            what = "" if drawing else " and is not a swarmshape drawing"
            self.confirming = path
            self._question = (
                f"{path.name} exists{what}: replace it?   y or Enter replaces, n or Esc keeps it"
            )
        else:
            self.save(path)

    def save(self, path: Path) -> bool:
        """Save the shape to `path`, which becomes the file being edited."""
        if not self._write(path):
            return False
        self.path, self.dirty = path, False
        return True

    def autosave(self) -> Path | None:
        """Keep unsaved work as NAME.autosave.png under a name nothing has yet: beside the
        user's file, or in their data folder (`data_folder`) for an untitled drawing, one of the
        shipped shapes, or a folder that cannot be written; the temporary folder is the last
        resort. Return where, or None."""
        if not self.dirty or self.shape() is None:
            return None
        shown = self.path or self.source
        name = f"{shown.stem if shown else 'untitled'}.autosave.png"
        ours = data_folder() / "autosaves"
        beside = [] if shown is None or shipped(shown) else [shown.parent]
        for folder in (*beside, ours, Path(tempfile.gettempdir())):
            try:
                if folder == ours:
                    ours.mkdir(parents=True, exist_ok=True)  # made only when it is needed
            except OSError:
                continue
            target = fresh_path(folder / name)
            if self._write(target):
                return target
        return None

    def _write(self, path: Path) -> bool:
        """Write the shape (as seen from the seeds) atomically; say how it went."""
        shape = self.shape()
        if shape is None:
            self.message = "nothing to save: paint some cells first"
            return False
        try:
            save_grid(shape.grid, path)
        except (OSError, InputError) as error:
            self.message = f"not saved: {error}"
            return False
        self.message = f"saved {path}"
        return True

    # --- drawing ------------------------------------------------------------------------

    def draw(self, surface: pygame.Surface, cell_rect: Callable) -> None:
        """Painted cells, the brush under the cursor, and the seed frame, over the arena."""
        for x, y in self.canvas.cells.tolist():
            surface.fill(PAINT, cell_rect((x, y)).inflate(-2, -2))
        if self.cursor is not None:
            half = (self.brush - 1) // 2
            corner = cell_rect((self.cursor[0] - half, self.cursor[1] - half))
            brush = pygame.Rect(corner.topleft, (corner.width * self.brush,) * 2)
            pygame.draw.rect(surface, CURSOR, brush.inflate(2, 2), width=2)
        for x, y in self.seeds.tolist():
            pygame.draw.rect(surface, CURSOR, cell_rect((x, y)), width=1)
