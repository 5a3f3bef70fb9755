from __future__ import annotations

import pytest

from swarmshape.config import configure
from swarmshape.core.shape import Pose
from swarmshape.errors import InputError, SettingWarning
from swarmshape.io.scenario import load_scenario, scenario_settings
from tests.conftest import SHAPES


def test_two_squares_has_two_coloured_groups_with_poses():
    scenario = load_scenario(SHAPES / "two-squares.toml")
    assert [g.name for g in scenario.groups] == ["blue", "red"]
    assert scenario.groups[0].colour == (0x3A, 0x6F, 0xD8)
    assert scenario.groups[1].pose == Pose(16, 12)
    assert scenario_settings(SHAPES / "two-squares.toml")["strategy"] == "paper"


def test_an_image_is_a_scenario_of_one_group():
    scenario = load_scenario(SHAPES / "line.png")
    assert scenario.name == "line.png"
    assert len(scenario.groups) == 1 and scenario.groups[0].shape.count == 16


def write(tmp_path, text):
    (tmp_path / "line.png").write_bytes((SHAPES / "line.png").read_bytes())
    path = tmp_path / "s.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("seed = 1\n", "at least one"),
        ("[[groups]]\nagents = 3\n", "needs a shape"),
        (
            "[[groups]]\nshape = 'line.png'\nagents = 'many'\n",
            r"groups\[0\]\.agents must be a whole",
        ),
        ("[[groups]]\nshape = 'line.png'\nagents = true\n", r"groups\[0\]\.agents must be a whole"),
        # a group's own run settings named the command line's flag (--threshold), not the file
        ("[[groups]]\nshape = 'line.png'\nagents = -3\n", r"s\.toml: groups\[0\]\.agents must"),
        (
            "[[groups]]\nshape = 'line.png'\n[[groups]]\nshape = 'line.png'\nthreshold = 7\n",
            r"s\.toml: groups\[1\]\.threshold must be a number from 0 to 1, got 7",
        ),
        ("[[groups]]\nshape = 'line.png'\ncells = 0\n", r"s\.toml: groups\[0\]\.cells must be"),
        ("[[groups]]\nshape = 'line.png'\ncolour = 'blurple'\n", "not a colour"),
        ("[[groups]]\nshape = 'line.png'\ncolour = 'rgb(999,999,999)'\n", "not a colour"),
        ("[[groups]]\nshape = 'line.png'\ncolour = 'hsl(999, 999%, 999%)'\n", "not a colour"),
        ("[[groups]]\nshape = 'line.png'\npose = {x = 1, z = 2}\n", "unknown key 'z'"),
        (  # was the Pose's own words, with no file named
            "[[groups]]\nshape = 'line.png'\npose = {x = 1, y = 2, rotation = 45}\n",
            r"s\.toml: groups\[0\]\.pose: rotation must be a multiple of 90 degrees, got 45",
        ),
        ("arena = [10]\n[[groups]]\nshape = 'line.png'\n", "arena must be two whole numbers"),
        (  # the fuzz (seed 42): text and a number in one list was an internal error
            "arena = ['0', 20]\n[[groups]]\nshape = 'line.png'\n",
            "arena must be two whole numbers",
        ),
        ("arena = [0.5, '20']\n[[groups]]\nshape = 'line.png'\n", "arena must be two whole"),
        ("order = 'random'\n[[groups]]\nshape = 'line.png'\n", "order is an option of paper"),
        ("[options]\norder = 'random'\n[[groups]]\nshape = 'line.png'\n", "not of optimal"),
        ("max_speed = 'fast'\n[[groups]]\nshape = 'line.png'\n", "max_speed must be"),
        ("msg_loss = 'often'\n[[groups]]\nshape = 'line.png'\n", "msg_loss must be"),
        ("[[groups]]\nshape = 'missing.png'\n", "no such file"),
    ],
)
def test_bad_scenarios_name_the_file_and_the_key(tmp_path, text, message):
    path = write(tmp_path, text)
    with pytest.raises(InputError, match=message):
        load_scenario(configure(path).shape)


def test_noise_settings_reach_the_run_and_a_bad_one_names_the_file(tmp_path):
    path = write(tmp_path, "msg_loss = 0.3\ndistance_noise = 0\n[[groups]]\nshape = 'line.png'\n")
    with pytest.warns(SettingWarning, match="read only by local plug-ins"):
        config = configure(path, seed=1)  # the default strategy, a central one, ignores noise
    assert (config.msg_loss, config.distance_noise) == (0.3, 0.0)
    path = write(tmp_path, "sense_radius = 40\n[[groups]]\nshape = 'line.png'\n")
    with pytest.raises(InputError, match=f"^{path}: sense_radius must be a number from 1 to 16"):
        configure(path)


def test_a_scenario_nested_deeper_than_python_recurses_is_one_clear_error(tmp_path):
    """Found by the fuzz: tomllib's RecursionError was an internal error."""
    path = write(tmp_path, f"seed = {'[' * 3000}{']' * 3000}\n[[groups]]\nshape = 'line.png'\n")
    with pytest.raises(InputError, match=r"s\.toml: nested too deeply to be a \.toml scenario"):
        scenario_settings(path)


def test_a_scenario_with_a_number_longer_than_int_reads_is_one_clear_error(tmp_path):
    """Found by the fuzz (seed 38): tomllib's int() stops at 4,300 digits with a ValueError
    that is not a TOMLDecodeError, and it was an internal error."""
    path = write(tmp_path, f"seed = {'9' * 5000}\n[[groups]]\nshape = 'line.png'\n")
    with pytest.raises(InputError, match=r"s\.toml: holds a number of more than 4,300 digits"):
        scenario_settings(path)
