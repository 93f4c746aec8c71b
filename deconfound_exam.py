"""The exam's gymnasium environment, registered under a module name no lab's own folder shadows.

    import gymnasium as gym
    env = gym.make("deconfound_exam:deconfound/Exam-v0", exam="datasets/object-exam", row=0)

works from any directory with nothing imported first: gymnasium imports this module for the
`deconfound_exam:` prefix (gymnasium 1.x loads third-party environments that way; it no longer
reads plugin entry points), which registers `deconfound/Exam-v0`; after `import deconfound_exam`
the plain id works too. The environment itself is `eval.env.ExamEnv` (documented there and in
docs/EXAM_FORMAT.md).

This project's packages have plain names (`eval`, `core`, ...), which a lab's own folders of the
same name would shadow on `sys.path`. So the environment loads them from this installation by
file location; a package of the same name that the lab has already imported is reported in one
line instead of being silently mixed with ours.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import gymnasium as gym

ENV_ID = "deconfound/Exam-v0"
ROOT = Path(__file__).resolve().parent
PACKAGES = ("core", "referents", "oracle", "gen", "eval")  # what eval.env imports, bottom layer first


def _load_ours(name: str) -> None:
    """Import this installation's package `name`, wherever the current directory is."""
    loaded = sys.modules.get(name)
    if loaded is not None:
        origin = Path(getattr(loaded, "__file__", None) or ".").resolve()
        if not origin.is_relative_to(ROOT / name):
            raise ImportError(
                f"a package named {name!r} ({origin}) is already imported, and the exam environment needs this "
                f"installation's {name!r} ({ROOT / name}); make the environment before importing yours"
            )
        return
    spec = importlib.util.spec_from_file_location(
        name, ROOT / name / "__init__.py", submodule_search_locations=[str(ROOT / name)]
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[name]
        raise


def make_exam_env(**kwargs: object) -> gym.Env:
    """`gymnasium.make`'s entry point: the exam environment for one row (see eval.env.ExamEnv)."""
    for name in PACKAGES:
        _load_ours(name)
    from eval.env import ExamEnv

    return ExamEnv(**kwargs)


if ENV_ID not in gym.registry:
    gym.register(id=ENV_ID, entry_point=make_exam_env)
