"""What every referent type shares: its declarative config, the role balancer, and the design
it returns for one episode (the discrete choices; poses are realised in gen/plan.py).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Hashable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import yaml

from gen.spec import Counterfactual, TaskSpec
from oracle import catalog
from oracle.world import TABLE_SIZE

T = TypeVar("T")


class ReferentSpecError(ValueError):
    """A referent spec file is malformed; the message names the file and the field."""


@dataclass(frozen=True)
class Candidate:
    """An object a scene may hold: its catalog kind, the noun for it, and its attributes."""

    kind: str
    name: str
    attributes: dict[str, str] = field(default_factory=dict)

    @property
    def key(self) -> str:
        """Identity within the referent's vocabulary (the name, qualified by attributes)."""
        attrs = " ".join(self.attributes[k] for k in sorted(self.attributes))
        return f"{attrs} {self.name}".strip()


@dataclass(frozen=True)
class Layout:
    """Where objects may stand: slot centres (x, y) on the table, jitter and yaw range."""

    slots: tuple[tuple[float, float], ...]
    jitter: float = 0.02
    yaw: tuple[float, float] = (-np.pi, np.pi)


@dataclass(frozen=True)
class ReferentConfig:
    """A referent type's declarative spec (referents/<type>.yaml), validated."""

    type: str
    path: str
    objects_per_scene: int
    objects: tuple[Candidate, ...]
    layout: Layout
    templates: tuple[str, ...]
    task: TaskSpec = TaskSpec()
    extra: dict[str, Any] = field(default_factory=dict)  # type-specific fields

    @classmethod
    def from_yaml(cls, path: Path, overrides: dict[str, Any] | None = None) -> ReferentConfig:
        try:
            data = yaml.safe_load(path.read_text())
        except (OSError, yaml.YAMLError) as exc:
            raise ReferentSpecError(f"{path}: cannot read referent spec: {exc}") from None
        if not isinstance(data, dict):
            raise ReferentSpecError(f"{path}: a referent spec must be a mapping")
        data.update(overrides or {})
        return cls.from_dict(data, str(path))

    @classmethod
    def from_dict(cls, data: dict[str, Any], path: str) -> ReferentConfig:
        def fail(field_name: str, problem: str) -> ReferentSpecError:
            return ReferentSpecError(f"{path}: {field_name}: {problem}")

        data = dict(data)
        for required in ("type", "objects_per_scene", "objects", "layout", "templates"):
            if required not in data:
                raise fail(required, "missing field")
        objects = []
        for i, o in enumerate(data.pop("objects") or []):
            if not isinstance(o, dict) or "kind" not in o or "name" not in o:
                raise fail(f"objects[{i}]", "each object needs 'kind' and 'name'")
            if o["kind"] not in catalog.KINDS:
                raise fail(f"objects[{i}].kind", f"unknown kind {o['kind']!r}; known: {', '.join(sorted(catalog.KINDS))}")
            attrs = {str(k): str(v) for k, v in (o.get("attributes") or {}).items()}
            if "color" in attrs and attrs["color"] not in catalog.COLORS:
                raise fail(f"objects[{i}].attributes.color", f"unknown color {attrs['color']!r}; known: {', '.join(catalog.COLORS)}")
            objects.append(Candidate(str(o["kind"]), str(o["name"]), attrs))
        if len({c.key for c in objects}) != len(objects):
            raise fail("objects", "two objects share the same name and attributes")
        layout_data = data.pop("layout")
        if not isinstance(layout_data, dict) or "slots" not in layout_data:
            raise fail("layout.slots", "missing field")
        try:
            slots = tuple((float(x), float(y)) for x, y in layout_data["slots"])
            layout = Layout(slots, float(layout_data.get("jitter", 0.02)), tuple(layout_data.get("yaw", (-np.pi, np.pi))))  # type: ignore[arg-type]
        except (TypeError, ValueError):
            raise fail("layout", "slots must be [x, y] pairs and jitter a number") from None
        half_x, half_y = TABLE_SIZE[0] / 2 - 0.05, TABLE_SIZE[1] / 2 - 0.05
        for i, (x, y) in enumerate(layout.slots):
            if abs(x) > half_x or abs(y) > half_y:
                raise fail(f"layout.slots[{i}]", f"({x}, {y}) is off the table (|x| <= {half_x}, |y| <= {half_y})")
        k = data.pop("objects_per_scene")
        if not isinstance(k, int) or k < 1:
            raise fail("objects_per_scene", f"must be a positive integer, got {k!r}")
        if k > len(layout.slots):
            raise fail("objects_per_scene", f"{k} objects cannot fit in the {len(layout.slots)} slots of layout.slots")
        templates = tuple(str(t) for t in data.pop("templates") or [])
        if not templates:
            raise fail("templates", "needs at least one instruction template")
        task = data.pop("task", None) or {}
        try:
            task_spec = TaskSpec(**task)
        except TypeError as exc:
            raise fail("task", str(exc)) from None
        return cls(
            type=str(data.pop("type")),
            path=path,
            objects_per_scene=k,
            objects=tuple(objects),
            layout=layout,
            templates=templates,
            task=task_spec,
            extra=data,
        )

    def assets(self) -> tuple[tuple[str, int], ...]:
        """The model inventory: enough bodies of each kind for any scene of this referent."""
        per_kind = Counter(c.kind for c in self.objects)
        return tuple(sorted((kind, min(n, self.objects_per_scene)) for kind, n in per_kind.items()))


@dataclass(frozen=True)
class Placement:
    """A candidate put at a slot under a scene-unique id."""

    id: str
    candidate: Candidate
    slot: int


@dataclass(frozen=True)
class Design:
    """The discrete choices of one episode, before poses are realised."""

    placements: tuple[Placement, ...]
    target: str
    template: str
    instruction: str
    counterfactuals: tuple[Counterfactual, ...]


class Balance:
    """Greedy least-used choices with seeded tie-breaks.

    Each choice takes an option whose count under `key` is lowest, so every prefix of a plan is
    as balanced as the choices allow: with n episodes every value is chosen n/len(options) (+-1)
    times, and (value, slot) pairs are all covered once n reaches their number.
    """

    def __init__(self, rng: np.random.Generator) -> None:
        self.rng = rng
        self.counts: Counter[tuple[Hashable, Hashable]] = Counter()

    def pick(self, key: Hashable, options: Sequence[T], also: Hashable | None = None) -> T:
        """Least-used option under `key`, ties broken by `also` (a second key), then at random."""
        if not options:
            raise ValueError(f"no options to choose {key!r} from")
        scores = [
            (self.counts[(key, self._id(o))], self.counts[(also, self._id(o))] if also is not None else 0)
            for o in options
        ]
        best = min(scores)
        ties = [o for o, s in zip(options, scores) if s == best]
        choice = ties[int(self.rng.integers(len(ties)))]
        self.counts[(key, self._id(choice))] += 1
        if also is not None:
            self.counts[(also, self._id(choice))] += 1
        return choice

    @staticmethod
    def _id(option: Any) -> Hashable:
        return option.key if isinstance(option, Candidate) else option


def fill(template: str, **words: str) -> str:
    return template.format(**words)
