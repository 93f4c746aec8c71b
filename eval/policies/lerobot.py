"""A LeRobot checkpoint takes the exam (`policy=lerobot:<pretrained_model dir>`).

Any `PreTrainedPolicy` that `lerobot-train` saved (ACT, Diffusion, SmolVLA, pi0, ...) is loaded
with lerobot's own classes, and its saved pre- and post-processors (normalisation, tokenizer,
device) run around it exactly as in `lerobot-eval`. The exam's observations already use the
dataset's feature names and conventions (a `profile=libero` exam's frames and 8-d state are
those of lerobot's LIBERO datasets), so they go in as the checkpoint saw them in training:
frames as float (1, 3, H, W) in [0, 1], state as float32 (1, D), the instruction as `task`.
The policy's own `select_action` keeps its action queue, so its chunking (`n_action_steps`,
temporal ensembling) is the checkpoint's; `reset` clears it at each rollout.

A checkpoint that `lerobot-train --peft.method_type=LORA ...` saved holds only its adapter
(`adapter_config.json`, `adapter_model.safetensors`, `"use_peft": true`): it is loaded as lerobot's
`make_policy` loads it, the base policy its adapter config names with this folder's config, the
adapter on top, and this folder's processors.

lerobot itself is imported only when such a policy is made; its features are checked against
the exam's before any rollout (`check`).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from core.profiles import IMAGE_PREFIX, TASK_KEY
from eval.policies import Context, PolicyError, require_features

if TYPE_CHECKING:
    from lerobot.configs.policies import PreTrainedConfig
    from lerobot.policies.pretrained import PreTrainedPolicy
    from peft import PeftModel

INSTALL = "make setup installs it (lerobot==0.4.4 without its torch pin; docs/EXAMS.md 'LeRobot checkpoints')"


class LeRobotPolicy:
    argument = "PATH"  # written lerobot:PATH (eval/policies/registry.py): a pretrained_model folder
    needs_images = True

    def __init__(self, path: str, device: str = "cpu") -> None:
        folder = Path(path)
        if not (folder / "config.json").is_file():
            raise PolicyError(f"{folder} is not a LeRobot checkpoint (no config.json; pass the pretrained_model folder)")
        try:
            import torch
            from lerobot.configs.policies import PreTrainedConfig
            from lerobot.policies.factory import get_policy_class, make_pre_post_processors
        except ImportError as exc:
            raise PolicyError(f"policy lerobot needs lerobot: {exc}; {INSTALL}") from None
        try:
            config = PreTrainedConfig.from_pretrained(folder)
            config.device = device
            policy_class = get_policy_class(config.type)
            if config.use_peft:
                self.policy = _adapted(policy_class, config, folder).to(device)
            else:
                self.policy = policy_class.from_pretrained(folder, config=config)
            self.preprocess, self.postprocess = make_pre_post_processors(  # an adapter's own, as lerobot-eval reads them
                config, pretrained_path=str(folder), preprocessor_overrides={"device_processor": {"device": device}}
            )
        except PolicyError:
            raise
        except Exception as exc:  # a folder lerobot cannot read: one line, not a traceback
            raise PolicyError(f"{folder}: lerobot cannot load this checkpoint: {type(exc).__name__}: {exc}") from None
        self.policy.eval()
        self._torch = torch
        self.name = f"lerobot:{path}"
        self.config = config

    def features(self) -> dict[str, tuple[int, ...]]:
        """The checkpoint's features as the exam states them: frames (H, W, 3), state, action."""
        expected = {}
        for key, feature in self.config.input_features.items():
            shape = tuple(feature.shape)
            expected[key] = (shape[1], shape[2], shape[0]) if key.startswith(IMAGE_PREFIX) else shape
        return expected | {key: tuple(f.shape) for key, f in self.config.output_features.items()}

    def check(self, features: dict[str, tuple[int, ...]]) -> None:
        require_features(self.features(), features, f"checkpoint {self.name.removeprefix('lerobot:')}")

    def reset(self, context: Context) -> None:
        self.policy.reset()
        self.preprocess.reset()
        self.postprocess.reset()

    def act(self, observation: dict) -> np.ndarray:
        torch = self._torch
        batch: dict = {TASK_KEY: [str(observation[TASK_KEY])]}
        for key in self.config.input_features:
            value = np.asarray(observation[key])
            if key.startswith(IMAGE_PREFIX):  # (H, W, 3) uint8 -> (1, 3, H, W) float in [0, 1], as lerobot-eval feeds it
                batch[key] = torch.from_numpy(np.ascontiguousarray(value.transpose(2, 0, 1))).float()[None] / 255.0
            else:
                batch[key] = torch.from_numpy(value.astype(np.float32))[None]
        with torch.inference_mode():
            action = self.postprocess(self.policy.select_action(self.preprocess(batch)))
        return action[0].cpu().numpy()


def _adapted(policy_class: type[PreTrainedPolicy], config: PreTrainedConfig, folder: Path) -> PeftModel:
    """lerobot's `make_policy` for a PEFT checkpoint: the folder holds only the adapter, so the base policy its
    adapter config names (`base_model_name_or_path`, the `--policy.path` it was trained from) is loaded with
    this folder's config and the adapter put on top with peft."""
    from peft import PeftConfig, PeftModel

    adapter = PeftConfig.from_pretrained(str(folder))
    base = adapter.base_model_name_or_path
    if not base:
        raise PolicyError(f"{folder}: its adapter_config.json names no base policy (base_model_name_or_path)")
    try:
        policy = policy_class.from_pretrained(base, config=config)
    except Exception as exc:
        why = f"{type(exc).__name__}: {exc}" if Path(base).is_dir() else f"no folder {Path(base).absolute()}"
        raise PolicyError(f"{folder}: cannot load the base policy its adapter_config.json names ({base}): {why}") from None
    return PeftModel.from_pretrained(policy, str(folder), config=adapter)
