"""`python -m train dataset=<dir> policy=tiny lora.rank=16 steps=3000 out=<ckpt>`: fine-tune the
tiny policy on a generated dataset (see train/fit.py); `python -m eval policy=ckpt:<out>` then
takes an exam with it."""

from __future__ import annotations

import sys
from pathlib import Path

from gen.cli import UserError, compose_config, usage
from train.fit import TrainConfig

USAGE = usage("python -m train", TrainConfig)


def validate(cfg: TrainConfig) -> None:
    if cfg.policy != "tiny":
        raise UserError(f"policy must be tiny (the CPU-trainable MiniLM + CNN policy), got {cfg.policy!r}")
    if cfg.finetune not in ("lora", "full", "frozen"):
        raise UserError(f"finetune must be lora, full or frozen, got {cfg.finetune!r}")
    for name in ("steps", "batch_size", "chunk", "threads", "log_every", "save_every"):
        if getattr(cfg, name) < 1:
            raise UserError(f"{name} must be at least 1, got {getattr(cfg, name)}")
    if cfg.lora.rank < 1:
        raise UserError(f"lora.rank must be at least 1, got {cfg.lora.rank}")


def main(argv: list[str]) -> int:
    if any(a in ("-h", "--help", "help") for a in argv):
        print(USAGE)
        return 0
    from train import data

    try:
        cfg = compose_config("train", TrainConfig, argv)
        validate(cfg)
        data.check(Path(cfg.dataset), cfg.image_size)
        from train.fit import fit

        summary = fit(cfg)
    except (UserError, data.DatasetError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(
        f"trained {summary['steps']} steps ({summary['trainable_parameters']:,} trainable parameters) on "
        f"{summary['frames']} frames, {summary['tasks']} instructions; final loss {summary['final_loss']:.4f}; "
        f"wrote {cfg.out}/model.pt"
    )
    print(f"take an exam with: python -m eval policy=ckpt:{cfg.out} exam=<exam dir>")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
