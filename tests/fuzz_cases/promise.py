"""The bad-input promise of ``crowdsim`` as one check, shared by tests/test_reproducers.py and tests/test_fuzz.py.

For any input, ``crowdsim ARGS`` either

- exits 0 with sane output: the files a command writes are all there, and no CSV or JSON it wrote holds NaN or
  infinity (JSON's ``NaN``/``Infinity`` are not JSON at all), or
- prints exactly one ``crowdsim: error: ...`` line on stderr (``crowdsim: warning: ...`` lines allowed besides),
  exits 2, and leaves nothing behind: no new file or folder in the folder it ran in or the output's folder, no
  hidden ``.*crowdsim-partial*`` folder;

and it never prints a Python traceback, never changes a file the user had.

``main(ARGS)`` runs in this process (a subprocess costs some 1.5 s of imports): its exit status is what it returns
(or argparse's ``SystemExit``), an exception that escapes it is the traceback a user would see, and a command still
running after ``limit`` seconds is stopped by SIGALRM and reported as a hang. Not a test module (no conftest): the
tests import it as ``fuzz_cases.promise``.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import os
import signal
import traceback
from dataclasses import dataclass, field
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPRO = HERE / "repro"  # the reproducers, as its repro script writes them
FOUND = HERE / "found"  # what tests/test_fuzz.py found while it was written
PARTIAL = "crowdsim-partial"
RUN_FILES = ("metrics.json", "groundtruth.csv", "tracks.csv", "robot.csv", "scenario.yaml", "summary.md",
             "topdown.png")


class Hang(BaseException):
    """Raised by SIGALRM in a command that ran past its time limit (a BaseException: nothing in crowdsim takes it
    for its own error)."""


@dataclass
class Outcome:
    argv: list[str]
    rc: int | None
    out: str
    err: str
    escaped: str = ""  # the traceback of an exception that escaped main(), or why the command was stopped
    problems: list[str] = field(default_factory=list)

    @property
    def error(self) -> str:
        """The one ``crowdsim: error:`` line (the promise checked first)."""
        lines = error_lines(self.err)
        return lines[0] if len(lines) == 1 else ""

    def report(self) -> str:
        tail = lambda s: "\n".join(s.strip().splitlines()[-8:])  # noqa: E731
        return (f"crowdsim {' '.join(map(repr, self.argv))}\n  rc={self.rc}\n  problems: {self.problems}\n"
                f"  stderr:\n{tail(self.err)}\n  stdout (end):\n{tail(self.out)}"
                + (f"\n  escaped main():\n{tail(self.escaped)}" if self.escaped else ""))


def error_lines(stderr: str) -> list[str]:
    """stderr's lines that are neither blank nor ``crowdsim: warning:`` lines."""
    return [line for line in stderr.replace("\r", "\n").splitlines()
            if line.strip() and not line.startswith("crowdsim: warning:")]


@contextlib.contextmanager
def time_limit(seconds: float):
    """SIGALRM raises Hang after ``seconds`` (in the main thread, between Python bytecodes)."""
    def on_alarm(signum, frame):
        raise Hang(f"still running after {seconds:g} s")

    before = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, before)


@contextlib.contextmanager
def in_dir(path: Path):
    old = os.getcwd()
    os.chdir(path)
    try:
        yield
    finally:
        os.chdir(old)


def invoke(argv: list[str], cwd: Path, limit: float = 120.0) -> Outcome:
    """``crowdsim ARGV`` run in-process from ``cwd``, its stdout and stderr captured."""
    from crowdsim.cli import main

    out, err = io.StringIO(), io.StringIO()
    rc, escaped = None, ""
    with in_dir(cwd), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            with time_limit(limit):
                rc = main([str(a) for a in argv])
        except SystemExit as e:  # argparse
            rc = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
        except Hang as e:
            escaped = f"hang: {e}"
        except BaseException:  # noqa: BLE001 - what a user would see as a traceback
            escaped = traceback.format_exc()
    return Outcome([str(a) for a in argv], rc, out.getvalue(), err.getvalue(), escaped)


def snapshot(folders) -> set[str]:
    """Every path under ``folders`` (recursive), as strings."""
    seen = set()
    for folder in folders:
        folder = Path(folder)
        if folder.is_dir():
            for root, dirs, files in os.walk(folder):
                seen.update(os.path.join(root, n) for n in dirs + files)
    return seen


