"""Fault injection for the crash tests: with DECONFOUND_CRASH_AT=<point> set, the process
SIGKILLs itself on reaching that point (`episode:<i>` before episode i is saved, `save:<i>`
halfway through saving it, `assemble:<i>` with the video files half written, `finalize`
before the completion marker, `worker:<i>` inside the worker process producing episode i).
With DECONFOUND_CRASH_ONCE=<file> as well, only the first process to get there dies (it
creates the file), so a restarted worker goes on. Unset, nothing happens."""

from __future__ import annotations

import os
import signal
from pathlib import Path


def point(name: str) -> None:
    if os.environ.get("DECONFOUND_CRASH_AT") != name:
        return
    once = os.environ.get("DECONFOUND_CRASH_ONCE")
    if once:
        try:
            Path(once).touch(exist_ok=False)
        except FileExistsError:
            return
    os.kill(os.getpid(), signal.SIGKILL)
