"""Whether a run's outputs could be written into a folder, and the folders made for them.

Every problem is an :class:`OutputError` with a one-line message naming the folder and what is in the way.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterable, Sequence
from pathlib import Path

__all__ = ["OutputError", "check_destination", "create_folder", "existing", "make_parents", "remove_created"]


class OutputError(Exception):
    """Outputs cannot be written where asked (not a folder, not writable, a disk error). One line."""


def writable(path: Path) -> bool:
    """Whether we may create and rename entries in the folder ``path``, or replace the file ``path``."""
    return os.access(path, os.W_OK | os.X_OK) if path.is_dir() else os.access(path, os.W_OK)


def existing(path: Path) -> bool:
    """Whether anything is at ``path``: a dangling link is in the way too."""
    return path.exists() or path.is_symlink()


def check_destination(out: Path, names: Iterable[str] = ()) -> None:
    """Check that outputs called ``names`` could be written into the folder ``out`` now.

    ``out`` must be a writable folder in which none of ``names`` is a folder or a read-only file, or not exist yet
    below a writable folder (the missing folders are created when the outputs are written).

    Raises:
        OutputError: naming ``out`` and what is in the way.
    """
    where = f"cannot write outputs to {out}:"
    try:
        _check_destination(out, names, where)
    except OSError as error:  # a name the file system refuses (too long, a bad byte), an unreadable folder
        raise OutputError(f"{where} {error.strerror or error}") from None


def _check_destination(out: Path, names: Iterable[str], where: str) -> None:
    if existing(out):
        if not out.is_dir():
            raise OutputError(f"{where} it exists and is not a folder")
        if not writable(out):
            raise OutputError(f"{where} the folder is not writable")
        for name in names:
            target = out / name
            if target.is_dir() and not target.is_symlink():
                raise OutputError(f"{where} {target} is a folder")
            if target.exists() and not writable(target):
                raise OutputError(f"{where} {target} is read-only")
        return
    ancestor = next((path for path in out.parents if existing(path)), None)
    if ancestor is None:  # only when the working folder itself was deleted
        raise OutputError(f"{where} no folder above it exists")
    if not ancestor.is_dir():
        raise OutputError(f"{where} {ancestor} is not a folder")
    if not writable(ancestor):
        raise OutputError(f"{where} {ancestor} is not writable")


def make_parents(out: Path) -> list[Path]:
    """Create the missing folders above ``out``; returns them, deepest first, to remove them after a failure."""
    missing = [path for path in out.parents if not existing(path)]
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        remove_created(missing)
        raise OutputError(f"cannot create output folder {out}: {error.strerror or error}") from None
    return missing


def create_folder(out: Path) -> None:
    """Create the folder ``out`` and the missing folders above it, for outputs written straight into it (a sweep's).

    Raises:
        OutputError: a folder cannot be created; those created before are removed.
    """
    missing = [path for path in (out, *out.parents) if not existing(path)]
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        remove_created(missing)
        raise OutputError(f"cannot create output folder {out}: {error.strerror or error}") from None


def remove_created(folders: Sequence[Path]) -> None:
    """Remove the ``folders`` a failed run created, deepest first."""
    for folder in folders:  # rmdir refuses a folder someone has put something in meanwhile
        with contextlib.suppress(OSError):
            folder.rmdir()
