"""A world's fixed destination (LIBERO-Object's basket): the spec's `container` field, which any
referent type may carry without knowing it.

A type designs its scene on the layout less its last slot; the container stands in that last slot
of every scene and every episode carries its target there (`task.params.destination`). It is never
an alternative and never named, so the audit, the exam's swaps and the shortcut see the type's own
scene (`without`). This is how a type's design is written once and a world brings where things go.
"""

from __future__ import annotations

from dataclasses import replace

from core.spec import EpisodeSpec
from referents.compose import slug
from referents.design import Design, Placement
from referents.schema import Candidate, ReferentConfig

FIELD = "container"


def container(cfg: ReferentConfig) -> Candidate | None:
    """The spec's container (`container: {kind, name}`), or None."""
    field = cfg.extra.get(FIELD)
    if field is None:
        return None
    if not isinstance(field, dict) or not isinstance(field.get("kind"), str) or not isinstance(field.get("name"), str):
        raise cfg.fail(FIELD, f"must be a mapping with a kind and a name, got {field!r}")
    return Candidate(field["kind"], field["name"], role=FIELD)


def inner(cfg: ReferentConfig) -> ReferentConfig:
    """The spec as the type designs with it: the layout without the container's (last) slot."""
    if container(cfg) is None:
        return cfg
    return replace(cfg, layout=replace(cfg.layout, slots=cfg.layout.slots[:-1]))


def add(cfg: ReferentConfig, design: Design) -> Design:
    """The type's design with the container in the last slot and the target carried into it."""
    held = container(cfg)
    if held is None:
        return design
    placed = Placement(slug(held.name), held, len(cfg.layout.slots) - 1)
    task = design.task or cfg.task
    return replace(
        design, placements=(*design.placements, placed), task=replace(task, params={**task.params, "destination": placed.id})
    )


def without(spec: EpisodeSpec) -> EpisodeSpec:
    """The scene as the type sees it: without the object its target is carried into."""
    destination = spec.task.params.get("destination")
    if destination is None:
        return spec
    return replace(spec, objects=tuple(o for o in spec.objects if o.id != destination))


def restored(spec: EpisodeSpec, seen: EpisodeSpec) -> EpisodeSpec:
    """`seen` (an episode the type made of `without(spec)`) back in the whole scene, still carried there."""
    return replace(seen, objects=spec.objects, task=replace(seen.task, program=spec.task.program, params=spec.task.params))
