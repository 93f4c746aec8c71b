"""An exam taken the way another lab takes it: its own loop over the documented gymnasium env and
exam format, no import of our policies or oracle, logs scored offline — and nothing the policy
side receives holds the answer."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import pandas as pd
import pytest

from helpers import ONE_TRIAL, Shared

ROOT = Path(__file__).resolve().parents[2]
ANSWER = {"target", "program", "face", "variant", "spec", "alternatives", "original_target", "counterfactuals"}


def readme_loop() -> str:
    """The python block of docs/EXAMS.md's "Taking the exam in your own code", exactly as printed."""
    text = (ROOT / "docs" / "EXAMS.md").read_text()
    section = text[text.index("## Taking the exam in your own code") :]
    return section[section.index("```python\n") + len("```python\n") : section.index("\n```\n")]


def test_the_readmes_own_loop_runs_as_printed_and_reads_the_instruction(tmp_path: Path) -> None:
    """A lab pastes the loop docs/EXAMS.md prints into a folder of its own and runs it: it makes its exam,
    takes every row through the documented env, logs and scores them; nothing the policy side
    receives holds the answer, and its policy obeys the name, on a switch row the new one too."""
    ran = subprocess.run([sys.executable, "-c", readme_loop()], capture_output=True, text=True, cwd=tmp_path)
    assert ran.returncode == 0, ran.stderr[-3000:]
    exam = tmp_path / "datasets" / "object-exam-libero"
    trials = pd.read_parquet(exam / "trials.parquet")
    assert not ANSWER & set(trials.columns)
    scene = json.loads(trials["scene"].iloc[0])
    assert scene["target"] == "" and scene["counterfactuals"] == [] and scene["instruction"] == ""
    env = gym.make("deconfound_exam:deconfound/Exam-v0", exam=str(exam), row=0)
    _, info = env.reset()
    assert not ANSWER & set(info) and info["instruction"] == trials["instruction"].iloc[0]
    env.close()
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["policy"] == "my_policy" and "python -m eval policy=position" in report["baseline_source"]
    assert "Shortcut column: none" in (tmp_path / "report.md").read_text()  # the report says why it is empty
    faces = report["faces"]
    assert faces["obeyed_name"]["rate"] >= 0.8 and faces["true_target"]["rate"] <= 0.1  # it reads the instruction
    assert faces["nonsense"]["k"] == 0 and faces["task"]["k"] == 0  # it never lifts anything
    switched = faces["switch_obeyed"]  # it is given info["instruction"], which changes on a switch row
    assert switched["n"] >= 4 and switched["rate"] >= 0.75 and faces["switch_blind"]["k"] == 0, switched


@pytest.mark.parametrize(
    "module, make",
    [
        ("gen", ["referent=libero_spatial", "n=2", "split=exam", "image_size=32", "switches=0"]),  # switch: its own test
        # two of its tasks: each of the ten is taken and scored in tests/libero/test_libero_goal.py's canonical-exam test
        ("gen.canonical", ["world=libero_goal", "states=1", "tasks=2", "image_size=32", "switches=0"]),
    ],
)
def test_the_readmes_own_loop_scores_a_libero_exam_whose_reset_settles(tmp_path: Path, module: str, make: list[str]) -> None:
    """The same block, its first lines making a LIBERO-world exam (or a canonical one), whose
    reset() runs the settle steps before the first observation: the scorer takes step 0 as the
    block logs it, where reset() leaves the scene."""
    loop = readme_loop()
    assert loop.count('"-m", "gen"') == 1 and "make = [" in loop
    start, end = loop.index("make = ["), loop.index("\n", loop.index("make = ["))
    loop = loop[:start] + f"make = {make + ['out=' + 'X', 'overwrite=true']!r}".replace("'out=X'", 'f"out={exam}"') + loop[end:]
    loop = loop.replace('"-m", "gen"', f'"-m", "{module}"')
    ran = subprocess.run([sys.executable, "-c", loop], capture_output=True, text=True, cwd=tmp_path)
    assert ran.returncode == 0, ran.stderr[-3000:]
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["faces"]["task"]["n"] > 0 and not report.get("errors")


LAB_SCRIPT = """
import gymnasium as gym
{first}
env = gym.make("deconfound_exam:deconfound/Exam-v0", exam={exam!r}, row=0)
obs, info = env.reset()
print(info["instruction"], sorted(obs))
"""


def test_the_env_is_made_from_a_lab_folder_whose_own_packages_share_our_names(shared: Shared, tmp_path: Path) -> None:
    root = shared.dataset("exam", *ONE_TRIAL)
    lab = tmp_path / "lab"
    for package in ("eval", "core"):  # a lab's own packages, first on sys.path when it runs from its folder
        (lab / package).mkdir(parents=True)
        (lab / package / "__init__.py").write_text("LAB = True\n")

    def run(first: str) -> subprocess.CompletedProcess[str]:
        script = LAB_SCRIPT.format(first=first, exam=str(root))
        return subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=lab)

    made = run("")
    assert made.returncode == 0, made.stderr[-2000:]
    instruction = pd.read_parquet(root / "trials.parquet").set_index("row").loc[0, "instruction"]
    assert (
        made.stdout.strip()
        == f"{instruction} {sorted(['observation.images.agentview', 'observation.images.wrist', 'observation.state'])}"
    )
    clash = run("import eval")  # the lab's own eval imported first: one line naming both, not a mixed-up import
    assert clash.returncode != 0
    assert f"a package named 'eval' ({lab / 'eval' / '__init__.py'}) is already imported" in clash.stderr.strip().splitlines()[-1]
