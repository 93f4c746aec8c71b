"""Where a generated episode's time goes, and how often the oracle succeeds before retries.

    python bench/generate.py [n=50] [referent=object] [image_size=128]

Runs the real pipeline (plan -> demonstrate -> replay with cameras -> encode -> write) in one
process and splits wall time into physics+oracle (demos, IK, trajectories, replay physics),
rendering (both cameras), and writing (video encoding, parquet, metadata).
"""

from __future__ import annotations

import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gen.produce as produce
from core.layout import NATIVE
from gen.cli import main
from gen.config import GenConfig, validate
from gen.lerobot_writer import Layout, LeRobotWriter
from gen.plan import designs, load_referent, sim_settings
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


def bench(options: BenchOptions) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        cfg = GenConfig(referent=options.referent, n=options.n, image_size=options.image_size, out=str(Path(tmp) / "ds"))
        validate(cfg)  # the generator's own rules for these options, before any work
        ref, sim, n, size = load_referent(cfg), sim_settings(cfg), cfg.n, cfg.image_size
        produce.encode_episode = timed("encode", produce.encode_episode)  # type: ignore[assignment]
        Cameras.render = timed("render", Cameras.render)  # type: ignore[method-assign]
        producer = produce.Producer(ref, sim)
        plan = designs(ref, n, seed=0)
        oracle = record = write = 0.0
        first_try = attempts = frames = 0
        writer = LeRobotWriter(Path(cfg.out), Layout(sim.fps, size, sim.cameras, NATIVE.state_names, NATIVE.action_names))
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
    render = CLOCKS["render"]
    physics = oracle + record - render - CLOCKS["encode"]
    writing = write + CLOCKS["encode"]
    total = physics + render + writing
    print(f"referent={ref.name} n={n} image_size={size} cameras=2 frames={frames} ({frames / n:.1f}/episode)")
    print(f"oracle success before retries: {first_try}/{n} = {first_try / n:.1%} (attempts {attempts})")
    print(f"{'stage':<16}{'s/episode':>10}{'share':>8}")
    for name, secs in (("physics+oracle", physics), ("rendering", render), ("writing", writing), ("total", total)):
        print(f"{name:<16}{secs / n:>10.3f}{secs / total:>8.1%}")
    print(f"throughput: {frames / total:.1f} frames/s, {total / n:.2f} s/episode (1 process)")
    print(f"rendering alone: {render / frames / len(sim.cameras) * 1000:.1f} ms per camera frame")


if __name__ == "__main__":
    sys.exit(main("python bench/generate.py", BenchOptions, bench, doc=__doc__))
