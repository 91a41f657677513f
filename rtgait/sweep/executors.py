"""Running physics cases in parallel: worker processes on this machine, or a Dask cluster.

Every case runs in a process of its own (:mod:`rtgait.sweep.worker`, started by :func:`run_isolated`), whichever
executor hands it out: a crash or a hang of the simulator ends that process only, and the same code computes the
same numbers everywhere. The rules, the same for both executors:

* a case whose process dies (a signal, an exit without an answer, a Dask worker lost) is run once more; dying again,
  it is recorded as failed with the reason;
* a case still running after ``timeout`` seconds is killed and recorded as failed (not retried: it would take as
  long again);
* a case that fails for a reason of its own (the robot cannot reach the walk) is recorded as failed at once;
* a Dask cluster that returns nothing for ``timeout`` plus :data:`CLUSTER_GRACE` seconds while cases are pending
  fails the cases still pending, so a sweep never hangs.

Results reach the caller's ``on_result(case_id, fields)`` in the calling thread, one case at a time.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import signal
import subprocess
import sys
import tempfile
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait
from typing import Any

from rtgait.sweep.worker import CASE_ERROR

CLUSTER_GRACE = 120.0
"""Seconds beyond the per-case timeout a Dask cluster may stay silent before its pending cases fail."""
RETRIES = 1
"""Extra runs of a case whose process died."""
CONNECT_TIMEOUT = 10.0
"""Seconds to wait for a Dask scheduler to answer before it is reported unreachable."""
WORKER_COMMAND = (sys.executable, "-m", "rtgait.sweep.worker")
"""The process one case runs in (reads the job on stdin, prints one JSON line)."""

Job = dict[str, Any]
OnResult = Callable[[str, dict[str, Any]], None]


def run_isolated(job: Job, timeout: float) -> dict[str, Any]:
    """Run one job in a fresh Python process; ``{"status": "ok", **outcome}``, or ``status`` ``"error"`` (the
    case's own), ``"died"`` (retry it) or ``"timeout"``, with a ``reason``."""
    payload = json.dumps({k: v for k, v in job.items() if k != "id"})
    with tempfile.TemporaryDirectory(prefix="rtgait-sweep-") as folder:  # nothing lands in the working folder
        process = subprocess.Popen(
            list(WORKER_COMMAND), stdin=subprocess.PIPE, stdout=subprocess.PIPE,
            stderr=subprocess.PIPE, text=True, cwd=folder,
        )  # fmt: skip
        _LIVE.add(process)
        try:
            stdout, stderr = process.communicate(payload, timeout=timeout)
        except subprocess.TimeoutExpired:
            process.kill()
            process.communicate()
            return {"status": "timeout", "reason": f"timed out after {timeout:g} s (killed)"}
        finally:
            _LIVE.discard(process)
    done = subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr)
    lines = done.stdout.strip().splitlines()
    try:
        answer = json.loads(lines[-1]) if lines else None
    except ValueError:
        answer = None
    if done.returncode == 0 and isinstance(answer, dict):
        return {"status": "ok", **answer}
    if done.returncode == CASE_ERROR and isinstance(answer, dict):
        return {"status": "error", "reason": str(answer.get("error", "failed"))}
    if done.returncode < 0:
        reason = f"worker killed by {signal.Signals(-done.returncode).name}"
    else:
        tail = (done.stderr.strip().splitlines() or ["no output"])[-1]
        reason = f"worker exited with code {done.returncode}: {tail}"
    return {"status": "died", "reason": reason}


_LIVE: set[subprocess.Popen] = set()
"""Case processes running now, for :func:`stop_all`."""


def stop_all() -> None:
    """Kill every case process still running (an interrupted sweep does not wait for them)."""
    for process in list(_LIVE):
        with contextlib.suppress(OSError):
            process.kill()


def outcome_fields(result: dict[str, Any]) -> dict[str, Any]:
    """The physics columns of a case from a :func:`run_isolated` result."""
    if result["status"] == "ok":
        keys = ("fell", "tipped", "fall_time", "steps_completed", "steps_planned")
        return {"physics": "ok", **{k: result.get(k) for k in keys}, "physics_error": ""}
    return {
        "physics": "failed", "fell": None, "tipped": None, "fall_time": None, "steps_completed": None,
        "steps_planned": None, "physics_error": result["reason"],
    }  # fmt: skip


class _Attempts:
    """Which cases to run again after their process died (the rule of the module docstring)."""

    def __init__(self) -> None:
        self.count: dict[str, int] = {}

    def retry(self, job: Job, result: dict[str, Any]) -> bool:
        if result["status"] != "died":
            return False
        runs = self.count[job["id"]] = self.count.get(job["id"], 0) + 1
        if runs > RETRIES:
            result["reason"] = f"died {runs} times: {result['reason']}"
            return False
        return True


