"""Where a generated episode's time goes, and how often the oracle succeeds before retries.

    python bench/generate.py [n=50] [referent=object] [image_size=128] ['profiles=[native,libero]']

Runs the real pipeline (plan -> demonstrate -> replay with cameras -> encode -> write) in one
process and splits wall time into physics+oracle (demos, IK, trajectories, replay physics),
rendering (both cameras), and writing (video encoding, parquet, metadata). With several
profiles they run one after the other in the same process at the same image size, and the
ratio of each one's s/episode to the first's is printed.
"""

from __future__ import annotations

import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, List

import gen.products.produce as produce
from core import worlds
from gen.config import GenConfig, load_referent, validate
from gen.lerobot.writer import LeRobotWriter, Recording
from gen.planning.plan import configured_setup, designs
from jobs.cli import main
from oracle.render import Cameras

CLOCKS: dict[str, float] = {"render": 0.0, "encode": 0.0}


def timed(name: str, fn: Callable[..., Any]) -> Callable[..., Any]:
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        start = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            CLOCKS[name] += time.perf_counter() - start

    return wrapper


@dataclass
class BenchOptions:
    n: int = 50  # episodes
    referent: str = "object"  # a referent type (referents/<type>.yaml)
    image_size: int = 128  # square camera frames, pixels
    profiles: List[str] = field(default_factory=lambda: ["native"])  # profiles to time, side by side


def bench(options: BenchOptions) -> None:
    configs = [
        GenConfig(referent=options.referent, n=options.n, image_size=options.image_size, profile=p) for p in options.profiles
    ]
    with tempfile.TemporaryDirectory() as tmp:
        for cfg in configs:
            cfg.out = str(Path(tmp) / cfg.profile)
            validate(cfg)  # the generator's own rules for these options, before any work
        produce.encode_episode = timed("encode", produce.encode_episode)
        Cameras.render = timed("render", Cameras.render)
        per_episode = {cfg.profile: run(cfg) for cfg in configs}
    first = options.profiles[0]
    for profile, secs in list(per_episode.items())[1:]:
        print(f"{profile} / {first}: {secs / per_episode[first]:.2f}x s/episode at image_size={options.image_size}")


def run(cfg: GenConfig) -> float:
    """Time one profile; prints its table and returns its s/episode."""
    for clock in CLOCKS:
        CLOCKS[clock] = 0.0
    ref = load_referent(cfg)
    setup, n, size = configured_setup(cfg, worlds.world(ref.config.world)), cfg.n, cfg.image_size
    producer = produce.Producer(ref, setup)
    producer.demonstrate(designs(ref, 1, seed=1)[0], 0, 1, max_attempts=10)  # warm-up: JIT caches, first scene
    plan = designs(ref, n, seed=0)
    oracle = record = write = 0.0
    first_try = attempts = frames = 0
    features = setup.interface
    writer = LeRobotWriter(Path(cfg.out), Recording(setup.fps, size, setup.cameras, features.state_names, features.action_names))
    for i, design in enumerate(plan):
        t0 = time.perf_counter()
        demo, failures = producer.demonstrate(design, i, 0, max_attempts=10)
        t1 = time.perf_counter()
        produced = producer.record(demo, failures)
        t2 = time.perf_counter()
        writer.add(produced.episode)
        t3 = time.perf_counter()
        oracle, record, write = oracle + t1 - t0, record + t2 - t1, write + t3 - t2
        first_try += not failures
        attempts += 1 + len(failures)
        frames += produced.episode.length
    t4 = time.perf_counter()
    writer.finalize()
    write += time.perf_counter() - t4
    producer.close()
    render = CLOCKS["render"]
    physics = oracle + record - render - CLOCKS["encode"]
    writing = write + CLOCKS["encode"]
    total = physics + render + writing
    print(f"profile={cfg.profile} referent={ref.name} n={n} image_size={size} frames={frames} ({frames / n:.1f}/episode)")
    print(f"oracle success before retries: {first_try}/{n} = {first_try / n:.1%} (attempts {attempts})")
    print(f"{'stage':<16}{'s/episode':>10}{'share':>8}")
    for name, secs in (("physics+oracle", physics), ("rendering", render), ("writing", writing), ("total", total)):
        print(f"{name:<16}{secs / n:>10.3f}{secs / total:>8.1%}")
    print(f"throughput: {frames / total:.1f} frames/s, {total / n:.2f} s/episode (1 process)")
    print(f"rendering alone: {render / frames / len(setup.cameras) * 1000:.1f} ms per camera frame")
    return total / n


if __name__ == "__main__":
    sys.exit(main("python bench/generate.py", BenchOptions, bench, doc=__doc__))
