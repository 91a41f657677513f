"""Writing output files so that a reader finds the whole old result or the whole new one, never a mix.

Two tools, standard library only, for every file rtgait writes:

* :func:`write_atomic` (and :func:`write_text_atomic`) for one file: written under a hidden temporary name beside
  it and renamed over it when complete (:mod:`.atomic`).
* :func:`staged_outputs` for a run's set of files: they are written into a staging folder; when all are complete
  they replace their namesakes in the output folder together. Replacing moves the old files aside into the
  staging folder first, so any failure or Ctrl-C while the files move puts the old ones back: the folder ends
  with the complete new set or unchanged. Files of other names in the output folder are never touched
  (:mod:`.staged`).

A run killed outright (SIGKILL, a power cut) cannot clean up: its staging folder stays. The next run into the same
output folder removes it, and only it (:mod:`.staging_folders`).

:func:`check_destination` tells, before a long run, whether its outputs could be written at all. Every problem
is an :class:`OutputError` with a one-line message (:mod:`.destination`).
"""

from rtgait.outputs.atomic import write_atomic, write_text_atomic
from rtgait.outputs.destination import OutputError, check_destination, create_folder
from rtgait.outputs.staged import Staging, staged_outputs
from rtgait.outputs.staging_folders import remove_stale_staging

__all__ = [
    "OutputError", "Staging", "check_destination", "create_folder", "remove_stale_staging", "staged_outputs",
    "write_atomic", "write_text_atomic",
]  # fmt: skip