class LocalExecutor:
    """``workers`` cases at a time on this machine, each in its own process."""

    def __init__(self, workers: int | None = None) -> None:
        self.workers = max(1, workers or os.cpu_count() or 1)

    def run(self, jobs: Sequence[Job], timeout: float, on_result: OnResult) -> None:
        attempts = _Attempts()
        with ThreadPoolExecutor(max_workers=self.workers, thread_name_prefix="rtgait-sweep") as pool:
            running: dict[Future, Job] = {pool.submit(run_isolated, job, timeout): job for job in jobs}
            try:
                while running:
                    finished, _ = wait(running, return_when=FIRST_COMPLETED)
                    for future in finished:
                        job = running.pop(future)
                        result = future.result()
                        if attempts.retry(job, result):
                            running[pool.submit(run_isolated, job, timeout)] = job
                        else:
                            on_result(job["id"], outcome_fields(result))
            except BaseException:
                for future in running:
                    future.cancel()  # those not started yet
                stop_all()  # and those running: an interrupted sweep keeps only finished cases
                raise


@contextlib.contextmanager
def _dask_logs(level: int) -> Iterator[None]:
    """Dask's log lines in this process at ``level`` and above only, while the block runs: the handlers of its
    ``distributed`` logger, which every ``distributed.*`` logger reaches, and those of ``bokeh`` (its dashboard)."""
    handlers = {
        handler: handler.level for name in ("distributed", "bokeh") for handler in logging.getLogger(name).handlers
    }
    for handler, previous in handlers.items():  # one handler may serve both loggers: each is set and restored once
        handler.setLevel(max(previous, level))
    try:
        yield
    finally:
        for handler, previous in handlers.items():
            handler.setLevel(previous)


class DaskExecutor:
    """Cases on a Dask cluster: ``address`` of its scheduler, or ``"local"`` for a
    :class:`distributed.LocalCluster` of ``workers`` single-threaded worker processes on this machine. ``quiet``:
    Dask's warnings are not shown (only its errors), here and in the local cluster's processes."""

    def __init__(
        self, address: str, workers: int | None = None, connect_timeout: float | None = None, quiet: bool = False
    ) -> None:
        try:
            import distributed
        except ImportError:
            raise RuntimeError("--scheduler needs dask.distributed: pip install 'dask[distributed]'") from None
        self._cluster = None
        log_level = logging.ERROR if quiet else logging.WARNING  # WARNING: LocalCluster's own default
        self._logs = contextlib.ExitStack()
        if quiet:
            self._logs.enter_context(_dask_logs(log_level))
        connect_timeout = CONNECT_TIMEOUT if connect_timeout is None else connect_timeout
        try:
            if address == "local":
                self._cluster = distributed.LocalCluster(
                    n_workers=max(1, workers or os.cpu_count() or 1), threads_per_worker=1, processes=True,
                    dashboard_address=None, silence_logs=log_level,  # the workers' processes log at it too
                )  # fmt: skip
                self.client = distributed.Client(self._cluster, timeout=connect_timeout)
            else:
                self.client = distributed.Client(address, timeout=connect_timeout)
        except (OSError, TimeoutError, ValueError) as error:
            self.close()
            reason = " ".join(str(error).split()) or type(error).__name__
            raise ValueError(f"--scheduler {address}: cannot reach the Dask scheduler ({reason})") from None

    def run(self, jobs: Sequence[Job], timeout: float, on_result: OnResult) -> None:
        from distributed import wait as dask_wait

        attempts = _Attempts()
        tries: dict[str, int] = {}

        def submit(job: Job):
            tries[job["id"]] = tries.get(job["id"], 0) + 1
            key = f"rtgait-sweep-{job['id']}-{tries[job['id']]}"
            return self.client.submit(run_isolated, job, timeout, key=key, pure=False, retries=0)

        running = {submit(job): job for job in jobs}
        try:
            while running:
                finished = dask_wait(list(running), timeout=timeout + CLUSTER_GRACE, return_when="FIRST_COMPLETED")
                if not finished.done:
                    raise TimeoutError
                for future in finished.done:
                    job = running.pop(future)
                    try:
                        result = future.result()
                    except Exception as error:  # the Dask worker died (KilledWorker) or the task was lost
                        result = {"status": "died", "reason": " ".join(f"{type(error).__name__}: {error}".split())}
                    if attempts.retry(job, result):
                        running[submit(job)] = job
                    else:
                        on_result(job["id"], outcome_fields(result))
        except TimeoutError:
            silent = f"no answer from the Dask cluster for {timeout + CLUSTER_GRACE:g} s"
            for future, job in running.items():
                future.cancel()
                on_result(job["id"], outcome_fields({"status": "died", "reason": silent}))
        except BaseException:
            for future in running:
                future.cancel()
            raise

    def close(self) -> None:
        try:
            client = getattr(self, "client", None)
            if client is not None:
                client.close()
            if self._cluster is not None:
                self._cluster.close()
        finally:
            self._logs.close()  # after the cluster: it may warn while its workers stop


__all__ = [
    "CLUSTER_GRACE", "RETRIES", "DaskExecutor", "LocalExecutor", "outcome_fields", "run_isolated", "stop_all",
]  # fmt: skip
