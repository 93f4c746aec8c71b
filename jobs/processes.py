"""Worker processes that never outlive their run."""

from __future__ import annotations

import ctypes
import os
import signal


def die_with(parent: int) -> None:
    """Make this worker process die with the run that started it (pid `parent`): a run killed
    outright (SIGKILL, out of memory) would otherwise leave its pool's workers waiting forever,
    holding its output pipes open (Linux's parent-death signal; elsewhere nothing is armed)."""
    try:
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        return
    if os.getppid() != parent:  # the run died before the signal was armed
        os._exit(1)
