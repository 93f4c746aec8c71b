"""What every referent type shares: its declarative config, the role balancer, the design it
returns for one episode (the discrete choices; poses are realised in gen/plan.py), and the
helpers most types are built from.
"""

from __future__ import annotations

import itertools
from collections import Counter
from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import yaml

from core import catalog
from core.spec import Counterfactual, EpisodeSpec, SceneObject, TaskSpec
from core.world import TABLE_SIZE

T = TypeVar("T")
CONFOUNDS = ("position",)


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
    """Where objects may stand: slot centres (x, y) on the table, jitter, yaw range, and the
    canonical slot a `confound=position` dataset always puts the target in."""

    slots: tuple[tuple[float, float], ...]
    jitter: float = 0.02
    yaw: tuple[float, float] = (-np.pi, np.pi)
    canonical_slot: int = 0


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
        objects = _candidates(data.pop("objects"), fail)
        naming = data.pop("naming")
        if len({c.key for c in objects}) != len(objects):
            raise fail("objects", "two objects share the same name and attributes")
        vocabulary: dict[str, tuple[str, ...]] = {}
        for option in ("holdout", "distractor_only", "targets"):
            values = tuple(str(v) for v in _strings(data.pop(option, None) or [], option, fail))
            for v in values:
                if not any(c.matches(v) for c in objects):
                    raise fail(option, f"{v!r} names no object of this referent")
            vocabulary[option] = values
        objects = [c for c in objects if not any(c.matches(v) for v in vocabulary["holdout"])]
        only = vocabulary["targets"]
        objects = [
            replace(
                c,
                targetable=not any(c.matches(v) for v in vocabulary["distractor_only"])
                and (not only or any(c.matches(v) for v in only)),
            )
            for c in objects
        ]
        layout = _layout(data.pop("layout"), fail)
        k = data.pop("objects_per_scene")
        if not isinstance(k, int) or k < 1:
            raise fail("objects_per_scene", f"must be a positive integer, got {k!r}")
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
            extra=data,
        )

    def assets(self) -> tuple[tuple[str, int], ...]:
        """The model inventory: enough bodies of each kind for any scene of this referent."""
        per_kind = Counter(c.kind for c in self.objects)
        return tuple(sorted((kind, min(n, self.objects_per_scene)) for kind, n in per_kind.items()))

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


def _candidates(raw: Any, fail: Callable[[str, str], ReferentSpecError]) -> list[Candidate]:
    """Objects, where a list-valued attribute expands into one candidate per value."""
    if not isinstance(raw, list) or not raw:
        raise fail("objects", "must be a non-empty list")
    out = []
    for i, o in enumerate(raw):
        if not isinstance(o, dict) or not isinstance(o.get("kind"), str) or not isinstance(o.get("name"), str):
            raise fail(f"objects[{i}]", "each object needs 'kind' and 'name' (words)")
        if not isinstance(o.get("role", ""), str):
            raise fail(f"objects[{i}].role", f"must be a word, got {o['role']!r}")
        if o["kind"] not in catalog.KINDS:
            raise fail(f"objects[{i}].kind", f"unknown kind {o['kind']!r}; known: {', '.join(sorted(catalog.KINDS))}")
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


def _layout(raw: Any, fail: Callable[[str, str], ReferentSpecError]) -> Layout:
    if not isinstance(raw, dict) or "slots" not in raw:
        raise fail("layout.slots", "missing field")
    try:
        slots = tuple((float(x), float(y)) for x, y in raw["slots"])
        yaw = tuple(float(v) for v in raw.get("yaw", (-np.pi, np.pi)))
        layout = Layout(slots, float(raw.get("jitter", 0.02)), yaw, int(raw.get("canonical_slot", 0)))  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise fail("layout", "slots must be [x, y] pairs, jitter a number, yaw [min, max]") from None
    half_x, half_y = TABLE_SIZE[0] / 2 - 0.05, TABLE_SIZE[1] / 2 - 0.05
    for i, (x, y) in enumerate(layout.slots):
        if abs(x) > half_x or abs(y) > half_y:
            raise fail(f"layout.slots[{i}]", f"({x}, {y}) is off the table (|x| <= {half_x}, |y| <= {half_y})")
    if not 0 <= layout.canonical_slot < len(slots):
        raise fail("layout.canonical_slot", f"must index layout.slots (0..{len(slots) - 1})")
    return layout


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
    task: TaskSpec | None = None  # None: the referent's task


