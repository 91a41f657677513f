"""A run's set of output files, written into a staging folder and moved into the output folder all or none.

Replacing moves the old files aside into the staging folder first (its ``.previous`` folder), then the new ones
in; any failure or Ctrl-C while the files move puts the old ones back, so the output folder ends with the complete
new set or unchanged. Files of other names in the output folder are never touched.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import threading
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from rtgait.outputs.destination import (
    OutputError,
    check_destination,
    existing,
    make_parents,
    remove_created,
)
from rtgait.outputs.staging_folders import (
    BACKUP,
    holds_previous_outputs,
    new_staging_folder,
    release,
    remove_stale_staging,
)

__all__ = ["Staging", "staged_outputs"]


@dataclass
class Staging:
    """Where a run writes its outputs before they move into place.

    Attributes:
        folder: the staging folder; every output file is written directly in it.
        files: names of the outputs written there, in the order a listing shows them; only these move.
    """

    folder: Path
    files: list[str] = field(default_factory=list)

    def add(self, name: str) -> Path:
        """Register the output ``name`` (a plain file name, once) and return the path to write it to."""
        if name in self.files:
            raise ValueError(f"output {name!r} is registered already")
        self.files.append(_plain_name(name))
        return self.folder / name


def _plain_name(name: str) -> str:
    # A hidden or nested name could collide with the staging machinery or escape the output folder.
    if not name or name.startswith(".") or os.sep in name or (os.altsep and os.altsep in name):
        raise ValueError(f"an output must be a plain file name, got {name!r}")
    return name


@contextlib.contextmanager
def staged_outputs(out: Path) -> Iterator[Staging]:
    """Yield a :class:`Staging` to write a run's outputs into; they replace their namesakes in ``out`` together
    when the block ends normally. On any failure or interrupt, in the block or while the files move, ``out`` is
    left as it was and the staging folder (and any folder created for ``out``) is removed.

    Raises:
        OutputError: ``out`` cannot receive the outputs, or writing failed (an ``OSError`` in the block, e.g. a
            full disk); the message names ``out`` and the reason.
    """
    check_destination(out)
    remove_stale_staging(out)
    created = make_parents(out)
    try:
        folder, lock = new_staging_folder(out)
    except OSError as error:
        remove_created(created)
        raise OutputError(f"cannot create output folder {out}: {error.strerror or error}") from None
    staging = Staging(folder)
    try:
        yield staging
        with _interrupts_held() as interrupted:
            _commit(staging, out, interrupted)
            shutil.rmtree(staging.folder, ignore_errors=True)  # the replaced files; gone already for a new folder
    except BaseException as error:
        with _interrupts_held():  # a second Ctrl-C must not leave the clean-up half done
            _discard(staging.folder, created)
        if isinstance(error, OSError):
            raise OutputError(f"cannot write outputs to {out}: {error.strerror or error}") from None
        raise
    finally:
        release(lock)


def _discard(folder: Path, created: Sequence[Path]) -> None:
    """Remove a failed run's staging folder, unless it still holds replaced files that could not be put back."""
    if holds_previous_outputs(folder):
        return  # the message of the error that got here names this folder
    shutil.rmtree(folder, ignore_errors=True)
    remove_created(created)


def _commit(staging: Staging, out: Path, interrupted: Callable[[], bool]) -> None:
    """Move the staged files into ``out``, all or none (see the module docstring); ``interrupted`` tells whether
    Ctrl-C was pressed meanwhile (the moves are then undone)."""
    names = staging.files
    if not existing(out) and _rename_new_folder(staging.folder, out, interrupted):
        return
    check_destination(out, names)  # again: the folder may have changed during the run
    _swap(staging.folder, out, names, interrupted)


def _rename_new_folder(folder: Path, out: Path, interrupted: Callable[[], bool]) -> bool:
    """Rename the staging folder to ``out`` (one atomic step for a new folder); False if ``out`` appeared meanwhile
    and the files must be moved one by one."""
    try:
        os.rename(folder, out)
    except OSError:
        if out.is_dir():
            return False
        raise
    if interrupted():
        os.rename(out, folder)  # Ctrl-C during the rename: the run is abandoned, so is its folder
        raise KeyboardInterrupt
    return True


def _swap(folder: Path, out: Path, names: Sequence[str], interrupted: Callable[[], bool]) -> None:
    """Move the old ``names`` from ``out`` into the staging folder's backup, then the new ones into ``out``; on any
    failure or interrupt, put everything back."""
    backup = folder / BACKUP
    aside: list[str] = []
    placed: list[str] = []
    try:
        for name in names:
            if existing(out / name):
                backup.mkdir(exist_ok=True)
                os.replace(out / name, backup / name)
                aside.append(name)
        for name in names:
            os.replace(folder / name, out / name)
            placed.append(name)
        if interrupted():
            raise KeyboardInterrupt
    except BaseException:
        _restore(out, backup, aside, placed)
        raise


def _restore(out: Path, backup: Path, aside: Sequence[str], placed: Sequence[str]) -> None:
    """Undo :func:`_swap`: remove the new files placed in ``out`` and move the old ones back from ``backup``."""
    try:
        for name in placed:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(out / name)
        for name in aside:
            os.replace(backup / name, out / name)
    except OSError as error:
        # The previous files stay in the backup (``_discard`` keeps it); say where, or they would seem lost.
        raise OutputError(
            f"cannot write outputs to {out}: {error.strerror or error}; the previous files are kept in {backup}"
        ) from None


@contextlib.contextmanager
def _interrupts_held() -> Iterator[Callable[[], bool]]:
    """Hold Ctrl-C (SIGINT) back while the block runs; yields a function telling whether one arrived.

    The block must check it and undo its work when one did; one that arrives after the last check is raised as
    :class:`KeyboardInterrupt` when the block ends (its work is then complete).
    """
    if threading.current_thread() is not threading.main_thread() or signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        yield lambda: False  # only the main thread receives signals; an ignored SIGINT (nohup) stays ignored
        return
    arrived: list[int] = []
    previous = signal.signal(signal.SIGINT, lambda number, frame: arrived.append(number))
    try:
        yield lambda: bool(arrived)
    finally:
        signal.signal(signal.SIGINT, previous if previous is not None else signal.SIG_DFL)
    if arrived:
        raise KeyboardInterrupt
