"""Every case of docs/errors.md, through the real command line in a subprocess."""

from __future__ import annotations

import json
import os
import re
import shlex
import struct
import subprocess
import zlib
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from swarmshape.io.checkpoint import VERSION
from tests.conftest import SHAPES, python

TABLE = Path(__file__).resolve().parent.parent / "docs" / "errors.md"
ROW = re.compile(
    r"^\| (?P<case>[^|]+) \| `(?P<command>[^`]*)` \| (?P<exit>\d) \| `(?P<message>[^`]*)` \|$"
)


def cases() -> list[tuple[str, str, int, str]]:
    rows = [ROW.match(line) for line in TABLE.read_text().splitlines()]
    return [(m["case"].strip(), m["command"], int(m["exit"]), m["message"]) for m in rows if m]


def png_chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


@pytest.fixture(scope="module")
def bad_files(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("bad")
    header = struct.pack(">IIBBBBB", 30000, 30000, 1, 0, 0, 0, 0)
    bomb = b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", header) + png_chunk(b"IEND", b"")
    (folder / "bomb.png").write_bytes(bomb)
    (folder / "empty.png").write_bytes(b"")
    (folder / "text.png").write_text("not an image")
    good = (SHAPES / "star.png").read_bytes()
    (folder / "truncated.png").write_bytes(good[: len(good) // 2])
    Image.new("L", (1, 1), 0).save(folder / "one.png")
    Image.new("L", (20, 20), 255).save(folder / "white.png")
    Image.new("L", (20, 20), 0).save(folder / "black.png")
    dots = Image.new("L", (400, 400), 255)
    dots.putpixel((0, 0), 0)
    dots.putpixel((399, 399), 0)
    dots.save(folder / "dots.png")
    (folder / "bad.toml").write_text("groups = [ {")
    (folder / "typed.toml").write_text("[[groups]]\nshape = 3\n")
    (folder / "long.toml").write_text(f"seed = {'9' * 5000}\n[[groups]]\nshape = 'one.png'\n")
    (folder / "typo.toml").write_text("[[groups]]\nshap = 'one.png'\n")
    (folder / "typo-sweep.toml").write_text(
        "shapes = ['one.png']\nstrategies = ['optimal']\nspeed = 3\n"
    )
    (folder / "old.state").write_bytes(b"swarmshape state 1\n\x80\x05garbage")
    manifest = {"format": "swarmshape state", "version": VERSION, "values": {}, "arrays": []}
    with (folder / "damaged.state").open("wb") as handle:
        text = json.dumps({**manifest, "checksum": "0"}).encode()
        np.savez(handle, manifest=np.frombuffer(text, dtype=np.uint8))
    (folder / "loop").symlink_to("loop")
    os.mkfifo(folder / "pipe.png")
    os.mkfifo(folder / "pipe.json")
    (folder / "eps.png").write_text("%!PS-Adobe-3.0 EPSF-3.0\n%%BoundingBox: 0 0 10 10\nshowpage\n")
    (folder / "short.ppm").write_bytes(b"P6\n10")
    huge = struct.pack(">IIBBBBB", 10000, 10000, 8, 0, 0, 0, 0)
    (folder / "huge.png").write_bytes(
        b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", huge) + png_chunk(b"IEND", b"")
    )
    (folder / "beyond.csv").write_text("x,y\n99999999999999999999999,1\n")
    (folder / "twins.toml").write_text(
        "[[groups]]\nname = 'a'\nshape = 'one.png'\n[[groups]]\nname = 'a'\nshape = 'one.png'\n"
    )
    (folder / "code.toml").write_text("strategy = 'this:X'\n[[groups]]\nshape = 'one.png'\n")
    (folder / "top-shape.toml").write_text("shape = 'one.png'\n[[groups]]\nshape = 'one.png'\n")
    (folder / "code-sweep.toml").write_text("shapes = ['one.png']\nstrategies = ['evil:X']\n")
    (folder / "nope-sweep.toml").write_text("shapes = ['one.png']\nstrategies = ['nope']\n")
    (folder / "faults.toml").write_text(
        "[[faults]]\nstep = 3\nkind = 'melt'\n[[groups]]\nshape = 'one.png'\n"
    )
    (folder / "fault-sweep.toml").write_text(
        "shapes = ['one.png']\nstrategies = ['optimal']\nfail = ['0.2']\n"
    )
    (folder / "mismatch.csv").write_text(
        'run,config.seed,curve_every,coverage_curve,wall_time\n"{""seed"": 7}",1,5,[1.0],0.1\n'
    )
    (folder / "far.toml").write_text(
        "[[groups]]\nshape = 'one.png'\npose = { x = 99999999999999999999, y = 2 }\n"
    )
    (folder / "turned.toml").write_text(
        "[[groups]]\nshape = 'one.png'\npose = {x = 3, y = 3, rotation = 45}\n"
    )
    (folder / "nul.toml").write_text('[[groups]]\nshape = "o\\u0000ne.png"\n')
    (folder / "start.csv").write_text("x,y\n0,0\n1,1\n")
    (folder / "letters.csv").write_text("x,y\na,b\n")
    (folder / "broken_strategy.py").write_text(
        "import sys\nimport numpy as np\nfrom swarmshape import Strategy\n"
        "class Broken(Strategy):\n    name = 'broken'\n    description = 'raises'\n"
        "    def on_start(self, swarm):\n        raise RuntimeError('boom')\n"
        "class Writes(Broken):\n    name = 'writes'\n    def on_start(self, swarm): pass\n"
        "    def on_step(self, swarm):\n        swarm.state[:] = 0\n"
        "class Nobody(Writes):\n    name = 'nobody'\n    def on_start(self, swarm):\n"
        "        swarm.assign(np.array([7]), np.array([0]))\n"
        "class Exits(Writes):\n    name = 'exits'\n    def on_step(self, swarm):\n"
        "        sys.exit(0)\n"
        "class Loops(Writes):\n    name = 'loops'\n    def on_step(self, swarm):\n"
        "        while True: pass\n"
        "class Bare(Writes):\n    name = 'bare'\n    def __init__(self):\n"
        "        super().__init__()\n"
    )
    (folder / "import_boom.py").write_text("raise RuntimeError('boom')\n")
    return folder


def swarmshape(folder: Path, command: str) -> subprocess.CompletedProcess:
    args = shlex.split(command.replace("{dir}", str(folder)))
    if args[0] not in ("sweep", "plot", "edit", "benchmark"):
        args += ["--headless"] + ([] if "--max-steps" in args else ["--max-steps", "3"])
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "PYTHONPATH": str(folder)}
    return python("-m", "swarmshape", *args, env=env, cwd=folder, timeout=60)


def test_the_table_has_every_case():
    assert len(cases()) >= 35


@pytest.mark.parametrize(
    ("case", "command", "code", "message"), cases(), ids=[c[0] for c in cases()]
)
def test_each_bad_input_is_one_clear_line(bad_files, case, command, code, message):
    result = swarmshape(bad_files, command)
    lines = result.stderr.strip().splitlines()
    assert result.returncode == code, result.stderr
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("swarmshape: "), lines[0]
    assert message in lines[0]
    assert "Traceback" not in result.stderr


@pytest.mark.parametrize(
    "name", ["one.png", "black.png", "anim.gif", "sixteen.png", "palette.png", "cmyk.jpg"]
)
def test_odd_but_valid_images_run(bad_files, name):
    rng = np.random.default_rng(0)
    frames = [Image.new("L", (10, 10), 255) for _ in range(3)]
    frames[0].paste(0, (2, 2, 6, 6))
    frames[0].save(bad_files / "anim.gif", save_all=True, append_images=frames[1:])
    Image.fromarray((rng.random((40, 40)) * 65535).astype(np.uint16)).save(
        bad_files / "sixteen.png"
    )
    cutout = Image.new("RGBA", (20, 20), (0, 0, 0, 0))
    cutout.paste((0, 0, 0, 255), (5, 5, 15, 15))
    cutout.convert("P").save(bad_files / "palette.png")
    Image.new("CMYK", (20, 20), (0, 0, 0, 255)).save(bad_files / "cmyk.jpg")
    result = swarmshape(bad_files, f"{{dir}}/{name}")
    assert result.returncode == 3, result.stderr  # ran, and stopped at 3 steps, before forming
    assert f"{name}: optimal" in result.stdout and "not formed after 3 steps" in result.stdout
