"""Producing episodes in parallel: worker processes on this machine, or Ray tasks.

Every episode depends on (design, index, seed) alone, and each worker encodes its own video,
so the dataset is byte-identical whatever the number of workers or the backend. Results come
back in episode order; the writer (in the calling process) only ever sees whole, verified
episodes. A worker that dies mid-episode loses nothing that was written: its unfinished
episodes are redone by a fresh pool, and the run stops with a clear error if crashes repeat.
A mix of referent types (gen/planning/mix.py) gives each worker one Producer per type, made when its
first episode of that type comes.
"""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
import os
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from core.spec import Setup
from gen.planning import mix
from gen.products.produce import Produced, Producer
from jobs import faults
from jobs.processes import die_with
from referents.design import Design

MAX_POOL_RESTARTS = 2


class WorkerCrash(RuntimeError):
    """Worker processes kept dying; the message says how often and on which episode."""


@dataclass(frozen=True)
class Job:
    """What a worker needs to build its own Producers: how to load each referent type (those of a
    mix take turns, gen/planning/mix.py: its name, its spec overrides, the setup of its world)."""

    referents: tuple[tuple[str, dict[str, Any], Setup], ...]
    spec_path: str | None
    codec: str
    seed: int
    max_attempts: int
    split: str = "train"

    def producer(self, place: int) -> Producer:
        from referents import registry

        name, overrides, setup = self.referents[place]
        return Producer(registry.load(name, self.spec_path, overrides, setup.world), setup, self.codec)


_producers: dict[int, Producer] = {}  # one per referent type, in each worker process
_job: Job | None = None


def _init(job: Job) -> None:
    global _job
    _producers.clear()
    _job = job


def _init_process(job: Job, parent: int) -> None:
    die_with(parent)
    _init(job)


def _produce(index: int, design: Design) -> Produced:
    assert _job is not None
    faults.point(f"worker:{index}")
    place = mix.turn(index, len(_job.referents))
    if place not in _producers:
        _producers[place] = _job.producer(place)
    return _producers[place].produce(design, index, _job.seed, _job.max_attempts)


def produce(job: Job, plan: list[Design], workers: int = 1, backend: str = "process", start: int = 0) -> Iterator[Produced]:
    """Produced episodes `start`, `start + 1`, ... of `plan`, in order."""
    if backend == "ray":
        yield from _ray(job, plan, workers, start)
    elif workers <= 1:
        _init(job)
        try:
            for i in range(start, len(plan)):
                yield _produce(i, plan[i])
        finally:
            for producer in _producers.values():
                producer.close()
    else:
        yield from _processes(job, plan, workers, start)


def _processes(job: Job, plan: list[Design], workers: int, start: int) -> Iterator[Produced]:
    next_index, restarts = start, 0
    while next_index < len(plan):
        context = multiprocessing.get_context("spawn")
        initargs = (job, os.getpid())
        with cf.ProcessPoolExecutor(workers, mp_context=context, initializer=_init_process, initargs=initargs) as pool:
            window: dict[int, cf.Future] = {}
            submitted = next_index
            try:
                while next_index < len(plan):
                    while submitted < len(plan) and len(window) < 2 * workers:
                        window[submitted] = pool.submit(_produce, submitted, plan[submitted])
                        submitted += 1
                    produced = window.pop(next_index).result()
                    next_index += 1
                    yield produced
            except cf.process.BrokenProcessPool:
                restarts += 1
                if restarts > MAX_POOL_RESTARTS:
                    raise WorkerCrash(
                        f"a worker process died {restarts} times while producing episodes {next_index}-{submitted - 1}; "
                        f"the {next_index} episodes before them are saved and resume=true continues from there"
                    ) from None
                for future in window.values():
                    future.cancel()


def _ray(job: Job, plan: list[Design], workers: int, start: int) -> Iterator[Produced]:
    import ray
    from ray.util import ActorPool

    if not ray.is_initialized():
        address = os.environ.get("RAY_ADDRESS")
        ray.init(
            address=address,
            num_cpus=None if address else workers,
            include_dashboard=False,
            log_to_driver=False,
            configure_logging=False,
        )

    @ray.remote
    class Worker:
        def __init__(self, job: Job) -> None:
            _init(job)

        def produce(self, index: int, design: Design) -> Produced:
            return _produce(index, design)

    pool = ActorPool([Worker.remote(job) for _ in range(max(1, workers))])
    try:
        yield from pool.map(lambda actor, item: actor.produce.remote(*item), [(i, plan[i]) for i in range(start, len(plan))])
    except ray.exceptions.RayActorError as exc:
        raise WorkerCrash(f"a Ray worker died ({exc.__class__.__name__}); nothing unfinished was written") from None
