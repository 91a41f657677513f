"""Helpers of the sweep tests: sweep files, and running ``rtgait sweep`` through its parser."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from rtgait.cli.sweep import add_parser, run

TINY = """name = "tiny"
connection = "real-time"
[robot]
cog_height = 0.80
[robot.sole]
front = 0.13
back = 0.10
inner = 0.07
outer = 0.07
[timing]
single_support = 0.6
double_support = 0.2
dt = 0.005
horizon_steps = 2
start = 0.4
end = 0.4
settle = 0.4
[walk]
steps = 2
step_length = 0.05
step_width = 0.19
step_height = 0.04
[[walk.change]]
step = 2
length = 0.08
"""
"""A walk of two steps and a closing one with short ends: a few seconds in physics."""


def parse(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="rtgait")
    add_parser(parser.add_subparsers(dest="command"))
    return parser.parse_args(["sweep", *argv])


def sweep(argv: list[str]) -> int:
    return run(parse(argv))


@pytest.fixture
def spec_file(tmp_path: Path):
    """Write a sweep file (and the tiny scenario beside it) and return its path."""

    def write(text: str, name: str = "sweep.toml") -> Path:
        (tmp_path / "tiny.toml").write_text(TINY, encoding="utf-8")
        path = tmp_path / name
        path.write_text(text, encoding="utf-8")
        return path

    return write
