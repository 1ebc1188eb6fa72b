"""Several models built at once: each build's C compile, most of its time, runs beside the
others', one a core (fmu_build lets one build at a time run rumoca and CasADi:
:data:`fmu_build.fmu_export.PYTHON_SIDE`). The builds run in threads of this process, so
a stop (Ctrl-C, SIGTERM) waits for those under way, each of which removes its own scratch
folder, and starts no other."""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import TypeVar

T = TypeVar("T")
R = TypeVar("R")


def each_built(build: Callable[[T], R], items: Sequence[T], n_jobs: int | None = None
               ) -> list[R]:
    """``build(item)`` of each of ``items``, in their order, ``n_jobs`` at once (default:
    every core). A build's exception is raised here in the items' order, after the
    builds under way have ended; those not started by then never are."""
    jobs = min(n_jobs or os.cpu_count() or 1, len(items))
    if jobs <= 1:
        return [build(item) for item in items]
    pool = ThreadPoolExecutor(jobs, thread_name_prefix="pydiag-build")
    try:
        futures = [pool.submit(build, item) for item in items]
        return [future.result() for future in futures]
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
