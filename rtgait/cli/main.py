"""The ``rtgait`` command: list the built-in scenarios, plan a scenario and write its trajectory and figures, or
walk it in physics (the subcommands live in :mod:`rtgait.cli`).

Exit codes: 0 success, 1 the run could not complete (outputs not writable, an extra package missing), 2 bad input
(unknown scenario, invalid file, bad option, a size beyond :mod:`rtgait.core.limits`); every error, argparse's
included, is one ``rtgait: error: ...`` line on stderr. Everything is checked before the run starts, and a run
replaces its whole set of outputs or changes nothing (:mod:`rtgait.outputs`).
"""

from __future__ import annotations

import argparse
import re
import sys
import warnings
from collections.abc import Callable, Sequence
from typing import Any, NoReturn

from rtgait import __version__
from rtgait.cli import plan, play, plot, simulate
from rtgait.cli import sweep as sweep_cli
from rtgait.cli.common import PROG, RunError, print_error
from rtgait.outputs import OutputError
from rtgait.scenario.loading import builtin_scenarios

# A value that starts like a negative number ("-0.1,0,0", "-1e-3", "-inf"); argparse would take it for an option.
_NEGATIVE_VALUE = re.compile(r"-(\d|\.\d|inf|nan)", re.IGNORECASE)


class _Parser(argparse.ArgumentParser):
    """argparse with rtgait's one-line errors, and option values that start with a minus sign."""

    def error(self, message: str) -> NoReturn:
        # argparse prints its usage and the message on several lines; scripts grep one line, humans read one.
        print_error(f"{message} (see '{self.prog} --help')")
        raise SystemExit(2)

    def parse_known_args(  # type: ignore[override]  # typeshed's overloads; the behaviour is argparse's
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        # Each subcommand's parser runs this on its own arguments, so it knows the options that take a value.
        tokens = list(sys.argv[1:] if args is None else args)
        return super().parse_known_args(self._glue_negative_values(tokens), namespace)

    def _glue_negative_values(self, tokens: list[str]) -> list[str]:
        """``--velocity -0.1,0,0`` as ``--velocity=-0.1,0,0``: argparse reads a value starting with '-' as an
        option unless it is a bare negative number, so comma lists and exponents would be refused."""
        glued: list[str] = []
        index = 0
        while index < len(tokens):
            token = tokens[index]
            if token == "--":  # the rest are positional, whatever they look like
                return glued + tokens[index:]
            following = tokens[index + 1] if index + 1 < len(tokens) else ""
            if self._takes_value(token) and _NEGATIVE_VALUE.match(following):
                glued.append(f"{token}={following}")
                index += 2
            else:
                glued.append(token)
                index += 1
        return glued

    def _takes_value(self, token: str) -> bool:
        """Whether ``token`` names (in full, or by a unique prefix as argparse allows) an option with a value."""
        if not token.startswith("--") or "=" in token:
            return False
        options = {name: action.nargs != 0 for action in self._actions for name in action.option_strings}
        if token in options:
            return options[token]
        matches = [name for name in options if name.startswith(token)]
        return self.allow_abbrev and len(matches) == 1 and options[matches[0]]


def _build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog=PROG,
        description="Real-time humanoid gait planning (Harada et al.'s analytical method):\nplan walks whose "
        "footsteps change while walking, and check that the ZMP stays inside\nthe support polygon.",
        epilog="examples:\n  rtgait scenarios\n  rtgait plan fig4\n"
        "  rtgait plan my_walk.toml --out results/my_walk --dt 0.001\n  rtgait simulate fig8 --velocity -0.1,0,0",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")
    commands.add_parser("scenarios", help="list the built-in scenarios", description="List the built-in scenarios.")
    plan.add_parser(commands)
    simulate.add_parser(commands)
    play.add_parser(commands)
    plot.add_parser(commands)
    sweep_cli.add_parser(commands)
    return parser


def _scenarios(args: argparse.Namespace) -> int:
    listing = builtin_scenarios()
    width = max(len(name) for name in listing)
    for name, description in listing.items():
        print(f"{name:<{width}}  {description}")
    return 0


_COMMANDS: dict[str, Callable[[argparse.Namespace], int]] = {
    "scenarios": _scenarios,
    "plan": plan.run,
    "simulate": simulate.run,
    "play": play.run,
    "plot": plot.run,
    "sweep": sweep_cli.run,
}


def _show_warning(message: Warning | str, category: type[Warning], *args: Any, **kwargs: Any) -> None:
    # Python's format (file, line, source) is for programmers; a user gets one line, like an error.
    print(f"{PROG}: warning: {' '.join(str(message).split())}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line ``argv`` (default ``sys.argv[1:]``); returns the exit code."""
    parser = _build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as stop:  # argparse's usage errors (code 2, one line) and --help/--version (0)
        return stop.code if isinstance(stop.code, int) else 2
    if args.command is None:
        print_error(f"choose a command: {', '.join(_COMMANDS)} (see '{PROG} --help')")
        return 2
    with warnings.catch_warnings():
        warnings.showwarning = _show_warning
        try:
            return _COMMANDS[args.command](args)
        except ValueError as error:  # ScenarioError, the robot's and the core's own input checks
            print_error(str(error))
            return 2
        except (RunError, OutputError) as error:
            print_error(str(error))
            return 1
        except OSError as error:  # a file the commands' own checks did not name: still one line, not a traceback
            print_error(_os_error_text(error))
            return 1
        except KeyboardInterrupt:
            print_error("interrupted")
            return 130


def _os_error_text(error: OSError) -> str:
    """``path: reason`` without Python's ``[Errno n]`` and quotes (``reason`` alone when no file is named)."""
    reason = error.strerror or str(error) or type(error).__name__
    return f"{error.filename}: {reason}" if error.filename is not None else reason


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
