"""One output file written under a hidden temporary name beside it and renamed over it when complete."""

from __future__ import annotations

import contextlib
import os
import uuid
from collections.abc import Callable
from pathlib import Path

__all__ = ["PREFIX_LENGTH", "write_atomic", "write_text_atomic"]

PREFIX_LENGTH = 64
"""Characters of an output's name kept in the name of its staging folder or temporary file beside it: the whole name
would make that name longer than a file system allows (255 bytes) for an output name that is itself fine."""


def write_atomic(path: str | os.PathLike[str], write: Callable[[Path], None]) -> Path:
    """Write one file: ``write`` fills a hidden temporary file beside ``path``, which is then renamed over
    ``path``, so ``path`` is never seen half written. Returns ``path``.

    Raises:
        Whatever ``write`` raises, or ``OSError``; the temporary file is removed then and ``path`` is unchanged.
    """
    target = Path(path)
    # The name cut short: a target whose name is near the file system's limit would make the temporary one too long.
    temporary = target.with_name(f".{target.name[:PREFIX_LENGTH]}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp")
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
