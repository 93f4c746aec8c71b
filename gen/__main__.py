"""`python -m gen referent=object n=20 seed=0 out=datasets/object image_size=128 fps=20`."""

from __future__ import annotations

import sys

from gen.cli import UserError, usage
from gen.config import GenConfig, parse

USAGE = usage("python -m gen", GenConfig)


def main(argv: list[str]) -> int:
    if any(a in ("-h", "--help", "help") for a in argv):
        print(USAGE)
        return 0
    try:
        cfg = parse(argv)
        from gen.run import generate  # the simulator stack loads only for valid input

        summary = generate(cfg)
        if cfg.push_to_hub:
            from gen.push import PushError, push

            print(summary)
            try:
                pushed = push(summary.out, cfg.repo_id or "")
            except PushError as exc:
                print(f"error: {exc}", file=sys.stderr)
                return 1
            print(f"pushed {len(pushed.files)} files to {pushed.url} (tag {pushed.tag})")
            return 0
    except UserError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("error: interrupted; nothing was written to out", file=sys.stderr)
        return 130
    print(summary)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
