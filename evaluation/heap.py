"""Giving freed memory back to the system between the stages of a long job.

Why: glibc's malloc keeps the heap a process has freed, in pieces between what is still in use, so a long run's
peak is each stage's need on top of the leftovers of the ones before; ``malloc_trim`` returns every free page.
"""

from __future__ import annotations

import ctypes
import gc


def release_memory() -> None:
    """Collect what is no longer referenced and give the freed heap back to the system (glibc; elsewhere only the
    collection). The collection walks the two young generations, where a stage's own garbage is: a full one walks
    every object of the imported libraries too (0.1 s each time, ../shared/briefs/profile.md), and a stage's arrays
    are freed by their reference counts anyway."""
    gc.collect(1)
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):  # not glibc: nothing to give back this way
        pass
