"""Fitting the tiny policy to a generated dataset, or to the union of several (train/data.py):
behaviour cloning of action chunks.

Each step samples frames (with several datasets, or a dataset mixing referent types, from each
dataset and type equally often unless `balance=false`), shifts the images by a few pixels (augmentation), encodes each
distinct instruction of the batch once, and regresses the next `chunk` actions (L1 on
normalised actions, masked past the episode's end). With `point_weight`, the agentview camera's
first keypoint map is also taught where the named object is in the picture (its scene position
seen through the world's camera, shifted with the image), on the frames before the gripper first
closes: a dense signal that finds the named object where the auxiliary head's three numbers did
not (LIBERO-Object's small groceries, docs/RESULTS_LIBERO.md). The learning rate can warm up over
`warmup` steps and then follow a cosine to `lr_floor` of its peak at the last step, over every
step after the warm-up or, with `decay`, only the last `decay` steps (a constant rate, then a
cool-down: the run can be extended and cooled again, see `resume`). Floor 1 keeps it constant.
fp32 by default: with this project's torch (2.14.1, a CUDA build run on the CPU) bf16 autocast
made a step ~15x slower here. A checkpoint (`last.pt`: weights, optimiser, step, random state)
is written every `save_every` steps, at the end, and as `stable.pt` where a cool-down begins, so
`resume=true` continues a killed run, or extends a finished one from the latest of those states
whose learning rates so far match this run's schedule; `model.pt` is the final policy. `branch`
continues another run's saved state in a new `out` (its cool-down redone, say, with `favour`: some
types of a mix drawn more often than the balance gives them).
"""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from core import worlds
from train import data
from train.model import ModelConfig, TinyPolicy
from train.policy import MODEL_FILE, save

if TYPE_CHECKING:
    import torch

LAST = "last.pt"
STABLE = "stable.pt"  # the training state where the cool-down (`decay`) begins


def snapshot_file(step: int) -> str:
    """The weights kept at `step` (`keep_every`), loadable as a checkpoint file."""
    return f"step-{step}.pt"


def kept_steps(out: Path, below: float = float("inf")) -> list[int]:
    """The steps under `below` whose weights are kept in `out` (a run extended with resume=true
    keeps those of its shorter start too)."""
    found = (p.name.removeprefix("step-").removesuffix(".pt") for p in out.glob(snapshot_file("*")))
    return sorted(step for step in map(int, filter(str.isdigit, found)) if step < below)


@dataclass
class LoraOptions:
    rank: int = 16
    alpha: int | None = None  # default: 2 x rank


@dataclass
class TrainConfig:
    dataset: Any = "datasets/object"  # a dataset folder, or several: 'dataset=[a,b]' trains one policy on their union
    balance: bool = True  # each batch draws its frames equally from each dataset and each referent type of a mix
    favour: list[str] = field(default_factory=list)  # referent types of a mix that take `favour_share` of each batch
    favour_share: float = 0.5  # with `favour`: their share of each batch together (the other types split the rest)
    switched_share: float = 0.0  # the share of each batch drawn from switched episodes' frames after the switch (0: as they fall)
    switched_first: int = 0  # with switched_share: only each switched episode's first this many frames from its switch (0: all)
    switched_before: int = 0  # with switched_share: its last this many frames before each switch take half that share
    switched_stay: bool = False  # with switched_share: unswitched episodes' frames at the switches' reach take half that share
    branch: str = ""  # a training state of another run (its stable.pt, last.pt) this run continues from, in `out`
    out: str = "runs/train/tiny"
    policy: str = "tiny"
    finetune: str = "lora"  # lora | full | frozen
    lora: LoraOptions = field(default_factory=LoraOptions)
    steps: int = 3000
    batch_size: int = 32
    lr: float = 3e-4  # vision and head
    text_lr: float | None = None  # text tower (LoRA adapters or full); default 3e-4 for lora, 3e-5 for full
    chunk: int = 10
    image_size: int | None = None  # must equal the dataset's frames; default: the dataset's
    shift: int = 4  # random image shift, pixels
    warmup: int = 0  # steps of linear learning-rate warm-up
    lr_floor: float = 1.0  # the cosine schedule's last learning rate, as a fraction of the peak (1: constant)
    decay: int = 0  # the cosine spans only the last this many steps (a cool-down); 0: every step after warm-up
    feed_located: bool = False  # the action head also reads the auxiliary prediction (see train/model.py)
    state_noise: float = 0.3  # Gaussian noise on the normalised state, so vision must carry the plan
    aux_weight: float = 1.0  # weight of the where-is-the-target loss (needs meta/scenes.parquet)
    point_weight: float = 0.0  # weight of the pointer loss: where in the agentview picture the target is, until the grasp
    seed: int = 0
    threads: int = 2
    bf16: bool = False  # bf16 autocast; measured 15x slower than fp32 on this machine's torch build
    log_every: int = 50
    save_every: int = 500
    keep_every: int = 0  # also keep the weights every this many steps (step-N.pt), for training curves; 0: never
    resume: bool = False


