"""Giving freed memory back to the system between the stages of a long job.

Why: glibc's malloc keeps the heap a process has freed, in pieces between what is still in use, so a long run's
peak is each stage's need on top of the leftovers of the ones before; ``malloc_trim`` returns every free page.
"""

from __future__ import annotations

import ctypes
import gc


def release_memory() -> None:
    """Collect what is no longer referenced and give the freed heap back to the system (glibc; elsewhere only the
    collection)."""
    gc.collect()
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):  # not glibc: nothing to give back this way
        pass
