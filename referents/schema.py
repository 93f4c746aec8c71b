"""A referent type's declarative spec (referents/<type>.yaml): its schema, validated on load so
that a bad file gets one line naming the field before anything is planned or simulated."""

from __future__ import annotations

import itertools
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from core import catalog, programs, worlds
from core.spec import TaskSpec

# The shortcuts `confound=` may re-introduce, for comparisons: `position` puts every target in its
# canonical slot; `layout` lays every scene out as a benchmark's own task of that target does (its
# objects, each in its place: LIBERO's demonstrations), so both where and what co-appears say it.
CONFOUNDS = ("position", "layout")


class ReferentSpecError(ValueError):
    """A referent spec file (or an option that edits it) is wrong; the message names the field."""


def object_key(name: str, attributes: dict[str, str]) -> str:
    """An object's identity in a referent's vocabulary: its name qualified by its attributes."""
    return " ".join([*(attributes[k] for k in sorted(attributes)), name])


@dataclass(frozen=True)
class Candidate:
    """An object a scene may hold: its catalog kind, the noun for it, and its attributes."""

    kind: str
    name: str
    attributes: dict[str, str] = field(default_factory=dict)
    role: str = ""  # for types whose scenes mix roles, e.g. "destination" vs "object"
    targetable: bool = True  # False for `distractor_only` values

    @property
    def key(self) -> str:
        return object_key(self.name, self.attributes)

    def word(self, naming: str) -> str:
        """The value of the naming variable: the name, the whole key, or an attribute."""
        if naming in ("name", "key"):
            return self.name if naming == "name" else self.key
        return self.attributes[naming]

    def matches(self, value: str) -> bool:
        return value in (self.name, self.key, *self.attributes.values())


@dataclass(frozen=True)
class Layout:
    """Where objects may stand: slot centres (x, y) on the table (or (x, y, z) on something at
    height z: a box, a cabinet), jitter, yaw range, and the
    canonical slot a `confound=position` dataset always puts the target in: one for every
    target, or one per target value (e.g. LIBERO's target_object_region of each task)."""

    slots: tuple[tuple[float, ...], ...]
    jitter: float | tuple[float, ...] = 0.02  # one for every slot, or one per slot
    yaw: tuple[float, float] = (-np.pi, np.pi)
    canonical_slot: int | dict[str, int] = 0

    def canonical(self, value: str) -> int:
        """The canonical slot of a target whose naming value (or key) is `value`."""
        slots = self.canonical_slot
        return slots if isinstance(slots, int) else slots[value]

    def surface(self, slot: int, default: float) -> float:
        """The height of what an object in `slot` stands on (`default`: the world's surface)."""
        return self.slots[slot][2] if len(self.slots[slot]) == 3 else default

    def jitter_at(self, slot: int) -> float:
        """How far (m, along x and y) an object may stand from the slot's centre."""
        return self.jitter[slot] if isinstance(self.jitter, tuple) else self.jitter