def contents(files) -> dict[str, bytes | None]:
    return {str(p): (Path(p).read_bytes() if Path(p).is_file() else None) for p in files}


def strict_json(text: str):
    """json.loads refusing NaN, Infinity and -Infinity (which Python writes but JSON does not have)."""
    def refuse(token):
        raise ValueError(f"{token} is not JSON")
    return json.loads(text, parse_constant=refuse)


def csv_problems(path: Path) -> list[str]:
    """Cells of a CSV a command wrote that read as NaN or infinity."""
    bad = []
    with open(path, encoding="utf-8") as f:
        header = f.readline().rstrip("\n").split(",")
        for n, line in enumerate(f, start=2):
            for col, cell in zip(header, line.rstrip("\n").split(",")):
                try:
                    value = float(cell)
                except ValueError:
                    continue
                if not math.isfinite(value):
                    bad.append(f"{path.name} line {n}, column {col}: {cell}")
                    if len(bad) >= 3:
                        return bad
    return bad


def output_problems(folder: Path, need=()) -> list[str]:
    """What is wrong with what a successful command wrote under ``folder``: a file of ``need`` missing, a JSON file
    that is not strict JSON or a CSV cell that is NaN or infinite."""
    problems = [f"missing {name}" for name in need if not (folder / name).is_file()]
    for path in sorted(folder.rglob("*.json")):
        try:
            strict_json(path.read_text(encoding="utf-8"))
        except ValueError as e:
            problems.append(f"{path.name}: {e}")
    for path in sorted(folder.rglob("*.csv")):
        problems += csv_problems(path)
    return problems


def check(argv, cwd: Path, *, watch=(), precious=(), outputs=(), need=RUN_FILES, limit: float = 120.0) -> Outcome:
    """Run ``crowdsim ARGV`` in ``cwd`` and assert the promise; return the outcome for the caller's own checks.

    ``watch``: folders (besides ``cwd``) where a failure must leave nothing new; ``precious``: files that must not
    change; ``outputs``: what a success writes (a folder: ``need`` in it and no NaN/inf in its CSVs and JSON; a
    file: strict JSON), checked when they exist after a zero exit."""
    cwd = Path(cwd)
    folders = [cwd, *map(Path, watch)]
    before, kept = snapshot(folders), contents(precious)
    o = invoke(list(argv), cwd, limit)
    after = snapshot(folders)
    p = o.problems
    if o.escaped:
        p.append("an exception escaped main() (a traceback)" if not o.escaped.startswith("hang") else o.escaped)
    if "Traceback (most recent call last)" in o.err + o.out:
        p.append("a traceback printed")
    if o.rc not in (0, 2) and not o.escaped:
        p.append(f"exit status {o.rc}; expected 0 or 2")
    lines = error_lines(o.err)
    if o.rc == 2:
        if not (len(lines) == 1 and lines[0].startswith("crowdsim: error: ")):
            p.append(f"expected one 'crowdsim: error:' line on stderr, got {len(lines)} line(s)")
    if o.rc == 0 and any(line.startswith("crowdsim: error:") for line in lines):
        p.append("exit 0 with an error line")
    if o.rc != 0:
        new = sorted(after - before)
        if new:
            p.append(f"a failure left {new[:5]}")
    partial = sorted(x for x in after if PARTIAL in os.path.basename(x))
    if partial:
        p.append(f"hidden partial output left: {partial[:3]}")
    changed = [f for f, data in contents(precious).items() if data != kept[f]]
    if changed:
        p.append(f"the user's files changed: {changed}")
    if o.rc == 0:
        for target in map(Path, outputs):
            target = target if target.is_absolute() else cwd / target
            if not target.exists():
                p.append(f"exit 0, but {target} was not written")
            elif target.is_dir():
                p += output_problems(target, need)
            elif target.is_file() and target.suffix == ".json":
                try:
                    strict_json(target.read_text(encoding="utf-8"))
                except ValueError as e:
                    p.append(f"{target.name}: {e}")
    assert not p, o.report()
    return o


def refused(o: Outcome, *words: str) -> str:
    """Assert that the command was refused with one error line holding each of ``words``; return the line."""
    assert o.rc == 2, f"expected a refusal (exit 2)\n{o.report()}"
    for w in words:
        assert w in o.error, f"the error does not name {w!r}\n{o.report()}"
    return o.error


def succeeded(o: Outcome) -> Outcome:
    assert o.rc == 0, f"expected success (exit 0)\n{o.report()}"
    return o