def model_config(cfg: TrainConfig, frames: data.Frames) -> ModelConfig:
    """The model for `frames`: their frame size and profile; the auxiliary target counted from 5 cm
    above the middle of their world's workspace (a table top, LIBERO's floor)."""
    rank = cfg.lora.rank
    world = worlds.world(frames.world)
    x0, x1, y0, y1 = world.reach
    centre = ((x0 + x1) / 2, (y0 + y1) / 2, round(world.surface_z + 0.05, 6))
    return ModelConfig(
        image_size=frames.image_size,
        chunk=cfg.chunk,
        finetune=cfg.finetune,
        lora_rank=rank,
        lora_alpha=cfg.lora.alpha or 2 * rank,
        feed_located=cfg.feed_located,
        profile=frames.profile,
        locate_origin=centre,
    )


def decay_start(cfg: TrainConfig) -> int:
    """The step where the cosine begins."""
    return max(cfg.warmup, cfg.steps - cfg.decay) if cfg.decay else cfg.warmup


def schedule(cfg: TrainConfig, step: int) -> float:
    """The learning rate at `step` as a fraction of its peak: linear warm-up, then constant until
    `decay_start`, then a cosine to `lr_floor` at the last step."""
    if step < cfg.warmup:
        return (step + 1) / cfg.warmup
    begin = decay_start(cfg)
    progress = max(0.0, step - begin) / max(1, cfg.steps - begin)
    return cfg.lr_floor + (1 - cfg.lr_floor) * 0.5 * (1 + np.cos(np.pi * min(1.0, progress)))


