"""What made a product, recorded once: every place that states it is rendered from here.

`meta/generation.json`, the card's provenance table, the `python -m gen ...` line that
regenerates a dataset, the matching exam's command and the options a resumed run must match
all come from one `Provenance`, so they cannot disagree.
"""

from __future__ import annotations

import hashlib
import json
import platform
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from functools import cached_property
from importlib import metadata
from pathlib import Path

from core import __version__, worlds
from core.profiles import NATIVE
from core.spec import FAST
from gen.config import GenConfig
from referents import registry
from referents.registry import Referent

# The options that determine a product's bytes (beside the referent spec's overrides).
DETERMINING = ("referent", "n", "seed", "image_size", "fps", "codec", "max_attempts", "spec", "objects_per_scene", "plan_only")
# Options a command line spells as a list.
LIST_OPTIONS = ("holdout", "distractor_only", "targets")
# What the exam of a dataset does not inherit from it: its size, random stream and confounds.
NOT_INHERITED_BY_EXAM = ("n", "seed", "plan_only", "split", "confound", "holdout", "distractor_only", "switches", "switched")


def run_record(cfg: GenConfig) -> dict:
    """The options that determine a product's bytes: a resumed run must match them."""
    record = {k: getattr(cfg, k) for k in DETERMINING} | cfg.spec_overrides() | {"generator_version": __version__}
    if cfg.profile != NATIVE.name:  # native records keep the keys they always had, so old runs still resume
        record["profile"] = cfg.profile
    if cfg.world not in (None, "native"):
        record["world"] = cfg.world
    if cfg.look != FAST:
        record["look"] = cfg.look
    if cfg.switches is not None:
        record["switches"] = cfg.switches
    if cfg.switched:
        record["switched"] = cfg.switched
    if cfg.spec:
        record["spec_text"] = Path(cfg.spec).read_text()
    return record


def _without_paths(spec: dict) -> dict:
    """A resolved spec (or a mix's, one per type) without the file path each was read from."""
    if "path" in spec:
        return {k: v for k, v in spec.items() if k != "path"}
    return {k: _without_paths(v) if isinstance(v, dict) else v for k, v in spec.items()}


@dataclass(frozen=True)
class Provenance:
    """The generator's options, the resolved referent spec, and the software that ran."""

    config: GenConfig
    referent_spec: dict
    versions: dict = field(
        default_factory=lambda: {
            "generator_version": __version__,
            "mujoco": metadata.version("mujoco"),
            "robosuite": metadata.version("robosuite"),
            "python": platform.python_version(),
        }
    )

    @classmethod
    def of(cls, cfg: GenConfig, types: Sequence[Referent]) -> Provenance:
        """A mix of types (gen/planning/mix.py) records each one's spec, by type."""
        if len(types) == 1:
            return cls(cfg, asdict(types[0].config))
        return cls(cfg, {referent.label: asdict(referent.config) for referent in types})

    @cached_property
    def spec_hash(self) -> str:
        """Content hash of the resolved referent spec: what it says, not where its file lies (the
        same spec installed elsewhere, or moved, hashes the same)."""
        return hashlib.sha256(json.dumps(_without_paths(self.referent_spec), sort_keys=True, default=str).encode()).hexdigest()[
            :16
        ]

    def _options(self) -> list[tuple[str, str]]:
        """(option, as the command line spells it) for every option the product's command names
        besides `referent`."""
        cfg = self.config
        parts = [("n", f"n={cfg.n}"), ("seed", f"seed={cfg.seed}"), ("image_size", f"image_size={cfg.image_size}")]
        parts.append(("fps", f"fps={cfg.fps}"))
        own = isinstance(cfg.referent, str) and cfg.world == registry.world_of(cfg.referent, cfg.spec)
        if cfg.world is not None and not own:
            parts.append(("world", f"world={cfg.world}"))  # a type's own world goes unsaid
        implied = {"profile": worlds.world(cfg.world or "native").profiles[0]}  # a world's default profile goes unsaid
        for name in ("codec", "spec", "objects_per_scene", "confound", "split", "profile", "look", "switches", "switched"):
            value = getattr(cfg, name)
            if isinstance(value, list):  # a mix's confounds, one per type
                parts.append((name, f"'{name}=[{','.join('null' if v is None else v for v in value)}]'"))
            elif value is not None and value != implied.get(name, GenConfig.__dataclass_fields__[name].default):
                parts.append((name, f"{name}={value}"))
        for name in LIST_OPTIONS:
            if getattr(cfg, name):
                parts.append((name, f"'{name}=[{','.join(repr(v) for v in getattr(cfg, name))}]'"))
        if cfg.plan_only:
            parts.append(("plan_only", "plan_only=true"))
        return parts

    def command(self) -> str:
        """The `python -m gen ...` line that regenerates this product."""
        referent = self.config.referent
        named = f"referent={referent}" if isinstance(referent, str) else f"'referent=[{','.join(referent)}]'"
        return " ".join(["python -m gen", named, *(text for _, text in self._options())])

    def exam_command(self) -> str:
        """The held-out exam for a dataset: same referent and options, exam split, another seed;
        for a mix of types (gen/planning/mix.py) one line per type, each type's exam."""
        kept = [text for name, text in self._options() if name not in NOT_INHERITED_BY_EXAM and name != "world"]
        lines = []
        for one in self.config.shares():
            own = one.world is None or one.world == registry.world_of(one.referent, one.spec)
            world = [] if own else [f"world={one.world}"]
            exam = ["n=200", f"seed={self.config.seed + 1}", "split=exam"]
            lines.append(" ".join(["python -m gen", f"referent={one.referent}", *world, *kept, *exam]))
        return "\n".join(lines)

    def table(self) -> str:
        """The card's provenance rows (markdown)."""
        v = self.versions
        return (
            f"| generator | deconfound {v['generator_version']} |\n| referent spec hash | `{self.spec_hash}` |\n"
            f"| seed | {self.config.seed} |\n| simulator | mujoco {v['mujoco']}, robosuite {v['robosuite']} |"
        )

    def _config(self) -> dict:
        """The options as meta/generation.json records them: `switched` only where episodes change
        course, so the records of the rest stay what they were before it."""
        config = asdict(self.config)
        if not self.config.switched:
            del config["switched"]
        return config

    def generation(self, episodes: int, failed_attempts: int, seconds: float, switched: int | None = None) -> dict:
        """`meta/generation.json`: what regenerates the product, and that it is complete (and, of a
        set asked for switched episodes, how many change course: `switched_episodes`)."""
        v = self.versions
        changed = {} if switched is None else {"switched_episodes": switched}
        return {
            "generator": "deconfound",
            **v,
            "config": self._config(),
            "referent_spec": self.referent_spec,
            "plan_only": self.config.plan_only,
            "run": run_record(self.config),
            "complete": True,
            "referent_spec_hash": self.spec_hash,
            "episodes": episodes,
            "failed_attempts": failed_attempts,
            **changed,
            "seconds": round(seconds, 2),
        }
