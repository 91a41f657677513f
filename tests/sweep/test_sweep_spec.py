"""Sweep files: what they may ask, and one clear line, with nothing written, for what they may not."""

from __future__ import annotations

import pytest
from conftest import sweep

from rtgait.sweep import spec as spec_module
from rtgait.sweep.spec import SweepError, case_scenario, load_spec

GOOD = """base = "fig4"
[axes]
"change.length" = { start = 0.05, stop = 0.25, num = 5 }
"timing.double_support" = [0.1, 0.2]
connection = ["real-time", "auto"]
"""


def test_cases_are_every_combination_in_order(spec_file):
    spec = load_spec(spec_file(GOOD))
    assert spec.n_cases == 20 and spec.axis_names == ("change.length", "timing.double_support", "connection")
    cases = spec.cases()
    assert cases[0] == {"change.length": 0.05, "timing.double_support": 0.1, "connection": "real-time"}
    assert cases[1]["connection"] == "auto" and cases[2]["timing.double_support"] == 0.2
    assert [c["change.length"] for c in cases[::4]] == [0.05, 0.1, 0.15, 0.2, 0.25]
    scenario = case_scenario(spec.base, cases[3])
    assert scenario.changes[0].length == 0.05 and scenario.timing.double_support == 0.2
    assert scenario.connection == "auto" and scenario.changes[0].through == spec.base.steps


def test_a_relative_base_file_and_step_ranges(spec_file):
    spec = load_spec(spec_file('base = "tiny.toml"\n[axes]\n"change.step" = [1, 2]\n'
                               '"timing.single_support" = { start = 0.5, stop = 0.7, step = 0.1 }\n'))  # fmt: skip
    assert spec.base.name == "tiny" and spec.n_cases == 6
    assert [c["timing.single_support"] for c in spec.cases()[:3]] == [0.5, 0.6, 0.7]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ('base = "fig4"\n[axes]\n"walk.yaw" = [0.1]\n', "axes.walk.yaw is not an axis one can sweep"),
        ('base = "fig4"\n[axes]\n"change.length" = []\n', "axes.change.length is empty"),
        ('base = "fig4"\n[axes]\n"change.length" = { start = 0.3, stop = 0.1, step = 0.05 }\n', "is empty"),
        ('base = "fig4"\n[axes]\nconnection = ["fast"]\n', "values must be among"),
        ('base = "fig4"\n[axes]\n"timing.double_support" = [-0.1]\n', "timing double_support"),
        ('base = "fig4"\n[axes]\n"change.length" = [3.0]\n', r"within \[-2, 2\] m, got 3.0"),
        ('base = "fig4"\n[axes]\n"change.step" = [11]\n', "case change.step = 11"),
        ('base = "nope"\n[axes]\nconnection = ["auto"]\n', "base: unknown scenario 'nope'"),
        ('base = "fig4"\n[axes]\n', "at least one axis"),
        ('base = "fig4"\nbogus = 1\n[axes]\nconnection = ["auto"]\n', "bogus"),
        ('base = "fig4"\n[axes]\n"change.length" = { start = 0.0, stop = 0.3, num = 200001 }\n', "at most 200000"),
    ],
)
def test_bad_specs_are_refused_and_nothing_is_written(spec_file, tmp_path, text, message):
    path = spec_file(text)
    with pytest.raises(SweepError, match=message) as caught:
        sweep([str(path), "--out", str(tmp_path / "out"), "--no-figures"])
    assert "\n" not in str(caught.value)
    assert not (tmp_path / "out").exists()


def test_too_many_cases(spec_file, tmp_path, monkeypatch):
    monkeypatch.setattr(spec_module, "MAX_CASES", 10)
    with pytest.raises(SweepError, match="more than the 10 one sweep may have"):
        sweep([str(spec_file(GOOD)), "--out", str(tmp_path / "out")])
    assert not (tmp_path / "out").exists()


def test_too_many_physics_cases_and_options_without_physics(spec_file, tmp_path, monkeypatch):
    import rtgait.cli.sweep as cli

    monkeypatch.setattr(cli, "MAX_PHYSICS_CASES", 10)
    with pytest.raises(SweepError, match="walk in physics"):
        sweep([str(spec_file(GOOD)), "--out", str(tmp_path / "out"), "--physics"])
    with pytest.raises(SweepError, match="--workers is for the physics cases"):
        sweep([str(spec_file(GOOD)), "--out", str(tmp_path / "out"), "--workers", "2"])
    assert not (tmp_path / "out").exists()


def test_an_unreachable_scheduler(spec_file, tmp_path, monkeypatch):
    pytest.importorskip("distributed")
    import socket

    import rtgait.sweep.executors as executors

    monkeypatch.setattr(executors, "CONNECT_TIMEOUT", 1.0)
    with socket.socket() as probe:  # a port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    text = 'base = "tiny.toml"\n[axes]\n"change.length" = [0.05]\n'
    with pytest.raises(ValueError, match=f"--scheduler tcp://127.0.0.1:{port}: cannot reach the Dask scheduler"):
        sweep([str(spec_file(text)), "--out", str(tmp_path / "out"), "--physics", "--scheduler",
               f"tcp://127.0.0.1:{port}"])  # fmt: skip
    assert not (tmp_path / "out").exists()