def _shift(images: np.ndarray, pixels: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Each image moved by up to `pixels` either way (edges repeated), and how far each moved,
    (n, 2) as (columns, rows)."""
    n, h, w, _ = images.shape
    if pixels <= 0:
        return images, np.zeros((n, 2))
    padded = np.pad(images, ((0, 0), (pixels, pixels), (pixels, pixels), (0, 0)), mode="edge")
    dy, dx = rng.integers(0, 2 * pixels + 1, size=(2, n))
    moved = np.stack([padded[i, dy[i] : dy[i] + h, dx[i] : dx[i] + w] for i in range(n)])
    return moved, np.stack([pixels - dx, pixels - dy], axis=1)


def pixels(frames: data.Frames, mirrored: bool) -> np.ndarray:
    """Where each target starts in its agentview frames (a row per row of `frames.target`: each
    episode's, then each switched episode's second), as (column, row), seen through the camera of
    the world its scene is in."""
    out = np.empty((len(frames.target), 2))
    for name in np.unique(frames.target_world):
        chosen = frames.target_world == name
        out[chosen] = worlds.world(str(name)).agentview.project(frames.target[chosen], frames.image_size, mirrored)
    return out


def point_loss(logits: torch.Tensor, pixels: torch.Tensor, image_size: int, sigma: float = 1.0) -> torch.Tensor:
    """Cross-entropy of the pointer's map (B, h, w) against a Gaussian of `sigma` cells around
    each target pixel (B, 2: column, row in the image's pixels), per frame (B,)."""
    import torch

    b, h, w = logits.shape
    cells = pixels * torch.tensor([w / image_size, h / image_size]) - 0.5
    xs, ys = torch.arange(w, dtype=torch.float32), torch.arange(h, dtype=torch.float32)
    gx = torch.exp(-0.5 * ((xs[None] - cells[:, :1]) / sigma) ** 2)
    gy = torch.exp(-0.5 * ((ys[None] - cells[:, 1:]) / sigma) ** 2)
    wanted = gy[:, :, None] * gx[:, None, :]
    wanted = wanted / wanted.sum(dim=(1, 2), keepdim=True).clamp(min=1e-12)
    return -(wanted * torch.log_softmax(logits.float().reshape(b, -1), dim=-1).reshape(b, h, w)).sum(dim=(1, 2))


def fit(cfg: TrainConfig, progress: bool = True) -> dict:
    import torch
    from tqdm import tqdm

    torch.set_num_threads(cfg.threads)
    frames = data.load(cfg.dataset, cfg.image_size)
    out = Path(cfg.out)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(cfg.seed)
    torch.manual_seed(cfg.seed)
    model = TinyPolicy(model_config(cfg, frames), frames.stats)
    text_params = [p for p in model.text.parameters() if p.requires_grad]
    other = [p for n, p in model.named_parameters() if p.requires_grad and not n.startswith("text.")]
    text_lr = cfg.text_lr or (3e-5 if cfg.finetune == "full" else cfg.lr)
    optimizer = torch.optim.AdamW([{"params": other, "lr": cfg.lr}, {"params": text_params, "lr": text_lr}], weight_decay=1e-4)
    peaks = [cfg.lr, text_lr]
    step, history = 0, []
    record = _resumable(cfg, out, model.config.to_dict()) if cfg.resume else None
    if record is None and cfg.branch:
        record = _continued(cfg, Path(cfg.branch), model.config.to_dict())
        if record is None:
            raise ValueError(f"branch={cfg.branch} was trained on another learning-rate schedule (lr, warmup, decay, lr_floor)")
    if record is not None:
        model.load_state_dict(record["weights"], strict=False)
        optimizer.load_state_dict(record["optimizer"])
        step, history = record["step"], record["history"]
        rng.bit_generator.state = record["rng"]
        torch.set_rng_state(record["torch_rng"])
        for later in kept_steps(out):  # kept by a run this one replaces past `step`
            if later > step:
                (out / snapshot_file(later)).unlink()
        if cfg.keep_every:  # the curve gains the point resumed from (where a finished shorter run ended)
            save(out / snapshot_file(step), model, {"train": asdict(cfg), "step": step})
    frozen_text = None
    if cfg.finetune == "frozen":
        with torch.no_grad():
            frozen_text = model.embed(frames.tasks)
    action = torch.from_numpy(frames.action)
    target_pos = torch.from_numpy(frames.target) if frames.target is not None else None
    pointing = cfg.point_weight > 0
    if pointing:
        if frames.target is None:
            raise data.DatasetError(f"point_weight={cfg.point_weight} needs the datasets' scene records (meta/scenes.parquet)")
        target_pixel = pixels(frames, model.config.features.mirrored)
        reaching = data.until_grasp(frames)
    n_trainable = sum(p.numel() for p in model.parameters() if p.requires_grad)
    draw_from = data.groups(frames) if cfg.balance else None
    chances = data.favoured(frames, draw_from, cfg.favour, cfg.favour_share) if cfg.favour else None
    if cfg.switched_share:
        draw_from, chances = data.after_switch(
            frames, draw_from, chances, cfg.switched_share, cfg.switched_first, cfg.switched_before, cfg.switched_stay
        )
    start, running = time.perf_counter(), []
    bar = tqdm(total=cfg.steps, initial=step, desc=f"train {cfg.finetune}", unit="step", disable=not progress)
    model.train()
    while step < cfg.steps:
        if cfg.decay and step == decay_start(cfg):  # where a longer run would branch off
            _checkpoint(out / STABLE, model, optimizer, step, history, rng)
        index = data.sample(frames, rng, cfg.batch_size, cfg.balance or bool(cfg.switched_share), draw_from, chances)
        targets, mask = data.chunk_indices(frames, index, cfg.chunk)
        shifted = {c: _shift(frames.images[c][index], cfg.shift, rng) for c in model.cameras}
        images = {c: torch.from_numpy(moved) for c, (moved, _) in shifted.items()}
        state = torch.from_numpy(frames.state[index])
        tasks = frames.task[index]
        with torch.autocast("cpu", dtype=torch.bfloat16, enabled=cfg.bf16):
            if frozen_text is not None:
                text = frozen_text[tasks]
            else:
                unique, inverse = np.unique(tasks, return_inverse=True)
                text = model.embed([frames.tasks[t] for t in unique])[torch.from_numpy(inverse)]
            predicted, located, pointer = model(images, state, text, cfg.state_noise)
        goal = model.normalise(action[torch.from_numpy(targets)])
        weight = torch.from_numpy(mask).float().unsqueeze(-1)
        loss = ((predicted.float() - goal).abs() * weight).sum() / (weight.sum() * goal.shape[-1])
        if target_pos is not None and cfg.aux_weight > 0:
            where = model.locate_target(target_pos[torch.from_numpy(frames.aim[index])])
            loss = loss + cfg.aux_weight * (located.float() - where).abs().mean()
        if pointing:
            pixel = target_pixel[frames.aim[index]] + shifted[model.pointer_camera][1]
            per_frame = point_loss(pointer, torch.from_numpy(pixel).float(), frames.image_size)
            loss = loss + cfg.point_weight * (per_frame * torch.from_numpy(reaching[index]).float()).mean()
        for group, peak in zip(optimizer.param_groups, peaks):
            group["lr"] = peak * schedule(cfg, step)
        optimizer.zero_grad(set_to_none=True)
        loss.backward()
        torch.nn.utils.clip_grad_norm_(model.parameters(), 1.0)
        optimizer.step()
        step += 1
        running.append(loss.item())
        bar.update()
        if step % cfg.log_every == 0 or step == cfg.steps:
            history.append({"step": step, "loss": float(np.mean(running)), "lr": optimizer.param_groups[0]["lr"]})
            bar.set_postfix(loss=f"{history[-1]['loss']:.4f}")
            running = []
        if step % cfg.save_every == 0 or step == cfg.steps:
            _checkpoint(out / LAST, model, optimizer, step, history, rng)
        if cfg.keep_every and step % cfg.keep_every == 0 and step < cfg.steps:
            save(out / snapshot_file(step), model, {"train": asdict(cfg), "step": step})
    bar.close()
    seconds = time.perf_counter() - start
    save(out / MODEL_FILE, model, {"train": asdict(cfg), "history": history})
    summary = {
        "steps": step,
        "final_loss": history[-1]["loss"] if history else None,
        "trainable_parameters": n_trainable,
        "seconds_this_run": round(seconds, 1),
        "frames": len(frames),
        "tasks": len(frames.tasks),
        "config": asdict(cfg),
        "history": history,
    }
    (out / "train.json").write_text(json.dumps(summary, indent=2))
    return summary


def _resumable(cfg: TrainConfig, out: Path, config: dict) -> dict | None:
    """The latest saved state in `out` (last.pt, else stable.pt) that this run continues: the
    same model, and every learning rate it logged is the one this run's schedule gives there."""

    found = [out / name for name in (LAST, STABLE) if (out / name).is_file()]
    for path in found:
        record = _continued(cfg, path, config)
        if record is not None:
            return record
    if found:
        raise ValueError(f"resume=true but {out} holds a run on another learning-rate schedule (lr, warmup, decay, lr_floor)")
    return None


def _continued(cfg: TrainConfig, path: Path, config: dict) -> dict | None:
    """The training state in `path` if this run continues it: the same model, and every learning
    rate it logged the one this run's schedule gives there; None where the schedules differ."""
    import torch

    record = torch.load(path, map_location="cpu", weights_only=False)
    if record["config"] != config:
        raise ValueError(f"{path} was trained with another model config: {record['config']}")
    if all(np.isclose(h["lr"], cfg.lr * schedule(cfg, h["step"] - 1), rtol=1e-9, atol=0) for h in record["history"]):
        return record
    return None


def _checkpoint(path: Path, model: TinyPolicy, optimizer, step: int, history: list, rng: np.random.Generator) -> None:  # noqa: ANN001
    import torch

    save(
        path,
        model,
        {
            "optimizer": optimizer.state_dict(),
            "step": step,
            "history": history,
            "rng": rng.bit_generator.state,
            "torch_rng": torch.get_rng_state(),
        },
    )
