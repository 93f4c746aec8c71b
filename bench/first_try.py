"""How often the oracle's first try succeeds, demonstrated without rendering (physics is cheap).

    python bench/first_try.py referent=color world=libero_spatial n=100 [seed=0] [workers=2]

Plans `n` episodes exactly as `python -m gen` with the same options would, and demonstrates
each one's first realisation (attempt 0) with the oracle, nothing rendered or written: the
first-try rate the docs' generation figures quote, with a Wilson 95% interval, the failed
episodes and why, and the mean episode length in control steps.
"""

from __future__ import annotations

import concurrent.futures as cf
import sys
import time
from dataclasses import dataclass
from typing import Optional

from core.rates import wilson
from gen.config import GenConfig, validate
from gen.planning.plan import plan_and_audit
from jobs.cli import main


@dataclass
class OracleOptions:
    referent: str = "object"  # a referent type (referents/<type>.yaml)
    world: Optional[str] = None  # a world that carries it (default: its own)
    n: int = 100  # episodes planned
    seed: int = 0
    workers: int = 2  # processes demonstrating episodes


_producers: dict = {}


def _first_try(cfg: GenConfig, index: int) -> tuple[int, bool, str, int]:
    """(episode, success, why not, control steps) of the first realisation of episode `index`."""
    from gen.planning.plan import realize
    from gen.products.produce import Producer
    from oracle.episode import demonstrate

    if "planned" not in _producers:
        planned = plan_and_audit(cfg)
        share = planned.only
        _producers["planned"] = planned
        _producers["producer"] = Producer(share.referent, share.setup)
    planned, producer = _producers["planned"], _producers["producer"]
    spec = realize(producer.referent, planned.designs[index], index, cfg.seed, producer.setup, 0, cfg.split)
    demo = demonstrate(producer.scene, producer.ik, spec, producer.referent.demo)
    return index, demo.success, demo.failure, len(demo.actions)


def bench(options: OracleOptions) -> None:
    cfg = GenConfig(referent=options.referent, world=options.world, n=options.n, seed=options.seed, plan_only=True)
    cfg.out = "/tmp/deconfound-oracle-bench"  # never written: validation wants a place
    validate(cfg)
    started = time.perf_counter()
    with cf.ProcessPoolExecutor(max(1, options.workers)) as pool:
        results = sorted(pool.map(_first_try, [cfg] * options.n, range(options.n), chunksize=max(1, options.n // 8)))
    ok = [r for r in results if r[1]]
    low, high = wilson(len(ok), len(results))
    print(
        f"{options.referent} in world {cfg.world}: oracle first try {len(ok)}/{len(results)} = {len(ok) / len(results):.1%} "
        f"(Wilson 95% CI {low:.1%}-{high:.1%}); {sum(r[3] for r in results) / len(results):.1f} control steps per "
        f"episode; {time.perf_counter() - started:.0f} s with {options.workers} workers"
    )
    for index, _, why, _ in (r for r in results if not r[1]):
        print(f"  episode {index}: {why}")


if __name__ == "__main__":
    sys.exit(main("python bench/first_try.py", OracleOptions, bench, doc=__doc__))
