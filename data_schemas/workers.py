"""Local worker processes that never outlive the run that started them.

``arco build-db`` and ``arco train`` both run their jobs on a local process pool; this is
the one place both packages reach (``gesture_db`` and ``pipelines`` share only
``data_schemas``). Each worker:

- asks Linux to kill it when its parent dies (``prctl(PR_SET_PDEATHSIG, SIGKILL)``
  through ``ctypes``), and
- runs a watchdog thread that exits the worker once its parent process is gone (for other
  systems, and for the moment before the ``prctl`` call took effect);
- ignores SIGINT: Ctrl-C reaches the whole terminal process group, and the parent, not each
  worker, decides what to do with it -- :func:`process_pool` then stops every worker.

Examples
--------
>>> with process_pool(2) as pool:
...     sorted(pool.map(abs, [-2, 1]))
[1, 2]
"""

from __future__ import annotations

import os
import signal
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pragma: no cover - typing only
    from concurrent.futures import ProcessPoolExecutor

#: How often (s) a worker's watchdog checks that its parent is alive.
WATCH_INTERVAL = 0.25

_PR_SET_PDEATHSIG = 1


def _die_with_parent() -> None:
    """Linux: SIGKILL this process when the thread that started it ends (best effort)."""
    if not sys.platform.startswith("linux"):
        return
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    except (OSError, AttributeError):  # pragma: no cover - no prctl: the watchdog remains
        pass


def _watch(parent: int) -> None:
    import time

    while os.getppid() == parent:
        time.sleep(WATCH_INTERVAL)
    os._exit(1)


def watch_parent(parent: int) -> None:
    """Pool initializer: tie this worker's life to process ``parent``.

    Parameters
    ----------
    parent : int
        Process id of the run that started the pool.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _die_with_parent()
    if os.getppid() != parent:  # the parent died before prctl took effect
        os._exit(1)
    threading.Thread(target=_watch, args=(parent,), name="arco-parent-watch",
                     daemon=True).start()


@contextmanager
def process_pool(workers: int, *, context: str | None = None) -> Iterator[ProcessPoolExecutor]:
    """A process pool whose workers die with this process, and stop on any error here.

    Parameters
    ----------
    workers : int
        Number of worker processes.
    context : {"fork", "spawn", "forkserver"}, optional
        Multiprocessing start method (default: the platform's).

    Yields
    ------
    concurrent.futures.ProcessPoolExecutor
        On an exception in the ``with`` block (Ctrl-C included) the workers are terminated
        before it propagates; on success the pool shuts down normally.
    """
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    pool = ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context(context),
                               initializer=watch_parent, initargs=(os.getpid(),))
    try:
        yield pool
    except BaseException:
        stop_pool(pool)
        raise
    pool.shutdown(wait=True)


def stop_pool(pool: ProcessPoolExecutor) -> None:
    """Terminate a pool's workers now and drop its queued jobs."""
    procs = dict(getattr(pool, "_processes", None) or {})  # pid -> Process (CPython)
    for proc in procs.values():
        try:
            proc.terminate()
        except OSError:  # pragma: no cover - already gone
            pass
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in procs.values():
        proc.join(timeout=5)


__all__ = ["WATCH_INTERVAL", "process_pool", "stop_pool", "watch_parent"]