@dataclass(frozen=True)
class Alternative:
    """One of the things an instruction could ask for in a scene, as the confound audit sees it:
    `value` is what the instruction would call it, `features` are non-instruction variables."""

    id: str
    value: str
    slot: int
    features: dict[str, Hashable]


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
        scores = [(self.counts[(key, self._id(o))], self.counts[(also, self._id(o))] if also is not None else 0) for o in options]
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


def fill(template: str, candidate: Candidate, **words: str) -> str:
    """A template filled with the candidate's name and attributes (and any extra words)."""
    return template.format(name=candidate.name, **candidate.attributes, **words)


def slug(text: str) -> str:
    return text.replace(" ", "_")


def target_slot(cfg: ReferentConfig, balance: Balance, key: Hashable, options: Sequence[int]) -> int:
    """The target's slot: least used for `key`, or always the canonical one under confound=position."""
    if cfg.confound == "position":
        if cfg.layout.canonical_slot not in options:
            raise ValueError("the canonical slot is not free")
        return cfg.layout.canonical_slot
    return balance.pick(("target_slot", key), list(options), also="slot")


def choose_scene(cfg: ReferentConfig, balance: Balance, pool: Sequence[Candidate], naming: str) -> list[Placement]:
    """A target and `objects_per_scene - 1` distractors that each differ from every other in
    the naming variable; the target comes first.

    The target value is the least-used one, its instance the least-used of that value, at its
    least-used slot; distractor values are the least-used as distractors, each instance at its
    least-used free slot.
    """
    for c in pool:
        if naming not in ("name", "key") and naming not in c.attributes:
            raise cfg.fail("objects", f"{c.key!r} has no {naming!r} attribute, which names targets (naming: {naming})")
    targets = [c for c in pool if c.targetable]
    value = balance.pick("target", list(dict.fromkeys(c.word(naming) for c in targets)))
    target = balance.pick(("instance", value), [c for c in targets if c.word(naming) == value])
    slots = list(range(len(cfg.layout.slots)))
    placements = [Placement(slug(target.key), target, target_slot(cfg, balance, target.key, slots))]
    others = list(dict.fromkeys(c.word(naming) for c in pool if c.word(naming) != value))
    if len(others) < cfg.objects_per_scene - 1:
        raise cfg.fail("objects", f"needs {cfg.objects_per_scene} different {naming} values per scene, has {len(others) + 1}")
    for _ in range(cfg.objects_per_scene - 1):
        other = balance.pick("distractor", others)
        others.remove(other)
        d = balance.pick(("distractor_instance", other), [c for c in pool if c.word(naming) == other])
        free = [s for s in slots if s not in {p.slot for p in placements}]
        placements.append(Placement(slug(d.key), d, balance.pick(("distractor_slot", d.key), free, also="slot")))
    return placements


def naming_design(cfg: ReferentConfig, balance: Balance, pool: Sequence[Candidate] | None = None) -> Design:
    """One target named by a single word (its name, or an attribute) among distractors that
    each have another value of it; the swap counterfactual names each distractor instead."""
    placements = choose_scene(cfg, balance, cfg.objects if pool is None else pool, cfg.naming)
    target = placements[0].candidate
    template = balance.pick("template", cfg.templates)
    return Design(
        placements=tuple(sorted(placements, key=lambda p: p.slot)),
        target=placements[0].id,
        template=template,
        instruction=fill(template, target),
        counterfactuals=tuple(
            Counterfactual(fill(template, p.candidate), p.id, (target.word(cfg.naming), p.candidate.word(cfg.naming)))
            for p in placements[1:]
        ),
    )


