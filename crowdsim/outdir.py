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

from .errors import Error

_TAG = "crowdsim-partial"


class RunDirError(Error):
    """An output path that cannot take a command's output."""


NAME_MAX = 255  # bytes of one path component (Linux, macOS)
PATH_MAX = 4096  # bytes of a whole path (Linux)


def _where_made(path: Path, flag: str) -> Path:
    """The nearest folder above ``path`` that exists, once ``path`` is known to have a legal name and to need no
    file to hold a folder; RunDirError naming ``flag`` otherwise."""
    text = str(path)
    shown = text if len(text) <= 80 else text[:80] + "..."
    if "\0" in text or len(os.fsencode(text)) > PATH_MAX:
        raise RunDirError(f"{flag} {shown!r}: not a legal path; expected at most {PATH_MAX} bytes, no NUL")
    long = [part for part in path.parts if len(os.fsencode(part)) > NAME_MAX]
    if long:
        raise RunDirError(f"{flag} {shown}: a name of {len(os.fsencode(long[0]))} bytes; expected at most "
                          f"{NAME_MAX} bytes for each name in the path")
    for above in path.absolute().parents:
        if above.exists():
            if not above.is_dir():
                raise RunDirError(f"{flag} {path}: {above} is a file; expected a folder there")
            return above
    return Path("/")  # pragma: no cover - the root exists


def _can_write(folder: Path, path: Path, flag: str) -> None:
    """A folder can be made in ``folder`` (tried: permissions, read-only and special file systems such as /proc)."""
    try:
        Path(tempfile.mkdtemp(prefix=f".{_TAG}-check-", dir=folder)).rmdir()
    except OSError as e:
        raise RunDirError(f"{flag} {path}: cannot write in {folder} ({e.strerror}); expected a folder this user can "
                          f"write in") from None


def check_out_dir(out: Path, flag: str = "--out") -> None:
    """``out`` can take a command's output folder: a legal name, new or empty, in a place where this user can make
    it. Checked before any work, so a command never fails at the end for its output's sake."""
    if not str(out).strip():
        raise RunDirError(f"{flag}: empty; expected the path of a folder (or leave the flag out for the default)")
    out = Path(out)
    folder = _where_made(out, flag)
    if out.exists() and not out.is_dir():
        raise RunDirError(f"{flag} {out}: is a file; expected a new or empty directory (nothing was written)")
    if out.exists() and any(out.iterdir()):
        raise RunDirError(f"{flag} {out}: already exists and is not empty; expected a new or empty directory "
                          f"(nothing was written)")
    _can_write(folder, out, flag)


def check_out_file(path: Path, flag: str) -> None:
    """``path`` can take a new file: a legal name, nothing there yet, in a folder that exists and can be written."""
    if not str(path).strip():
        raise RunDirError(f"{flag}: empty; expected the path of a new file")
    path = Path(path)
    folder = _where_made(path, flag)
    if path.exists() or path.is_symlink():
        raise RunDirError(f"{flag} {path}: already exists; expected a new file (nothing was written)")
    if folder != path.absolute().parent:
        raise RunDirError(f"{flag} {path}: the folder {path.parent} does not exist; expected a file in an existing "
                          "folder")
    _can_write(folder, path, flag)


def write_file(path: Path, text: str) -> None:
    """``text`` into the new file ``path`` whole or not at all (written beside it, then moved into place)."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.{_TAG}-{_host()}-{os.getpid()}-", dir=path.absolute().parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


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


def final_path(path: str) -> str:
    """``path`` with a temporary directory of ``write_directory`` named as the directory it becomes: what a user
    asked for, in messages."""
    return re.sub(rf"(^|/)\.([^/]+)\.{_TAG}-[^/]+", r"\1\2", path)


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


def write_directory(out: Path, write, flag: str = "--out"):
    """Call ``write(tmp)`` to fill a fresh temporary directory beside ``out`` and move it into place only when
    complete: a failure leaves nothing half-written, and an existing non-empty ``out`` is never touched.
    Returns what ``write`` returns. ``flag`` names ``out`` in errors."""
    out = Path(out)
    check_out_dir(out, flag)
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
