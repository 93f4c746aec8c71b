"""The confound audit: does anything but the instruction predict the target?

Computed from episode specs alone (no simulation). For every non-instruction variable a
referent exposes (slot, position bins, identity, composition, rank, side, ...), a predictor
learns on 4/5 of the episodes how often an alternative with each value of the variable was the
answer, and on the held-out fifth picks the alternative whose value scored best (ties share the
credit). Its held-out accuracy, with a Wilson 95% interval, is compared with chance (one over
the number of alternatives). A variable leaks when the lower end of a one-sided 95% Wilson
bound, Bonferroni-corrected for the number of variables audited, exceeds chance by more than
LEAK_MARGIN. Below MIN_EPISODES a plan is too small for any verdict and none is given. A leak
is expected when the options asked for it: `confound=position` for variables of the POSITION
family, `confound=layout` for both families, a vocabulary restriction (distractor_only, targets)
for the IDENTITY family; each variable declares its families where the referent makes it
(referents/variables.py).
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence
from statistics import NormalDist

import pandas as pd

from core.rates import Rate, wilson
from core.spec import EpisodeSpec
from referents.registry import Referent
from referents.variables import IDENTITY, POSITION, Family

FOLDS = 5
LEAK_MARGIN = 0.05
MIN_EPISODES = 20
AUDIT_VERSION = 1


def _table(referent: Referent, goals: Sequence[EpisodeSpec]) -> tuple[pd.DataFrame, dict[str, Family]]:
    """One row per (goal, alternative, variable); and each variable's families."""
    rows = []
    families: dict[str, Family] = defaultdict(lambda: Family.NONE)
    for i, goal in enumerate(goals):
        answer = referent.answer(goal)
        for alt in referent.alternatives(goal):
            for var, variable in alt.variables.items():
                rows.append((i, i % FOLDS, alt.id, var, repr(variable.value), alt.id == answer))
                families[var] |= variable.family
    return pd.DataFrame(rows, columns=["episode", "fold", "alt", "variable", "value", "answer"]), families


def _goals(specs: Sequence[EpisodeSpec]) -> list[EpisodeSpec]:
    """What the audit reads: each goal of each episode (LIBERO-10's "put both": the second named too,
    which nothing but the words may predict either), as a spec of that goal (EpisodeSpec.goals)."""
    return [goal for spec in specs for goal in spec.goals()]


def _held_out_hits(df: pd.DataFrame) -> float:
    """Expected number of held-out episodes whose answer a value->rate predictor picks."""
    hits = 0.0
    prior = df["answer"].mean()
    for fold in range(FOLDS):
        train, test = df[df.fold != fold], df[df.fold == fold]
        if test.empty:
            continue
        stats = train.groupby("value")["answer"].agg(["sum", "count"])
        score = ((stats["sum"] + prior) / (stats["count"] + 1)).rename("score")
        scored = test.join(score, on="value")
        scored["score"] = scored["score"].fillna(prior)
        best = scored.groupby("episode")["score"].transform("max")
        top = scored[scored.score >= best - 1e-12]
        per_episode = top.groupby("episode")["answer"].agg(["sum", "count"])
        hits += float((per_episode["sum"] / per_episode["count"]).sum())
    return hits


def expected_leaks(referent: Referent) -> Family:
    """The families of variables that are meant to leak because the user asked for it."""
    families = Family.NONE
    if referent.config.confound == "position":
        families |= POSITION
    if referent.config.confound == "layout":  # where the target stands, and among what
        families |= POSITION | IDENTITY
    if referent.config.distractor_only or referent.config.targets:
        families |= IDENTITY
    return families


def audit(referent: Referent, specs: Sequence[EpisodeSpec]) -> dict:
    """The audit as JSON-ready data; see module docstring."""
    goals = _goals(specs)
    n = len(goals)
    df, families = _table(referent, goals)
    per_episode = df.drop_duplicates(["episode", "alt"]).groupby("episode").size()
    chance = float((1.0 / per_episode).mean())
    expected = expected_leaks(referent)
    groups = list(df.groupby("variable", sort=True))
    z = NormalDist().inv_cdf(1 - 0.05 / max(len(groups), 1))
    variables = []
    for var, sub in groups:
        rate = Rate(_held_out_hits(sub), n)
        bound = wilson(rate.k, n, z)[0]
        leak = n >= MIN_EPISODES and bound > chance + LEAK_MARGIN
        variables.append(
            {
                "variable": var,
                **rate.to_dict(),
                "leak_bound": round(bound, 4),
                "chance": round(chance, 4),
                "leak": leak,
                "expected": leak and bool(families[var] & expected),
            }
        )
    leaks = [v["variable"] for v in variables if v["leak"]]
    unexpected = [v["variable"] for v in variables if v["leak"] and not v["expected"]]
    return {
        "version": AUDIT_VERSION,
        "referent": referent.name,
        "episodes": len(specs),
        **({"goals": n} if n != len(specs) else {}),  # a task of more goals: each audited
        "chance": round(chance, 4),
        "method": f"{FOLDS}-fold held-out accuracy of a value->answer-rate predictor per variable; leak when the "
        f"Bonferroni-corrected one-sided 95% Wilson lower bound exceeds chance + {LEAK_MARGIN}",
        "variables": variables,
        "balance": role_balance(referent, specs),
        "vocabulary": {
            "holdout": list(referent.config.holdout),
            "distractor_only": list(referent.config.distractor_only),
            "targets": list(referent.config.targets),
        },
        "confound": referent.config.confound,
        "leaks": leaks,
        "unexpected_leaks": unexpected,
        "verdict": (
            f"too few episodes to audit (n < {MIN_EPISODES})"
            if n < MIN_EPISODES
            else "no leak"
            if not leaks
            else f"leak: {', '.join(leaks)}"
        ),
    }


def role_balance(referent: Referent, specs: Sequence[EpisodeSpec]) -> dict[str, dict[str, dict[str, int]]]:
    """value -> role (target / distractor) -> slot -> count."""
    table: dict[str, dict[str, dict[str, int]]] = defaultdict(lambda: {"target": {}, "distractor": {}})
    for goal in _goals(specs):
        answer = referent.answer(goal)
        for alt in referent.alternatives(goal):
            cell = table[alt.value]["target" if alt.id == answer else "distractor"]
            cell[str(alt.slot)] = cell.get(str(alt.slot), 0) + 1
    return {
        value: {role: dict(sorted(c.items(), key=lambda kv: int(kv[0]))) for role, c in roles.items()}
        for value, roles in sorted(table.items())
    }


def agree(planned: dict, written: dict) -> bool:
    """Resampled demos keep roles, so the two audits must reach the same verdict and balance."""
    return planned["leaks"] == written["leaks"] and planned["balance"] == written["balance"]
