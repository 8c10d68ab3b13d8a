"""Output directories written whole or not at all.

A command's outputs go into a hidden temporary directory beside the target, named after the target, this host and
the writing process, and are moved into place only when complete: an interrupted or failed command leaves nothing
under the target's name, and an existing non-empty directory is never touched. A process killed outright (``kill
-9``) cannot remove its temporary directory; the next command that writes into the same parent folder does, once
the process that made it is gone.
"""

from __future__ import annotations

import os
import re
import shutil
import socket
import tempfile
from pathlib import Path

_TAG = "crowdsim-partial"


class RunDirError(ValueError):
    pass


def check_out_dir(out: Path) -> None:
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise RunDirError(f"--out {out}: already exists and is not empty; expected a new or empty directory "
                          f"(nothing was written)")


def _host() -> str:
    return re.sub(r"[^A-Za-z0-9_-]", "_", socket.gethostname()) or "host"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process: alive
        return True
    return True


def remove_stale(parent: Path) -> list[Path]:
    """Remove the temporary directories in ``parent`` that a process of this host left behind when it was killed
    (its process is gone); return them. Directories of live processes, of other hosts, and anything not named as
    ``write_directory`` names its temporary directories are left alone."""
    pattern = re.compile(rf"^\..+\.{_TAG}-{re.escape(_host())}-(\d+)-[^.]+$")
    removed = []
    try:
        entries = list(Path(parent).iterdir())
    except OSError:
        return removed
    for path in entries:
        match = pattern.match(path.name)
        if match and path.is_dir() and not path.is_symlink() and not _alive(int(match.group(1))):
            shutil.rmtree(path, ignore_errors=True)
            removed.append(path)
    return removed


def write_directory(out: Path, write):
    """Call ``write(tmp)`` to fill a fresh temporary directory beside ``out`` and move it into place only when
    complete: a failure leaves nothing half-written, and an existing non-empty ``out`` is never touched.
    Returns what ``write`` returns."""
    out = Path(out)
    check_out_dir(out)
    made = [p for p in reversed(out.absolute().parents) if not p.exists()]  # parents this creates
    out.parent.mkdir(parents=True, exist_ok=True)
    remove_stale(out.parent)
    tmp = None
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.{_TAG}-{_host()}-{os.getpid()}-", dir=out.parent))
        umask = os.umask(0)
        os.umask(umask)
        tmp.chmod(0o777 & ~umask)  # mkdtemp makes it private; the finished directory is an ordinary one
        result = write(tmp)
        if out.exists():
            out.rmdir()  # checked empty above
        tmp.rename(out)
    except BaseException:
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)
        for parent in reversed(made):
            try:
                parent.rmdir()
            except OSError:
                break
        raise
    return result