def object_features(spec: EpisodeSpec, obj: SceneObject) -> dict[str, Hashable]:
    """Non-instruction variables of one object, for the confound audit."""
    features: dict[str, Hashable] = {
        "slot": obj.slot,
        "x bin (5 cm)": int(np.floor(obj.pos[0] / 0.05)),
        "y bin (5 cm)": int(np.floor(obj.pos[1] / 0.05)),
        "identity": object_key(obj.name, obj.attributes),
        "kind": obj.kind,
        "composition": (
            tuple(sorted(object_key(o.name, o.attributes) for o in spec.objects)),
            object_key(obj.name, obj.attributes),
        ),
    }
    for attr, value in obj.attributes.items():
        features[f"{attr} at slot"] = (value, obj.slot)
    return features


def object_alternatives(
    cfg: ReferentConfig,
    spec: EpisodeSpec,
    ids: Sequence[str] | None = None,
    extra: Callable[[SceneObject], dict[str, Hashable]] | None = None,
) -> list[Alternative]:
    """Objects as alternatives (all of the scene's, or `ids`), valued by the naming variable."""
    chosen = [spec.object(i) for i in ids] if ids is not None else list(spec.objects)
    out = []
    for o in chosen:
        key = object_key(o.name, o.attributes)
        value = {"name": o.name, "key": key}.get(cfg.naming) or o.attributes.get(cfg.naming, key)
        features = object_features(spec, o) | (extra(o) if extra else {})
        out.append(Alternative(o.id, value, o.slot, features))
    return out


@dataclass(frozen=True)
class Crossed:
    """Four objects crossing two values of an axis with two colors; `objects[(axis, color)]`."""

    placements: tuple[Placement, ...]
    objects: dict[tuple[str, str], Placement]
    axis: tuple[str, str]  # (target's value, the other)
    color: tuple[str, str]  # (target's color, the other)

    @property
    def target(self) -> Placement:
        return self.objects[(self.axis[0], self.color[0])]


def crossed_scene(cfg: ReferentConfig, balance: Balance, axis: str) -> Crossed:
    """Two values of `axis` (e.g. shape or size) x two colors: every object shares one attribute
    with two others, so no single word picks the target. The target is the least-used object;
    the other axis value and the other color are the least used alongside it; slots as usual."""
    table = {(c.word(axis), c.attributes.get("color", "")): c for c in cfg.objects}
    axis_values = list(dict.fromkeys(a for a, _ in table))
    colors = list(dict.fromkeys(col for _, col in table))
    if len(axis_values) < 2 or len(colors) < 2 or len(table) != len(axis_values) * len(colors):
        raise cfg.fail("objects", f"needs every {axis} in the same two or more colors")
    target = balance.pick("target", [c for c in cfg.objects if c.targetable])
    a_target, c_target = target.word(axis), target.attributes["color"]
    a_other = balance.pick(("other", axis, a_target), [a for a in axis_values if a != a_target])
    c_other = balance.pick(("other color", c_target), [col for col in colors if col != c_target])
    slots = list(range(len(cfg.layout.slots)))
    cells = [(a_target, c_target), (a_other, c_target), (a_target, c_other), (a_other, c_other)]
    objects: dict[tuple[str, str], Placement] = {}
    for i, cell in enumerate(cells):
        cand = table[cell]
        free = [s for s in slots if s not in {p.slot for p in objects.values()}]
        slot = (
            target_slot(cfg, balance, cand.key, free)
            if i == 0
            else balance.pick(("distractor_slot", cand.key), free, also="slot")
        )
        objects[cell] = Placement(slug(cand.key), cand, slot)
    return Crossed(tuple(sorted(objects.values(), key=lambda p: p.slot)), objects, (a_target, a_other), (c_target, c_other))
