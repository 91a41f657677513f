"""Writing output files so that a reader finds the whole old result or the whole new one, never a mix.

Two tools, standard library only, for every file rtgait writes:

* :func:`write_atomic` (and :func:`write_text_atomic`) for one file: written under a hidden temporary name beside
  it and renamed over it when complete.
* :func:`staged_outputs` for a run's set of files: they are written into a staging folder; when all are complete
  they replace their namesakes in the output folder together. Replacing moves the old files aside into the
  staging folder first, so any failure or Ctrl-C while the files move puts the old ones back: the folder ends
  with the complete new set or unchanged. Files of other names in the output folder are never touched.

A run killed outright (SIGKILL, a power cut) cannot clean up: its staging folder stays. The next run into the same
output folder removes it, and only it: a staging folder's name holds its owner's host and process id, and its owner
holds a lock on it (``flock``) while it lives, so a folder is removed only when it was made on this host by a process
that no longer exists and nobody holds its lock. One that still holds previous outputs (the run was killed while
the files moved) is kept, with a warning naming it.

:func:`check_destination` tells, before a long run, whether its outputs could be written at all. Every problem
is an :class:`OutputError` with a one-line message.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import signal
import socket
import threading
import uuid
import warnings
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

__all__ = [
    "OutputError", "Staging", "check_destination", "create_folder", "remove_stale_staging", "staged_outputs",
    "write_atomic", "write_text_atomic",
]  # fmt: skip

_BACKUP = ".previous"
"""Folder inside the staging folder that holds the files being replaced until the new ones are all in place."""
_STAGING = "rtgait-staging"
"""The word in every staging folder's name: ``.rtgait-staging.HOST.PID.XXXXXXXX.tmp`` inside the output folder, or
``.NAME.rtgait-staging.HOST.PID.XXXXXXXX.tmp`` beside an output folder ``NAME`` that does not exist yet."""
_STAGING_NAME = re.compile(
    r"\.(?:(?P<prefix>.+)\.)?" + _STAGING + r"\.(?P<host>[A-Za-z0-9-]+)\.(?P<pid>[0-9]+)\.[0-9a-f]{8}\.tmp"
)
_PREFIX_LENGTH = 64
"""Characters of an output's name kept in the name of its staging folder or temporary file beside it: the whole name
would make that name longer than a file system allows (255 bytes) for an output name that is itself fine."""


class OutputError(Exception):
    """Outputs cannot be written where asked (not a folder, not writable, a disk error). One line."""


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


def _writable(path: Path) -> bool:
    """Whether we may create and rename entries in the folder ``path``, or replace the file ``path``."""
    return os.access(path, os.W_OK | os.X_OK) if path.is_dir() else os.access(path, os.W_OK)


def _existing(path: Path) -> bool:
    return path.exists() or path.is_symlink()  # a dangling link is in the way too


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
    if _existing(out):
        if not out.is_dir():
            raise OutputError(f"{where} it exists and is not a folder")
        if not _writable(out):
            raise OutputError(f"{where} the folder is not writable")
        for name in names:
            target = out / name
            if target.is_dir() and not target.is_symlink():
                raise OutputError(f"{where} {target} is a folder")
            if target.exists() and not _writable(target):
                raise OutputError(f"{where} {target} is read-only")
        return
    ancestor = next((path for path in out.parents if _existing(path)), None)
    if ancestor is None:  # only when the working folder itself was deleted
        raise OutputError(f"{where} no folder above it exists")
    if not ancestor.is_dir():
        raise OutputError(f"{where} {ancestor} is not a folder")
    if not _writable(ancestor):
        raise OutputError(f"{where} {ancestor} is not writable")


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
    created = _make_parents(out)
    try:
        folder, lock = _new_staging_folder(out)
    except OSError as error:
        _remove_created(created)
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
        _release(lock)


def _make_parents(out: Path) -> list[Path]:
    """Create the missing folders above ``out``; returns them, deepest first, to remove them after a failure."""
    missing = [path for path in out.parents if not _existing(path)]
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        _remove_created(missing)
        raise OutputError(f"cannot create output folder {out}: {error.strerror or error}") from None
    return missing


def create_folder(out: Path) -> None:
    """Create the folder ``out`` and the missing folders above it, for outputs written straight into it (a sweep's).

    Raises:
        OutputError: a folder cannot be created; those created before are removed.
    """
    missing = [path for path in (out, *out.parents) if not _existing(path)]
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        _remove_created(missing)
        raise OutputError(f"cannot create output folder {out}: {error.strerror or error}") from None


def _remove_created(folders: Sequence[Path]) -> None:
    for folder in folders:  # deepest first; rmdir refuses a folder someone has put something in meanwhile
        with contextlib.suppress(OSError):
            folder.rmdir()


def _host() -> str:
    """This machine's name as a staging folder's name holds it: letters, digits and '-' only."""
    return re.sub(r"[^A-Za-z0-9-]", "-", socket.gethostname())[:_PREFIX_LENGTH] or "host"


def _new_staging_folder(out: Path) -> tuple[Path, int | None]:
    """A fresh hidden folder on the same file system as ``out``: inside it when it exists, else beside it; and the
    descriptor holding its lock (``None`` where locks are not available), to release when the outputs are in place."""
    tag = f"{_STAGING}.{_host()}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp"
    staging = out / f".{tag}" if out.is_dir() else out.parent / f".{out.name[:_PREFIX_LENGTH]}.{tag}"
    # Not tempfile.mkdtemp: its 0700 mode would survive the rename and surprise anyone sharing the results.
    staging.mkdir()
    return staging, _lock(staging)


def _lock(folder: Path) -> int | None:
    """Take the lock that tells other runs the staging ``folder`` is in use, and return its descriptor; the system
    releases it when the process ends, however it ends. ``None`` where there is no ``flock`` (Windows) or the file
    system refuses it.

    Raises:
        BlockingIOError: another process holds the lock.
    """
    try:
        import fcntl
    except ImportError:
        return None
    try:
        descriptor = os.open(folder, os.O_RDONLY)
    except OSError:
        return None
    try:
        fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as error:
        os.close(descriptor)
        if isinstance(error, BlockingIOError):
            raise
        return None
    return descriptor


def _release(lock: int | None) -> None:
    if lock is not None:
        with contextlib.suppress(OSError):
            os.close(lock)  # closing the last descriptor releases the lock


def remove_stale_staging(out: Path) -> list[Path]:
    """Remove the staging folders that runs into ``out`` killed outright left behind (module docstring); returns
    the folders removed. A folder that may belong to a live run, or that holds previous outputs, is kept."""
    places = [(out, None), (out.parent, out.name[:_PREFIX_LENGTH])]
    removed = []
    for folder, prefix in places:
        try:
            entries = list(os.scandir(folder))
        except OSError:  # no such folder yet, or unreadable: nothing of ours can be there
            continue
        for entry in entries:
            match = _STAGING_NAME.fullmatch(entry.name)
            if match is None or match["prefix"] != prefix or not _is_folder(entry):
                continue
            path = Path(entry.path)
            if not _abandoned(path, match["host"], int(match["pid"])):
                continue
            if _holds_previous_outputs(path):
                warnings.warn(
                    f"{path} holds the previous outputs of a run killed while it replaced them in {out}: kept (move "
                    "them back, or remove the folder)",
                    stacklevel=2,
                )
                continue
            shutil.rmtree(path, ignore_errors=True)
            removed.append(path)
    return removed


def _is_folder(entry: os.DirEntry[str]) -> bool:
    try:
        return entry.is_dir(follow_symlinks=False)  # a link is never ours to follow
    except OSError:
        return False


def _abandoned(folder: Path, host: str, pid: int) -> bool:
    """Whether the staging ``folder`` of process ``pid`` on ``host`` belongs to no live run: made on this host, by a
    process that no longer exists, and unlocked. A process id reused since is taken for the owner (kept: safe)."""
    if host != _host() or pid == os.getpid() or os.name != "posix":  # os.kill(pid, 0) is no probe on Windows
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        pass  # no such process
    except OSError:
        return False  # it exists (another user's): alive
    else:
        return False
    # The same host name may hide another process namespace (a container), where the owner has another id: its lock
    # tells. Taken now, it is released at once: the folder is removed next.
    try:
        _release(_lock(folder))
    except BlockingIOError:
        return False
    return True


def _holds_previous_outputs(folder: Path) -> bool:
    """Whether the staging ``folder`` holds replaced files that were not put back (or cannot tell)."""
    backup = folder / _BACKUP
    try:
        return backup.is_dir() and any(backup.iterdir())
    except OSError:
        return True  # cannot tell: keep it


def _discard(folder: Path, created: Sequence[Path]) -> None:
    """Remove a failed run's staging folder, unless it still holds replaced files that could not be put back."""
    if _holds_previous_outputs(folder):
        return  # the message of the error that got here names this folder
    shutil.rmtree(folder, ignore_errors=True)
    _remove_created(created)


def _commit(staging: Staging, out: Path, interrupted: Callable[[], bool]) -> None:
    """Move the staged files into ``out``, all or none (see the module docstring); ``interrupted`` tells whether
    Ctrl-C was pressed meanwhile (the moves are then undone)."""
    names = staging.files
    if not _existing(out) and _rename_new_folder(staging.folder, out, interrupted):
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
    backup = folder / _BACKUP
    aside: list[str] = []
    placed: list[str] = []
    try:
        for name in names:
            if _existing(out / name):
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


def write_atomic(path: str | os.PathLike[str], write: Callable[[Path], None]) -> Path:
    """Write one file: ``write`` fills a hidden temporary file beside ``path``, which is then renamed over
    ``path``, so ``path`` is never seen half written. Returns ``path``.

    Raises:
        Whatever ``write`` raises, or ``OSError``; the temporary file is removed then and ``path`` is unchanged.
    """
    target = Path(path)
    # The name cut short: a target whose name is near the file system's limit would make the temporary one too long.
    temporary = target.with_name(f".{target.name[:_PREFIX_LENGTH]}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp")
    try:
        write(temporary)
        os.replace(temporary, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temporary)
        raise
    return target


def write_text_atomic(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` with :func:`write_atomic`; returns ``path``."""

    def write(temporary: Path) -> None:
        # Mode "x": never write into a file that is already there; the new file honours the umask like any other.
        with open(temporary, "x", encoding="utf-8") as stream:
            stream.write(text)

    return write_atomic(path, write)
