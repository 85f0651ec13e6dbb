"""Parallel map over independent work items with a progress bar.

A local process pool (spawn, so no state leaks from the parent) by default; Ray when the user gives a cluster
address, or ``"local"`` for a private Ray instance on this machine with ``workers`` CPUs (what the tests use).
On 2-core machines the pool beats Ray and Dask on start-up and memory (reference/stack-measurements.md section
2.7); Ray is an optional extra (``pip install centerart[cluster]``).
"""

from __future__ import annotations

import multiprocessing as mp
import os
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any, TypeVar

from tqdm.auto import tqdm

from centerart.errors import CenterArtError

#: Items per worker of one pool: about what each worker runs before fresh processes replace it (the pool hands
#: items out as workers free up, so a slow worker runs fewer and a fast one more). A scene worker grows with every
#: scene it renders: a slice's 4,000 kitchen scenes on 2 workers made one the kernel's out-of-memory victim at 12 GB
#: after about 1,800 scenes (session 22). A fresh worker costs a few seconds of imports.
WORKER_MAX_TASKS = 200

T = TypeVar("T")
R = TypeVar("R")


def launcher_rank() -> int:
    """This process's rank when a launcher started several copies of the command (torchrun: RANK; SLURM:
    SLURM_PROCID; MPI; Lightning's own DDP launcher: LOCAL_RANK / NODE_RANK); 0 for a process started alone."""
    for key in ("RANK", "SLURM_PROCID", "OMPI_COMM_WORLD_RANK"):
        if key in os.environ:
            return int(os.environ[key])
    return int(os.environ.get("LOCAL_RANK", 0)) or int(os.environ.get("NODE_RANK", 0))


def default_workers() -> int:
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1))


def parallel_map(
    fn: Callable[[T], R],
    items: Iterable[T],
    workers: int | None = None,
    desc: str = "",
    ray_address: str | None = None,
    disable_progress: bool = False,
) -> Iterator[R]:
    """Apply ``fn`` to every item, yielding results as they complete (order not kept).

    ``workers=1`` runs in this process (easy to debug and profile). ``fn`` must be a module-level function so
    that it pickles. ``ray_address``: a Ray cluster's address, or ``"local"``; when this call initialised Ray it
    also shuts it down (an instance the caller initialised is used as it is and left running).
    """
    items = list(items)
    workers = default_workers() if workers is None else max(1, workers)
    bar = tqdm(total=len(items), desc=desc, unit="item", disable=disable_progress or not items)
    try:
        if ray_address:
            yield from _ray_map(fn, items, ray_address, workers, bar)
        elif workers == 1 or len(items) <= 1:
            for item in items:
                yield fn(item)
                bar.update()
        else:
            yield from _pool_map(fn, items, workers, bar)
    finally:
        bar.close()


def _pool_map(fn: Callable[[T], R], items: list[T], workers: int, bar) -> Iterator[R]:
    """A fresh spawn pool per ``workers * WORKER_MAX_TASKS`` items, so no worker lives through more than one pool's
    share (the cores wait at each pool's last items: a few seconds per pool, beside minutes of work).

    Written here rather than with the executor's ``max_tasks_per_child``: on Python 3.11 a pool whose workers
    reach that quota is not refilled and hangs (CPython gh-115634, fixed only in later versions)."""
    ctx = mp.get_context("spawn")
    n = min(workers, len(items))
    chunk = n * WORKER_MAX_TASKS
    for start in range(0, len(items), chunk):
        with ProcessPoolExecutor(max_workers=n, mp_context=ctx) as pool:
            futures = [pool.submit(fn, item) for item in items[start : start + chunk]]
            for fut in as_completed(futures):
                yield fut.result()
                bar.update()


def init_ray(address: str, workers: int | None = None) -> bool:
    """Connect to the Ray cluster at ``address`` (``"local"``: start a private instance with ``workers`` CPUs) unless
    Ray is already initialised; returns whether this call initialised it (the caller then shuts it down).

    A caller that runs several :func:`parallel_map` calls (the recipe) initialises Ray once with it, so that each
    call does not start and stop its own local instance (about 10 s each)."""
    try:
        import ray
    except ImportError as err:
        raise CenterArtError(
            "--ray-address was given but Ray is not installed; install it with `pip install centerart[cluster]`"
        ) from err
    if ray.is_initialized():
        return False
    # A cluster decides its own CPUs; only a private local instance takes the worker count.
    local = {"num_cpus": workers or default_workers()} if address == "local" else {}
    ray.init(address=address, ignore_reinit_error=True, include_dashboard=False, **local)
    return True


def _ray_map(fn: Callable[[Any], Any], items: list[Any], address: str, workers: int, bar: tqdm) -> Iterator[Any]:
    started_here = init_ray(address, workers)
    import ray

    try:
        remote = ray.remote(fn)
        pending = [remote.remote(item) for item in items]
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            for ref in done:
                yield ray.get(ref)
                bar.update()
    finally:
        if started_here:
            ray.shutdown()
