"""Staging folders: their names, their locks, and the removal of those that runs killed outright left behind.

A staging folder is named ``.rtgait-staging.HOST.PID.XXXXXXXX.tmp`` inside the output folder, or
``.NAME.rtgait-staging.HOST.PID.XXXXXXXX.tmp`` beside an output folder ``NAME`` that does not exist yet. Its owner
holds a lock on it (``flock``) while it lives, so a folder is removed only when it was made on this host by a
process that no longer exists and nobody holds its lock. One that still holds previous outputs (the run was killed
while the files moved) is kept, with a warning naming it.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import socket
import uuid
import warnings
from pathlib import Path

from rtgait.outputs.atomic import PREFIX_LENGTH

__all__ = ["BACKUP", "holds_previous_outputs", "host", "new_staging_folder", "release", "remove_stale_staging"]

BACKUP = ".previous"
"""Folder inside the staging folder that holds the files being replaced until the new ones are all in place."""
_STAGING = "rtgait-staging"
"""The word in every staging folder's name (module docstring)."""
_STAGING_NAME = re.compile(
    r"\.(?:(?P<prefix>.+)\.)?" + _STAGING + r"\.(?P<host>[A-Za-z0-9-]+)\.(?P<pid>[0-9]+)\.[0-9a-f]{8}\.tmp"
)


def host() -> str:
    """This machine's name as a staging folder's name holds it: letters, digits and '-' only."""
    return re.sub(r"[^A-Za-z0-9-]", "-", socket.gethostname())[:PREFIX_LENGTH] or "host"


def new_staging_folder(out: Path) -> tuple[Path, int | None]:
    """A fresh hidden folder on the same file system as ``out``: inside it when it exists, else beside it; and the
    descriptor holding its lock (``None`` where locks are not available), to release when the outputs are in place."""
    tag = f"{_STAGING}.{host()}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp"
    staging = out / f".{tag}" if out.is_dir() else out.parent / f".{out.name[:PREFIX_LENGTH]}.{tag}"
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


def release(lock: int | None) -> None:
    """Release a staging folder's lock taken by :func:`new_staging_folder`."""
    if lock is not None:
        with contextlib.suppress(OSError):
            os.close(lock)  # closing the last descriptor releases the lock


def remove_stale_staging(out: Path) -> list[Path]:
    """Remove the staging folders that runs into ``out`` killed outright left behind (module docstring); returns
    the folders removed. A folder that may belong to a live run, or that holds previous outputs, is kept."""
    places = [(out, None), (out.parent, out.name[:PREFIX_LENGTH])]
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
            if holds_previous_outputs(path):
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


def _abandoned(folder: Path, owner_host: str, pid: int) -> bool:
    """Whether the staging ``folder`` of process ``pid`` on ``owner_host`` belongs to no live run: made on this host,
    by a process that no longer exists, and unlocked. A process id reused since is taken for the owner (kept: safe)."""
    if owner_host != host() or pid == os.getpid() or os.name != "posix":  # os.kill(pid, 0) is no probe on Windows
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
        release(_lock(folder))
    except BlockingIOError:
        return False
    return True


def holds_previous_outputs(folder: Path) -> bool:
    """Whether the staging ``folder`` holds replaced files that were not put back (or cannot tell)."""
    backup = folder / BACKUP
    try:
        return backup.is_dir() and any(backup.iterdir())
    except OSError:
        return True  # cannot tell: keep it
