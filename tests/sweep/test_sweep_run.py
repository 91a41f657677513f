"""Running sweeps: the rows are rtgait plan's numbers, an interrupted sweep resumes, physics runs the same anywhere."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import sweep

import rtgait.sweep.executors as executors
import rtgait.sweep.pendulum as pendulum
from rtgait.core import OnlinePlanner, rollout
from rtgait.io.plan_summary import summarize
from rtgait.sweep.executors import LocalExecutor
from rtgait.sweep.spec import case_scenario, load_spec
from rtgait.sweep.store import read_results

SMALL = """base = "fig4"
[axes]
"change.length" = [0.06, 0.15]
"timing.double_support" = [0.1, 0.2]
connection = ["real-time", "quasi-real-time", "auto", "preview"]
"""


def test_rows_are_what_rtgait_plan_reports(spec_file, tmp_path):
    path = spec_file(SMALL)
    assert sweep([str(path), "--out", str(tmp_path / "out"), "--no-figures", "--quiet"]) == 0
    rows = read_results(tmp_path / "out")
    spec = load_spec(path)
    assert len(rows) == 16 and [r["connection"] for r in rows[:4]] == ["real-time", "quasi-real-time", "auto",
                                                                       "preview"]  # fmt: skip
    for row in rows:
        values = {name: row[name] for name in spec.axis_names}
        scenario = case_scenario(spec.base, values)
        if row["connection"] == "preview":
            want = pendulum.rolled_out(scenario, "preview")
            assert row["zmp_margin_min"] == pytest.approx(want["zmp_margin_min"], abs=1e-9)
            assert row["zmp_margin_min_time"] == want["zmp_margin_min_time"]
            continue
        run = rollout(OnlinePlanner(scenario.planner_config(), scenario.strides()), scenario.dt, scenario.sole,
                      scenario.changes)  # fmt: skip
        summary = summarize(run, scenario)
        assert row["zmp_margin_min"] == pytest.approx(summary["zmp_margin_min"], abs=1e-9)
        assert row["zmp_margin_min_time"] == summary["zmp_margin_min_time"]
        assert row["zmp_outside"] == summary["zmp_outside"]
        dx, dy = summary["zmp_deviation_max"]
        assert (row["zmp_deviation_max_x"], row["zmp_deviation_max_y"]) == pytest.approx((dx, dy), abs=1e-9)
        if row["connection"] == "auto":
            assert row["decision"] == summary["auto_decisions"][0]["connection"]
    assert (tmp_path / "out" / "results.parquet").stat().st_size > 0


def test_an_interrupted_sweep_resumes_without_recomputing(spec_file, tmp_path, monkeypatch):
    path, out = spec_file(SMALL), tmp_path / "out"
    real = pendulum.evaluate_group
    evaluated: list[str] = []

    def interrupted(spec, group):
        if evaluated:  # the second group: as if Ctrl-C were pressed
            raise KeyboardInterrupt
        evaluated.extend(key for key, _ in group)
        return real(spec, group)

    monkeypatch.setattr(pendulum, "evaluate_group", interrupted)
    with pytest.raises(KeyboardInterrupt):
        sweep([str(path), "--out", str(out), "--no-figures", "--quiet"])
    partial = read_results(out)  # valid tables of the cases finished
    assert [r["case"] for r in partial] == evaluated and 0 < len(partial) < 16

    again: list[str] = []

    def counted(spec, group):
        again.extend(key for key, _ in group)
        return real(spec, group)

    monkeypatch.setattr(pendulum, "evaluate_group", counted)
    sweep([str(path), "--out", str(out), "--no-figures", "--quiet"])
    assert not set(again) & set(evaluated) and len(again) + len(evaluated) == 16
    monkeypatch.setattr(pendulum, "evaluate_group", real)
    sweep([str(path), "--out", str(tmp_path / "whole"), "--no-figures", "--quiet"])
    assert (out / "results.csv").read_text() == (tmp_path / "whole" / "results.csv").read_text()


def test_a_sweep_run_twice_computes_nothing_again(spec_file, tmp_path, monkeypatch):
    path, out = spec_file(SMALL), tmp_path / "out"
    sweep([str(path), "--out", str(out), "--no-figures", "--quiet"])
    monkeypatch.setattr(pendulum, "evaluate_group", lambda spec, group: pytest.fail("computed again"))
    sweep([str(path), "--out", str(out), "--no-figures", "--quiet"])
    assert len(read_results(out)) == 16


# ----- physics ------------------------------------------------------------------------------------------------
needs_physics = pytest.mark.skipif(
    not all(importlib.util.find_spec(m) for m in ("mujoco", "pinocchio", "distributed")),
    reason="needs MuJoCo, Pinocchio and dask.distributed",
)


@needs_physics
def test_physics_on_a_local_cluster_gives_the_rows_of_one_worker(spec_file, tmp_path):
    text = 'base = "tiny.toml"\n[axes]\n"change.length" = [0.05, 0.12]\nconnection = ["real-time", "preview"]\n'
    path = spec_file(text)
    sweep([str(path), "--out", str(tmp_path / "one"), "--physics", "--workers", "1", "--no-figures", "--quiet"])
    sweep([str(path), "--out", str(tmp_path / "dask"), "--physics", "--workers", "2", "--scheduler", "local",
           "--no-figures", "--quiet"])  # fmt: skip
    one, dask = read_results(tmp_path / "one"), read_results(tmp_path / "dask")
    assert one == dask
    walked = [r for r in one if r["connection"] == "real-time"]
    assert all(r["physics"] == "ok" and r["steps_planned"] == 3 for r in walked)
    assert all(r["physics"] == "skipped" for r in one if r["connection"] == "preview")


def fake_worker(monkeypatch, tmp_path, body: str) -> Path:
    """Replace the case process by a script that counts its runs in a file, then does ``body``."""
    counter = tmp_path / "runs"
    script = f"import os, sys, time, json, signal\nopen({str(counter)!r}, 'a').write('x')\n{body}\n"
    monkeypatch.setattr(executors, "WORKER_COMMAND", (sys.executable, "-c", script))
    return counter


@pytest.mark.parametrize(
    ("body", "runs", "reason"),
    [
        ("os.kill(os.getpid(), signal.SIGKILL)", 2, "died 2 times: worker killed by SIGKILL"),
        ("time.sleep(30)", 1, "timed out after 0.5 s"),
        ("print(json.dumps({'error': 'unreachable'})); sys.exit(3)", 1, "unreachable"),
        (
            "sys.stdin.read(); print(json.dumps({'fell': True, 'tipped': False, 'fall_time': 1.5, "
            "'steps_completed': 2, 'steps_planned': 3}))",
            1,
            "",
        ),
    ],
)
def test_dying_cases_are_retried_once_and_hanging_ones_killed(monkeypatch, tmp_path, body, runs, reason):
    counter = fake_worker(monkeypatch, tmp_path, body)
    results = {}
    LocalExecutor(1).run([{"id": "a", "document": {}, "values": {}}], 0.5 if "sleep" in body else 20.0,
                         lambda key, fields: results.__setitem__(key, fields))  # fmt: skip
    assert counter.read_text() == "x" * runs
    fields = results["a"]
    if reason:
        assert fields["physics"] == "failed" and reason in fields["physics_error"]
    else:
        assert fields["physics"] == "ok" and fields["fell"] is True and fields["fall_time"] == 1.5


@pytest.mark.parametrize(("option", "state"), [([], None), (["--state", "truth"], "truth")])
def test_the_state_reaches_every_physics_case(monkeypatch, spec_file, tmp_path, option, state):
    # The case processes replaced by one that keeps the job it is given and answers a walk.
    jobs = tmp_path / "jobs"
    answer = {"fell": False, "tipped": False, "fall_time": None, "steps_completed": 3, "steps_planned": 3}
    body = f"open({str(jobs)!r}, 'a').write(sys.stdin.read() + '\\n'); print(json.dumps({answer!r}))"
    fake_worker(monkeypatch, tmp_path, body)
    path = spec_file('base = "tiny.toml"\n[axes]\n"change.length" = [0.05, 0.12]\n')
    out = tmp_path / "out"
    sweep([str(path), "--out", str(out), "--physics", "--workers", "1", "--no-figures", "--quiet", *option])
    sent = [json.loads(line) for line in jobs.read_text().splitlines()]
    assert len(sent) == 2 and all(job["state"] == state for job in sent)
    assert json.loads((out / "sweep.json").read_text())["state"] == (state or "estimated")
    # The worker hands it to the loop (the default's when none).
    from rtgait.sweep.worker import simulate_options

    options = simulate_options(None, state).get("options")
    assert (options is None) if state is None else options.state == state


def test_the_map_is_drawn(spec_file, tmp_path):
    pytest.importorskip("matplotlib")
    from rtgait.sweep.maps import plot_map

    path = spec_file(SMALL.replace("[0.1, 0.2]", "[0.05, 0.1, 0.2, 0.5]"))
    sweep([str(path), "--out", str(tmp_path / "out"), "--quiet"])
    for name in ("map.png", "map.pdf"):
        assert (tmp_path / "out" / name).stat().st_size > 10_000
    rows = read_results(tmp_path / "out")
    meta = json.loads((tmp_path / "out" / "sweep.json").read_text())
    for row in rows:
        row.update({"physics": "ok", "fell": row["zmp_outside"], "tipped": False})
    figure = plot_map(rows, {**meta, "physics": True})
    markers = [c for ax in figure.axes for c in ax.collections if c.get_offsets().shape[0]]
    assert len(markers) >= 3  # walked and fell markers on the method panels
    np.testing.assert_array_equal(
        sorted({r["connection"] for r in rows}), sorted(["auto", "preview", "quasi-real-time", "real-time"])
    )
