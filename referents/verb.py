"""Verb referent: the verb names the motor program; the object is named too.

Objects and slots are balanced as in the object referent; the program is balanced per object.
The swap counterfactual changes the verb on the same object. The alternatives the audit sees
are the programs, with object- and position-dependent variables attached to each.
"""

from __future__ import annotations

from core import programs
from core.spec import Counterfactual, EpisodeSpec, TaskSpec
from referents.balance import Balance
from referents.compose import choose_scene
from referents.design import Design
from referents.schema import ReferentConfig
from referents.variables import Alternative, Variable, object_variables


def validate(cfg: ReferentConfig) -> None:
    verbs = cfg.need("verbs", dict)
    alone = [n for n, p in programs.PROGRAMS.items() if p.lands and not p.needs]  # on the named object, nothing else
    unknown = set(verbs) - set(alone)
    if len(verbs) < 2 or unknown:
        raise cfg.fail("verbs", f"needs two or more of the programs {', '.join(alone)}; unknown: {sorted(unknown)}")


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    placements = choose_scene(cfg, balance, cfg.objects, "name")
    target = placements[0]
    verbs: dict[str, str] = cfg.extra["verbs"]
    program = balance.pick(("program", target.candidate.key), list(verbs), also="program")
    template = balance.pick("template", cfg.templates)

    def say(p: str) -> str:
        return template.format(verb=verbs[p], name=target.candidate.name)

    return Design(
        placements=tuple(sorted(placements, key=lambda p: p.slot)),
        target=target.id,
        template=template,
        instruction=say(program),
        counterfactuals=tuple(
            Counterfactual(say(p), target.id, (verbs[program], verbs[p]), program=p) for p in verbs if p != program
        ),
        task=TaskSpec(program=program, lift_margin=cfg.task.lift_margin),
    )


def answer(spec: EpisodeSpec) -> str:
    return spec.task.program


def alternatives(cfg: ReferentConfig, spec: EpisodeSpec) -> list[Alternative]:
    obj = spec.object(spec.target)
    base = object_variables(spec, obj)

    def crossed(p: str) -> dict[str, Variable]:
        """The program, and every object variable paired with it (same families)."""
        return {"program": Variable(p), **{f"{k} and program": Variable((f.value, p), f.family) for k, f in base.items()}}

    return [Alternative(p, verb, obj.slot, crossed(p)) for p, verb in cfg.extra["verbs"].items()]
