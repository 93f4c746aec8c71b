"""Referent types: the ways an instruction can name its target.

Each type is one declarative spec (`<type>.yaml`, validated by `referents.base`) and one small
module (`<type>.py`) with `design(config, balance) -> Design` (the balanced discrete choices of
one episode) and, unless the type only picks and lifts, `demo(skills, spec)` (the oracle's
plan). Adding a type means adding those two files; nothing else changes.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

from referents.base import Balance, Design, ReferentConfig, ReferentSpecError

if TYPE_CHECKING:
    from gen.spec import EpisodeSpec
    from oracle.skills import Skills

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
        if hasattr(self.module, "demo"):
            self.module.demo(skills, spec)
        else:
            skills.grasp(spec.target)
            skills.lift()


def load(name: str, spec_path: str | None = None, overrides: dict[str, Any] | None = None) -> Referent:
    """The referent `name` (referents/<name>.yaml), or the spec file at `spec_path`."""
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
    if hasattr(module, "validate"):
        module.validate(config)
    return Referent(config, module)
