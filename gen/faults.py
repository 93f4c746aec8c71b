"""Fault injection for the crash tests: with DECONFOUND_CRASH_AT=<point> set, the process
SIGKILLs itself on reaching that point (`episode:<i>` before episode i is saved, `save:<i>`
halfway through saving it, `assemble:<i>` with the video files half written, `finalize`
before the completion marker). Unset, nothing happens."""

from __future__ import annotations

import os
import signal


def point(name: str) -> None:
    if os.environ.get("DECONFOUND_CRASH_AT") == name:
        os.kill(os.getpid(), signal.SIGKILL)
