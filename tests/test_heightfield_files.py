"""Height fields in scenario files (``[terrain] type = "heightfield"``, :mod:`rtgait.scenario.heightfield_file`): the
file read relative to the scenario, .npy and .csv alike, the example scenarios placed as their grids say, and one-line
errors naming the field or the file."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scenario_files import scenario_text

from rtgait.core.geometry.heightfield import Heightfield
from rtgait.scenario.loading import load_scenario
from rtgait.scenario.scenario import ScenarioError

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "heightfield"
TALOS_SOLE = "[robot.sole]\nfront = 0.105\nback = 0.105\ninner = 0.065\nouter = 0.065\n"


def _write(folder: Path, terrain: str, steps: int = 6, step_length: float = 0.2) -> Path:
    text = scenario_text(steps=steps, step_length=step_length).replace(
        "[robot.sole]\nfront = 0.13\nback = 0.10\ninner = 0.07\nouter = 0.07\n", TALOS_SOLE
    )
    path = folder / "walk.toml"
    path.write_text(text + "[terrain]\n" + terrain, encoding="utf-8")
    return path


def _ramp(folder: Path, suffix: str = ".npy") -> Path:
    """A 5 degree ramp from x = 0.5 m, 5 cm samples over 3 m along x, 3 rows across y = -0.5..0.5 m."""
    x = np.linspace(0.0, 3.0, 61)
    grid = np.tile(math.tan(math.radians(5.0)) * np.clip(x - 0.5, 0.0, None), (3, 1))
    path = folder / f"ramp{suffix}"
    if suffix == ".npy":
        np.save(path, grid)
    else:
        path.write_text(
            "# heights (m), rows along y\n" + "\n".join(",".join(map(repr, row.tolist())) for row in grid) + "\n"
        )
    return path


@pytest.mark.parametrize("suffix", [".npy", ".csv"])
def test_the_file_is_read_relative_to_the_scenario_and_the_walk_placed_on_it(tmp_path, monkeypatch, suffix):
    (tmp_path / "grids").mkdir()
    _ramp(tmp_path / "grids", suffix)
    path = _write(tmp_path, f'type = "heightfield"\nfile = "grids/ramp{suffix}"\nsize = [3.0, 1.0]\n')
    monkeypatch.chdir("/")  # not the scenario's folder
    scenario = load_scenario(path)
    terrain = scenario.terrain.terrain
    assert isinstance(terrain, Heightfield) and terrain.origin == (0.0, -0.5)  # the default origin
    prints = scenario.nominal_footprints()
    on_ramp = [f for f in prints if 0.61 <= f.x <= 2.5]
    assert on_ramp and all(f.pitch == pytest.approx(-math.radians(5.0), abs=1e-12) for f in on_ramp)
    assert [f.z for f in on_ramp] == pytest.approx([math.tan(math.radians(5.0)) * (f.x - 0.5) for f in on_ramp])


def test_the_example_scenarios_load_and_the_ramp_is_the_analytic_slope():
    ramp = load_scenario(EXAMPLES / "heightfield-ramp.toml")
    for foot in ramp.nominal_footprints():
        if 0.61 <= foot.x <= 2.39:
            assert foot.pitch == pytest.approx(-math.radians(5.0), abs=1e-12)
    swell = load_scenario(EXAMPLES / "heightfield-swell.toml").nominal_footprints()
    assert max(f.z for f in swell) < 0.04 and min(f.roll for f in swell) >= 0.0 < max(f.roll for f in swell)
    bumps = load_scenario(EXAMPLES / "heightfield-bumps.toml").nominal_footprints()
    assert max(f.z for f in bumps) == pytest.approx(0.034, abs=0.002)  # the second bump's top under a left foot
    assert max(abs(f.roll) for f in bumps) > 0.03 and max(abs(f.pitch) for f in bumps) > 0.05


@pytest.mark.parametrize(
    ("terrain", "message"),
    [
        ('file = "missing.npy"\nsize = [3.0, 1.0]\n', r"^cannot read terrain\.file .*missing\.npy: No such file"),
        ('file = "ramp.png"\nsize = [3.0, 1.0]\n', r"^terrain\.file must be a \.npy or \.csv file of heights"),
        ('file = "ramp.npy"\nsize = [3.0]\n', r"^terrain\.size must be two numbers \[x, y\] \(m\)"),
        ('file = "ramp.npy"\nsize = [3.0, -1.0]\n', r"^terrain\.size\[1\] must be a number > 0 m"),
        ('file = "ramp.npy"\n', r"terrain.*size"),
        ('file = "ramp.npy"\nsize = [3.0, 1.0]\norigin = [-0.6, -0.5]\n', r"^terrain: standing foot F\[0\] .*level"),
        # The grid squeezed to 1 m: its top ends in a 22 cm drop to the level ground at x = 1 m, under the walk.
        (
            'file = "ramp.npy"\nsize = [1.0, 1.0]\n',
            r"^terrain: step \d at x = [\d.]+ m, y = .*discontinuity or .*rough",
        ),
    ],
)
def test_bad_height_fields_are_refused_in_one_line(tmp_path, terrain, message):
    _ramp(tmp_path)
    path = _write(tmp_path, 'type = "heightfield"\n' + terrain)
    with pytest.raises(ScenarioError, match=message) as error:
        load_scenario(path)
    assert "\n" not in str(error.value)


def test_a_grid_that_is_not_numbers_is_refused(tmp_path):
    (tmp_path / "bad.csv").write_text("0,0,0\n0,x,0\n")
    path = _write(tmp_path, 'type = "heightfield"\nfile = "bad.csv"\nsize = [1.0, 1.0]\n')
    with pytest.raises(ScenarioError, match=r"^terrain\.file .*bad\.csv is not a grid of numbers"):
        load_scenario(path)
