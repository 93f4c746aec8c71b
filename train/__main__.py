"""`python -m train dataset=<dir> policy=tiny lora.rank=16 steps=3000 out=<ckpt>`: fine-tune the
tiny policy on a generated dataset, or on the union of several (`'dataset=[<dir>,<dir>]'`; see
train/fit.py); `python -m eval policy=ckpt:<out>` then takes an exam with it."""

from __future__ import annotations

import sys
from pathlib import Path

from jobs.cli import UserError, main
from train.fit import TrainConfig


def validate(cfg: TrainConfig) -> None:
    if cfg.policy != "tiny":
        raise UserError(f"policy must be tiny (the CPU-trainable MiniLM + CNN policy), got {cfg.policy!r}")
    if cfg.finetune not in ("lora", "full", "frozen"):
        raise UserError(f"finetune must be lora, full or frozen, got {cfg.finetune!r}")
    for name in ("steps", "batch_size", "chunk", "threads", "log_every", "save_every"):
        if getattr(cfg, name) < 1:
            raise UserError(f"{name} must be at least 1, got {getattr(cfg, name)}")
    for name in ("warmup", "decay", "keep_every", "aux_weight", "point_weight", "switched_first", "switched_before"):
        if getattr(cfg, name) < 0:
            raise UserError(f"{name} must be at least 0, got {getattr(cfg, name)}")
    if not 0 <= cfg.lr_floor <= 1:
        raise UserError(f"lr_floor is a fraction of the peak learning rate, between 0 and 1; got {cfg.lr_floor}")
    if cfg.favour and (not cfg.balance or not 0 < cfg.favour_share < 1):
        raise UserError(f"favour needs balance=true and favour_share in (0, 1), got {cfg.balance}, {cfg.favour_share}")
    if not 0 <= cfg.switched_share < 1:
        raise UserError(f"switched_share is a share of each batch, in [0, 1); got {cfg.switched_share}")
    for name in ("switched_first", "switched_before", "switched_stay"):
        if getattr(cfg, name) and not cfg.switched_share:
            raise UserError(f"{name}={getattr(cfg, name)} picks the frames switched_share draws from; set switched_share too")
    if cfg.switched_before and cfg.switched_stay:
        raise UserError("switched_before and switched_stay each pick the other half of switched_share; set one")
    if cfg.branch and not Path(cfg.branch).is_file():
        raise UserError(f"branch={cfg.branch} is no training state (a run's stable.pt or last.pt)")
    if cfg.lora.rank < 1:
        raise UserError(f"lora.rank must be at least 1, got {cfg.lora.rank}")


def train(cfg: TrainConfig) -> None:
    validate(cfg)
    from train import data
    from train.fit import fit

    try:
        data.check_all(data.roots(cfg.dataset), cfg.image_size)
        summary = fit(cfg)
    except ValueError as exc:  # the dataset (data.DatasetError) or resume=true over another model config
        raise UserError(str(exc)) from None
    print(
        f"trained {summary['steps']} steps ({summary['trainable_parameters']:,} trainable parameters) on "
        f"{summary['frames']} frames, {summary['tasks']} instructions; final loss {summary['final_loss']:.4f}; "
        f"wrote {cfg.out}/model.pt"
    )
    print(f"take an exam with: python -m eval policy=ckpt:{cfg.out} exam=<exam dir>")


if __name__ == "__main__":
    sys.exit(main("python -m train", TrainConfig, train, doc=__doc__))
