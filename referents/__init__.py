"""Referent types: the ways an instruction can name its target.

Each type is one declarative spec (`<type>.yaml`, validated by `referents.base`) and one small
module (`<type>.py`) holding:

* `design(config, balance) -> Design` — the balanced discrete choices of one episode (required);
* `demo(skills, spec)` — the oracle's plan (default: grasp the target and lift it);
* `alternatives(config, spec) -> list[Alternative]` — what the instruction chooses among, for
  the confound audit (default: every object in the scene);
* `answer(spec) -> str` — which alternative is right (default: the target object);
* `assets(config)` — the model inventory (default: one body per candidate of a kind, at most
  `objects_per_scene`);
* `CONFOUNDS` — the shortcuts `confound=` may re-introduce (default: none).

Adding a type means adding those two files; nothing else changes.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

from core.demo import Plan, Skills
from core.spec import EpisodeSpec
from referents.base import Alternative, Balance, Design, ReferentConfig, ReferentSpecError, object_alternatives

HERE = Path(__file__).parent


class UnknownReferent(ValueError):
    pass


def available() -> list[str]:
    return sorted(p.stem for p in HERE.glob("*.yaml"))


@dataclass(frozen=True)
class Referent:
    config: ReferentConfig
    module: ModuleType

    @property
    def name(self) -> str:
        return self.config.type

    def design(self, balance: Balance) -> Design:
        return self.module.design(self.config, balance)

    def demo(self, skills: Skills, spec: EpisodeSpec) -> None:
        demo_of(self.name)(skills, spec)

    def alternatives(self, spec: EpisodeSpec) -> list[Alternative]:
        if hasattr(self.module, "alternatives"):
            return self.module.alternatives(self.config, spec)
        return object_alternatives(self.config, spec)

    def assets(self) -> tuple[tuple[str, int], ...]:
        if hasattr(self.module, "assets"):
            return tuple(sorted(self.module.assets(self.config)))
        return self.config.assets()

    def answer(self, spec: EpisodeSpec) -> str:
        return self.module.answer(spec) if hasattr(self.module, "answer") else spec.target


def pick_and_lift(skills: Skills, spec: EpisodeSpec) -> None:
    skills.grasp(spec.target)
    skills.lift()


def demo_of(referent_type: str) -> Plan:
    """The oracle's plan for a type's episodes (all a replay needs: no spec file)."""
    return getattr(importlib.import_module(f"referents.{referent_type}"), "demo", pick_and_lift)


def load(name: str, spec_path: str | None = None, overrides: dict[str, Any] | None = None) -> Referent:
    """The referent `name` (referents/<name>.yaml), or the spec file at `spec_path`.

    `overrides` replace top-level spec fields (e.g. objects_per_scene, holdout, confound).
    """
    if spec_path is None:
        if name not in available():
            raise UnknownReferent(f"unknown referent {name!r}; available: {', '.join(available())}")
        path = HERE / f"{name}.yaml"
    else:
        path = Path(spec_path)
        if not path.is_file():
            raise ReferentSpecError(f"{path}: referent spec file not found")
    config = ReferentConfig.from_yaml(path, overrides)
    if not (HERE / f"{config.type}.py").is_file():
        raise ReferentSpecError(f"{path}: type: no module referents/{config.type}.py for type {config.type!r}")
    module = importlib.import_module(f"referents.{config.type}")
    if config.confound and config.confound not in getattr(module, "CONFOUNDS", ()):
        raise ReferentSpecError(f"{path}: confound: {config.confound!r} is not defined for referent type {config.type!r}")
    if hasattr(module, "validate"):
        module.validate(config)
    return Referent(config, module)
