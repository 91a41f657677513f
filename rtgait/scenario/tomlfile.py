"""Finding, reading and checking rtgait's small TOML files (walking scenarios, robot descriptions).

Every kind of file is found the same way (the name of a built-in file packaged in a folder of ``rtgait``, or a
path) and its fields are checked with the same rules. Only the error class differs: each kind raises its own
(``ScenarioError``, ``RobotError``), so a caller can catch exactly the problems of the file it loads.
:class:`TomlFiles` holds that class and the kind's names; every message it raises is one line naming the field.
Standard library only, so that loading a file never pulls in numerical or robotics packages.
"""

from __future__ import annotations

import math
import re
import sys
from collections.abc import Callable
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised only on Python 3.10
    import tomli as tomllib

if TYPE_CHECKING:
    if sys.version_info >= (3, 11):
        from importlib.resources.abc import Traversable
    else:  # pragma: no cover - exercised only on Python 3.10
        from importlib.abc import Traversable

__all__ = ["NumberRule", "SettingsPairs", "TomlDocument", "TomlFiles", "is_finite_number"]

NumberRule = Literal["any", "> 0", ">= 0", "|x| < pi/2"]
"""What :meth:`TomlFiles.number` requires of a finite number besides being finite."""

# For each rule: what the message says the value must be, and the test a finite value has to pass.
_NUMBER_RULES: dict[str, tuple[str, Callable[[float], bool]]] = {
    "any": ("a finite number", lambda x: True),
    "> 0": ("a number > 0", lambda x: x > 0.0),
    ">= 0": ("a number >= 0", lambda x: x >= 0.0),
    "|x| < pi/2": ("a number strictly between -pi/2 and pi/2", lambda x: abs(x) < math.pi / 2),
}


SettingsPairs = tuple[tuple[str, "bool | int | float | str"], ...]
"""A table of settings as read (:meth:`TomlFiles.settings`): its ``(key, value)`` pairs in file order, a subtable's keys
dotted (``("dcm.k_p", 2.0)``); frozen, so that a frozen description holding it stays comparable and hashable."""


def is_finite_number(value: Any) -> bool:
    """Whether ``value`` is a finite int or float (TOML's ``nan`` and ``inf`` are not; neither is a bool)."""
    # bool is an int subclass in Python: `cog_height = true` must not pass as 1.0.
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _natural_key(name: str) -> list[int | str]:
    """Sort key that puts fig4 before fig11: digit runs compare as numbers."""
    return [int(part) if part.isdigit() else part for part in re.split(r"(\d+)", name)]


@dataclass(frozen=True)
class TomlDocument:
    """A parsed TOML file and where it came from.

    Attributes:
        data: the parsed document.
        source: ``"builtin"`` for a packaged file, else the path as given; used in messages.
        path: the file read, ``None`` for a packaged file.
    """

    data: dict[str, Any]
    source: str
    path: Path | None = None

    @property
    def folder(self) -> Path | None:
        """Folder that relative paths inside the file resolve against; ``None`` for a packaged file."""
        return None if self.path is None else self.path.resolve().parent