@dataclass(frozen=True)
class ReferentConfig:
    """A referent type's declarative spec (referents/<type>.yaml), validated.

    `naming` is the variable the instruction names the target by ("name" or an attribute);
    `holdout` values never appear, `distractor_only` values never are the target, `targets`
    (when given) are the only values that may be (e.g. an exam of exactly the held-out values),
    and `confound` deliberately re-introduces a shortcut (only "position") for comparisons.
    """

    type: str
    path: str
    naming: str
    objects_per_scene: int
    objects: tuple[Candidate, ...]
    layout: Layout
    templates: tuple[str, ...]
    task: TaskSpec = TaskSpec()
    holdout: tuple[str, ...] = ()
    distractor_only: tuple[str, ...] = ()
    targets: tuple[str, ...] = ()
    confound: str | None = None
    world: str = "native"  # the world its scenes happen in (core/worlds/): its objects and where they may stand
    words: tuple[tuple[str, str], ...] = ()  # (option, value) pairs whose value names no object (see `unknown_words`)
    extra: dict[str, Any] = field(default_factory=dict)  # type-specific fields

    @classmethod
    def from_yaml(cls, path: Path, overrides: dict[str, Any] | None = None) -> ReferentConfig:
        try:
            data = yaml.safe_load(path.read_text())
        except (OSError, yaml.YAMLError) as exc:
            raise ReferentSpecError(f"{path}: cannot read referent spec: {exc}") from None
        if not isinstance(data, dict):
            raise ReferentSpecError(f"{path}: a referent spec must be a mapping")
        data.update({k: v for k, v in (overrides or {}).items() if v is not None})
        return cls.from_dict(data, str(path))

    @classmethod
    def from_dict(cls, data: dict[str, Any], path: str) -> ReferentConfig:
        def fail(field_name: str, problem: str) -> ReferentSpecError:
            return ReferentSpecError(f"{path}: {field_name}: {problem}")

        data = dict(data)
        for required in ("type", "naming", "objects_per_scene", "objects", "layout", "templates"):
            if required not in data:
                raise fail(required, "missing field")
        for name in ("type", "naming"):
            if not isinstance(data[name], str) or not data[name].isidentifier():
                raise fail(name, f"must be a word, got {data[name]!r}")
        try:
            world = worlds.world(str(data.pop("world", "native")))
        except worlds.UnknownWorld as exc:
            raise fail("world", str(exc)) from None
        objects = _candidates(data.pop("objects"), fail, world)
        naming = data.pop("naming")
        if len({c.key for c in objects}) != len(objects):
            raise fail("objects", "two objects share the same name and attributes")
        vocabulary: dict[str, tuple[str, ...]] = {}
        words: list[tuple[str, str]] = []  # values that name no object: the type's own words, checked when its module loads
        for option in ("holdout", "distractor_only", "targets"):
            values = tuple(str(v) for v in _strings(data.pop(option, None) or [], option, fail))
            words += [(option, v) for v in values if not any(c.matches(v) for c in objects)]
            vocabulary[option] = values
        objects = [c for c in objects if not any(c.matches(v) for v in vocabulary["holdout"])]
        if not objects:
            raise fail("holdout", f"holds out every object ({', '.join(vocabulary['holdout'])}); nothing is left to place")
        only = [v for v in vocabulary["targets"] if ("targets", v) not in words]
        if vocabulary["targets"] and not only:  # every target is one of the type's own words: it chooses among them
            only = [c.key for c in objects]
        objects = [
            replace(
                c,
                targetable=not any(c.matches(v) for v in vocabulary["distractor_only"])
                and (not only or any(c.matches(v) for v in only)),
            )
            for c in objects
        ]
        layout = _layout(data.pop("layout"), fail, world)
        k = data.pop("objects_per_scene")
        if not isinstance(k, int) or isinstance(k, bool) or k < 2:
            raise fail("objects_per_scene", f"must be an integer of at least 2 (a swap needs another object), got {k!r}")
        if k > len(layout.slots):
            raise fail("objects_per_scene", f"{k} objects cannot fit in the {len(layout.slots)} slots of layout.slots")
        if not any(c.targetable for c in objects):
            raise fail("distractor_only" if not only else "targets", "leaves no object that can be the target")
        templates = tuple(_strings(data.pop("templates") or [], "templates", fail))
        if not templates:
            raise fail("templates", "needs at least one instruction template")
        task_fields = data.pop("task", None) or {}
        if not isinstance(task_fields, dict):
            raise fail("task", f"must be a mapping, got {task_fields!r}")
        try:
            task = TaskSpec(**task_fields)
        except TypeError as exc:
            raise fail("task", str(exc)) from None
        margin_ok = isinstance(task.lift_margin, (int, float))
        well_typed = isinstance(task.program, str) and margin_ok and isinstance(task.params, dict)
        if not well_typed:
            raise fail("task", "program must be a word, lift_margin a number, params a mapping")
        if task.program not in programs.PROGRAMS:
            raise fail("task", f"unknown program {task.program!r}; known: {', '.join(programs.PROGRAMS)}")
        confound = data.pop("confound", None)
        if confound is not None and confound not in CONFOUNDS:
            raise fail("confound", f"unknown confound {confound!r}; known: {', '.join(CONFOUNDS)}")
        return cls(
            type=data.pop("type"),
            path=path,
            naming=naming,
            objects_per_scene=k,
            objects=tuple(objects),
            layout=layout,
            templates=templates,
            task=task,
            holdout=vocabulary["holdout"],
            distractor_only=vocabulary["distractor_only"],
            targets=vocabulary["targets"],
            confound=confound,
            world=world.name,
            words=tuple(words),
            extra=data,
        )

    def assets(self) -> tuple[tuple[str, int], ...]:
        """The default model inventory (a type's `assets`): one body per object of a kind, at most
        `objects_per_scene`, which is enough for any scene that holds each object at most once."""
        per_kind = Counter(c.kind for c in self.objects)
        return tuple(sorted((kind, min(n, self.objects_per_scene)) for kind, n in per_kind.items()))

    def unknown_words(self, own: tuple[str, ...]) -> ReferentSpecError | None:
        """The first holdout/distractor_only/targets value that names neither an object nor one of the
        type's `own` words (what else its instructions name targets by, e.g. a place), or None."""
        stray = [(option, v) for option, v in self.words if v not in own]
        if not stray:
            return None
        option, value = stray[0]
        named = {c.name for c in self.objects} | {c.attributes.get(self.naming, c.name) for c in self.objects}
        accepted = ", ".join(sorted(named | set(own)))
        return self.fail(option, f"{value!r} names no object of this referent; it accepts: {accepted}")

    def role(self, role: str) -> list[Candidate]:
        return [c for c in self.objects if c.role == role]

    def need(self, key: str, kind: type = object) -> Any:
        """A type-specific field of the spec, required."""
        if key not in self.extra:
            raise ReferentSpecError(f"{self.path}: {key}: missing field (required by referent type {self.type})")
        value = self.extra[key]
        if kind is not object and not isinstance(value, kind):
            raise ReferentSpecError(f"{self.path}: {key}: expected a {kind.__name__}, got {value!r}")
        return value

    def fail(self, field_name: str, problem: str) -> ReferentSpecError:
        return ReferentSpecError(f"{self.path}: {field_name}: {problem}")