@dataclass(frozen=True)
class TomlFiles:
    """One kind of TOML file: what messages call it, where its built-in files are, which error it raises.

    Attributes:
        kind: what one file describes, as messages name it (``"scenario"``); the plural adds an "s".
        folder: folder of the ``rtgait`` package holding the built-in ``<name>.toml`` files.
        error: exception class raised, with a one-line message, for every problem.
    """

    kind: str
    folder: str
    error: type[Exception]

    # ----- checking fields ----------------------------------------------------------------------------------

    def table(self, data: Any, where: str) -> dict[str, Any]:
        """``data`` itself, after checking that it is a TOML table; ``where`` names it in the message."""
        if not isinstance(data, dict):
            raise self.error(f"{where} must be a table, got {type(data).__name__} {data!r}")
        return data

    def check_keys(
        self, data: dict[str, Any], where: str, required: tuple[str, ...], optional: tuple[str, ...]
    ) -> None:
        """Check that the table ``data`` (the document itself when ``where`` is empty) has exactly these keys.

        Every ``required`` key must be there; any key that is neither required nor ``optional`` is an error.
        """
        prefix = f"{where}." if where else ""
        allowed = required + optional
        for key in data:
            if key not in allowed:
                # Unknown keys are almost always typos ("singel_support", "cog_heigth"); silently ignoring them
                # would walk differently from what the file's author meant.
                kind = "key" if where else "top-level key"
                raise self.error(f"unknown {kind} {prefix}{key} (allowed here: {', '.join(allowed)})")
        for key in required:
            if key not in data:
                raise self.error(f"missing required key {prefix}{key}")

    def settings(self, data: Any, where: str) -> SettingsPairs:
        """The table ``where`` (e.g. ``control``) as :data:`SettingsPairs`, after checking that each value is a
        number, true or false, a string or a subtable of those; what the keys mean is for the code that applies
        them to check."""
        pairs: list[tuple[str, bool | int | float | str]] = []
        for key, value in self.table(data, where).items():
            if isinstance(value, dict):
                pairs.extend((f"{key}.{sub}", item) for sub, item in self.settings(value, f"{where}.{key}"))
            elif isinstance(value, (bool, int, float, str)):
                pairs.append((key, value))
            else:
                raise self.error(f"{where}.{key} must be a number, true or false, a string or a table, got {value!r}")
        return tuple(pairs)

    def string(self, data: dict[str, Any], key: str, where: str = "", *, non_empty: bool = False) -> str:
        """The string ``data[key]`` of the table ``where`` (empty: the document); ``non_empty`` rejects ``""``."""
        value = data[key]
        path = f"{where}.{key}" if where else key
        if not isinstance(value, str) or (non_empty and not value):
            requirement = "a non-empty string" if non_empty else "a string"
            raise self.error(f"{path} must be {requirement}, got {value!r}")
        return value

    def number(self, value: Any, path: str, *, rule: NumberRule = "any", unit: str = "") -> float:
        """``value`` as a float, after checking that it is a finite number satisfying ``rule``.

        Args:
            value: the TOML value.
            path: its dotted name, for the message.
            rule: what the number must satisfy besides being finite.
            unit: shown after the requirement in the message (``"m"``), if any.
        """
        requirement, accept = _NUMBER_RULES[rule]
        if not (is_finite_number(value) and accept(float(value))):
            unit_text = f" {unit}" if unit else ""
            raise self.error(f"{path} must be {requirement}{unit_text}, got {value!r}")
        return float(value)

    def count(self, value: Any, path: str, *, high: int | None = None, why: str = "") -> int:
        """``value``, after checking that it is an integer >= 1 and, if ``high`` is given, at most ``high``.

        Args:
            value: the TOML value.
            path: its dotted name, for the message.
            high: the largest value accepted.
            why: a short clause explaining ``high``, shown in the message.
        """
        if not isinstance(value, int) or isinstance(value, bool) or value < 1:
            raise self.error(f"{path} must be an integer >= 1, got {value!r}")
        if high is not None and value > high:
            reason = f" ({why})" if why else ""
            raise self.error(f"{path} must be at most {high}{reason}, got {value!r}")
        return value

    # ----- finding files -------------------------------------------------------------------------------------

    def _builtin_dir(self) -> Traversable:
        return resources.files("rtgait").joinpath(self.folder)

    def builtin_names(self) -> list[str]:
        """Names of the built-in files (without ``.toml``), in natural order: fig4 before fig11."""
        names = (entry.name[: -len(".toml")] for entry in self._builtin_dir().iterdir() if entry.name.endswith(".toml"))
        return sorted(names, key=_natural_key)

    def _parse(self, text: str, source: str) -> dict[str, Any]:
        try:
            return tomllib.loads(text)
        except tomllib.TOMLDecodeError as error:
            raise self.error(f"invalid TOML in {source}: {error}") from None

    def load(self, name_or_path: str | Path) -> TomlDocument:
        """Read and parse a built-in file by name, or any TOML file by path; the fields are not checked.

        A string that is a built-in name wins over a file of the same name in the current folder; anything that
        looks like a path (a ``.toml`` suffix, a folder separator, or an existing file) is read as a file.
        """
        text_arg = str(name_or_path)
        if not isinstance(name_or_path, Path) and text_arg in self.builtin_names():
            text = self._builtin_dir().joinpath(f"{text_arg}.toml").read_text(encoding="utf-8")
            return TomlDocument(self._parse(text, "builtin"), "builtin")
        path = Path(name_or_path)
        looks_like_path = isinstance(name_or_path, Path) or path.suffix == ".toml" or "/" in text_arg or path.exists()
        if not looks_like_path:
            known = ", ".join(self.builtin_names())
            raise self.error(
                f"unknown {self.kind} {text_arg!r}: built-in {self.kind}s are {known} (or give a .toml path)"
            )
        return self.load_file(name_or_path)

    def load_file(self, path: str | Path) -> TomlDocument:
        """Read and parse the TOML file at ``path``, whatever its name; the fields are not checked."""
        text_arg = str(path)
        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as error:
            # strerror ("No such file or directory") reads better than str(error), which repeats the path.
            reason = error.strerror if isinstance(error, OSError) and error.strerror else str(error)
            raise self.error(f"cannot read {self.kind} file {text_arg}: {reason}") from None
        return TomlDocument(self._parse(text, str(path)), str(path), path)