def _strings(raw: Any, field_name: str, fail: Callable[[str, str], ReferentSpecError]) -> list[str]:
    if not isinstance(raw, list) or not all(isinstance(v, (str, int, float)) and not isinstance(v, bool) for v in raw):
        raise fail(field_name, f"must be a list of words, got {raw!r}")
    return [str(v) for v in raw]


def _candidates(raw: Any, fail: Callable[[str, str], ReferentSpecError], world: worlds.World) -> list[Candidate]:
    """Objects, where a list-valued attribute expands into one candidate per value."""
    if not isinstance(raw, list) or not raw:
        raise fail("objects", "must be a non-empty list")
    out = []
    for i, o in enumerate(raw):
        if not isinstance(o, dict) or not isinstance(o.get("kind"), str) or not isinstance(o.get("name"), str):
            raise fail(f"objects[{i}]", "each object needs 'kind' and 'name' (words)")
        if not isinstance(o.get("role", ""), str):
            raise fail(f"objects[{i}].role", f"must be a word, got {o['role']!r}")
        if o["kind"] not in world.kinds:
            known = ", ".join(sorted(world.kinds))
            raise fail(f"objects[{i}].kind", f"unknown kind {o['kind']!r} in world {world.name}; known: {known}")
        attrs = o.get("attributes") or {}
        if not isinstance(attrs, dict):
            raise fail(f"objects[{i}].attributes", "must be a mapping")
        options = {
            str(k): _strings(v if isinstance(v, list) else [v], f"objects[{i}].attributes.{k}", fail) for k, v in attrs.items()
        }
        if any(not values for values in options.values()):
            raise fail(f"objects[{i}].attributes", "an attribute list is empty")
        for color in options.get("color", []):
            if color not in catalog.COLORS:
                raise fail(f"objects[{i}].attributes.color", f"unknown color {color!r}; known: {', '.join(catalog.COLORS)}")
        for combo in itertools.product(*options.values()):
            out.append(Candidate(str(o["kind"]), str(o["name"]), dict(zip(options, combo)), str(o.get("role", ""))))
    return out


def _layout(raw: Any, fail: Callable[[str, str], ReferentSpecError], world: worlds.World) -> Layout:
    if not isinstance(raw, dict) or "slots" not in raw:
        raise fail("layout.slots", "missing field")
    try:
        slots = tuple(tuple(float(v) for v in slot) for slot in raw["slots"])
        if any(len(slot) not in (2, 3) for slot in slots):
            raise ValueError("a slot is [x, y] or [x, y, z]")
        yaw = tuple(float(v) for v in raw.get("yaw", (-np.pi, np.pi)))
        if len(yaw) != 2 or yaw[0] > yaw[1]:
            raise ValueError("yaw is [min, max]")
        jitter = raw.get("jitter", 0.02)
        jitter = tuple(float(j) for j in jitter) if isinstance(jitter, list) else float(jitter)
        if isinstance(jitter, tuple) and len(jitter) != len(slots):
            raise ValueError("one jitter per slot")
        if not all(0 <= j < np.inf for j in (jitter if isinstance(jitter, tuple) else (jitter,))):
            raise ValueError("jitter is a distance: 0 or more")
        canonical = raw.get("canonical_slot", 0)
        canonical = {str(k): int(v) for k, v in canonical.items()} if isinstance(canonical, dict) else int(canonical)
        layout = Layout(slots, jitter, yaw, canonical)
    except (TypeError, ValueError):
        raise fail(
            "layout",
            "slots must be [x, y] (or [x, y, the height of what the object stands on]), "
            "jitter a number of 0 or more (or one per slot), yaw [min, max]",
        ) from None
    x0, x1, y0, y1 = world.reach
    for i, (x, y, *z) in enumerate(layout.slots):
        fixed = bool(z) and layout.jitter_at(i) == 0  # a place on furniture (the stove's knob stands beyond the reach)
        if not fixed and not (x0 <= x <= x1 and y0 <= y <= y1):
            raise fail(
                f"layout.slots[{i}]",
                f"({x}, {y}) is off the workspace of world {world.name} (x in [{x0:g}, {x1:g}], y in [{y0:g}, {y1:g}])",
            )
    canonical = layout.canonical_slot
    for slot in canonical.values() if isinstance(canonical, dict) else (canonical,):
        if not 0 <= slot < len(slots):
            raise fail("layout.canonical_slot", f"must index layout.slots (0..{len(slots) - 1}), got {slot}")
    return layout
