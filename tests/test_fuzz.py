"""Property-based fuzzing of crowdsim's promise (issue 28, point 9): for any input, ``crowdsim ...`` exits 0 with
sane output, or prints one ``crowdsim: error:`` line, exits 2 and leaves nothing behind; never a traceback, never a
change to the user's files (fuzz_cases.promise.check, the one check every property asserts).

The properties mutate, as the outside fuzzer (issue 28) did:

(a) the bundled scenarios (scenarios/bundled/*.yaml, read with ``scenarios.loader.read_raw``, base resolved): a
    random key path's value replaced (wrong type, negative, zero, huge, NaN and infinity as numbers and as strings,
    empty list or mapping...), the key deleted, an unknown key added, a list's item doubled; written as YAML (the
    whole scenario, or as ``base: NAME`` and the top-level keys changed) and checked with ``validate-scenario``;
    a few of those that validate also run for 0.2 s;
(b) PedSim XML files (tests/data/pedsim, BSD, its LICENSE beside them): attribute values, attributes and elements
    dropped or doubled, bytes cut or spoiled; ``validate-scenario`` on each;
(c) the CSVs of ``crowdsim evaluate``: cells of a small valid ground-truth and tracks pair set to NaN, inf, text,
    huge integers, empty; columns dropped, a BOM, non-UTF-8 bytes, NUL, CRLF, cut lines, doubled rows; besides the
    promise, NaN or infinite positions, ids beyond 2^53 and a ground truth without its visible column (occlusion on)
    must be refused;
(d) command lines of run, navigate, evaluate, validate-scenario, report and evaluate-nav with bad numbers and paths
    (values argparse can parse: the app's own checks); a value the issue says is wrong must be refused. Values
    argparse itself refuses are a fixed list, test_argparse_refusals_are_one_error_line.

Everything runs in-process (``crowdsim.cli.main``), each example in a fresh folder, with hypothesis' seed fixed
(``derandomize``, no example database, and without the constants hypothesis collects from the modules imported so
far, which would make the examples depend on what ran before): every run tries the same examples, alone or in the
whole suite. A few dozen examples each in CI (the file takes about 20 s on the 2-core machine); every test here
carries the ``fuzz`` marker.

    pytest tests/test_fuzz.py                                    # CI: a few dozen examples per property
    pytest -m fuzz                                               # only the fuzz tests
    pytest -m "not fuzz"                                         # everything else
    CROWDSIM_FUZZ_EXAMPLES=2000 pytest -m fuzz                   # long: 2000 examples per property (of the runs
                                                                 #   in (a) a twentieth: 100), about 6 minutes
    CROWDSIM_FUZZ_EXAMPLES=2000 CROWDSIM_FUZZ_SEED=7 pytest -m fuzz   # another seed than the fixed one

A failure prints hypothesis' falsifying example (the mutations, the file written and the command) and the
command's outcome (exit status, stderr, the traceback that escaped main()); ``--hypothesis-show-statistics`` shows
how many examples were refused and how many succeeded.
"""

from __future__ import annotations

import copy
import math
import os
import re
import shutil
import tempfile
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, Phase, assume, event, given, seed, settings
from hypothesis import strategies as st

from fuzz_cases.promise import REPRO, RUN_FILES, check, output_problems

pytestmark = pytest.mark.fuzz

ROOT = Path(__file__).resolve().parent.parent
BUNDLED = sorted(p.stem for p in (ROOT / "scenarios" / "bundled").glob("*.yaml"))
PEDSIM = Path(__file__).resolve().parent / "data" / "pedsim"
PEDSIM_FILES = ["corridor.xml", "singleagent.xml", "scene1.xml", "contexts/queueing.xml"]

LONG = int(os.environ.get("CROWDSIM_FUZZ_EXAMPLES", "0") or 0)
SEED = os.environ.get("CROWDSIM_FUZZ_SEED")


def fuzz(ci: int, share: float = 1.0, shrink: bool = True):
    """Hypothesis settings for a property: ``ci`` examples, or CROWDSIM_FUZZ_EXAMPLES times ``share`` when set; a
    fixed seed (CROWDSIM_FUZZ_SEED, or derandomized); no deadline; no shrinking where each example runs a
    simulation (a failing one is printed as found)."""
    phases = [Phase.explicit, Phase.generate] + ([Phase.shrink] if shrink else [])
    s = settings(max_examples=max(ci, int(LONG * share)) if LONG else ci, deadline=None, database=None,
                 derandomize=SEED is None, phases=phases, print_blob=False,
                 suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                        HealthCheck.filter_too_much, HealthCheck.large_base_example,
                                        HealthCheck.function_scoped_fixture])

    def wrap(f):
        f = s(f)
        return seed(int(SEED))(f) if SEED is not None else f
    return wrap


@pytest.fixture(autouse=True)
def same_examples_whatever_ran_before(monkeypatch):
    """Hypothesis (6.1xx) also draws constants it finds in the project's modules imported so far, so a fixed seed
    would give other examples in the whole suite than in this file alone (or after a test that imported one more
    module); without them every run tries the same examples. Private API: left alone where it is not there."""
    try:
        from hypothesis.internal.conjecture import providers
        from hypothesis.internal.constants_ast import Constants
    except ImportError:  # pragma: no cover - another hypothesis
        return
    if not (hasattr(providers, "_get_local_constants") and hasattr(providers, "CONSTANTS_CACHE")):
        return  # pragma: no cover
    empty = Constants()
    monkeypatch.setattr(providers, "_get_local_constants", lambda: empty)
    providers.CONSTANTS_CACHE.cache.clear()
    yield
    providers.CONSTANTS_CACHE.cache.clear()


class Folder:
    """A fresh folder for one example (hypothesis runs many examples in one test: no tmp_path each)."""

    def __enter__(self) -> Path:
        self.path = Path(tempfile.mkdtemp(prefix="crowdsim-fuzz-"))
        return self.path

    def __exit__(self, *exc):
        shutil.rmtree(self.path, ignore_errors=True)


# -- writing YAML as a user would (NaN and infinity as YAML's .nan and .inf) -----------------------------------------

class Dumper(yaml.SafeDumper):
    pass


def _float(dumper, value):
    if math.isnan(value):
        text = ".nan"
    elif math.isinf(value):
        text = ".inf" if value > 0 else "-.inf"
    else:
        text = repr(value)
    return dumper.represent_scalar("tag:yaml.org,2002:float", text)


Dumper.add_representer(float, _float)


def dump(data) -> str:
    return yaml.dump(data, Dumper=Dumper, sort_keys=False, allow_unicode=True, width=200)


def plain(x):
    """Plain dicts and lists (the loader's tagged mappings are dict subclasses)."""
    if isinstance(x, dict):
        return {k: plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [plain(v) for v in x]
    return x


_RAW: dict[str, dict] = {}


def raw(name: str) -> dict:
    from scenarios.loader import read_raw, resolve

    if name not in _RAW:
        _RAW[name] = plain(read_raw(resolve(name)))
    return copy.deepcopy(_RAW[name])


def node_paths(d, path=()) -> list[tuple]:
    """Every key path in ``d`` (to mappings, lists and plain values alike)."""
    out = [path] if path else []
    if isinstance(d, dict):
        for k, v in d.items():
            out += node_paths(v, path + (k,))
    elif isinstance(d, list):
        for i, v in enumerate(d):
            out += node_paths(v, path + (i,))
    return out


def get(d, path):
    for k in path:
        d = d[k]
    return d


# -- (a) scenario files ------------------------------------------------------------------------------------------

WILD = [None, -1, 0, 1, -0.5, 0.5, 1e-300, 1e9, 1e308, -1e308, 10 ** 20, 2 ** 63, 2 ** 64, 10 ** 400,
        float("nan"), float("inf"), -float("inf"), "", "x", "nan", "NaN", ".nan", "inf", "1e999", "日本語", 'a"b',
        "../x", True, False, [], {}, [1], [[]], [0, 0], [0, 0, 0], [float("nan"), 0], {"zz": 1}]
TAME = [None, -1, 0, 1, -0.5, 0.5, 2, float("nan"), float("inf"), "", "x", "nan", True, [], {}, [0, 0], [0, 0, 0]]
KEEP_FOR_RUNS = {"name", "description", "warmup", "duration", "dt", "seed"}


def mutate(draw, data: dict, pool: list, skip: set, huge: bool) -> list[str]:
    """Apply 1-3 random mutations to ``data`` in place; what was done, as text."""
    done = []
    for _ in range(draw(st.integers(1, 3))):
        paths = [p for p in node_paths(data) if p[0] not in skip]
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        parent, key, cur = get(data, path[:-1]), path[-1], get(data, path)
        op = draw(st.sampled_from(["set", "set", "set", "number", "delete", "unknown", "empty", "double", "wrap"]))
        where = ".".join(map(str, path))
        if op == "number" and isinstance(cur, (int, float)) and not isinstance(cur, bool):
            factors = [-1, 0, 1e6, 1e-6, 10] if huge else [-1, 0, 0.1, 3]
            value = cur * draw(st.sampled_from(factors)) if draw(st.booleans()) else -abs(cur) - 1
            parent[key] = value
            done.append(f"{where} = {value!r}")
        elif op == "delete":
            del parent[key]
            done.append(f"del {where}")
        elif op == "unknown" and isinstance(cur, dict):
            cur["zz_unknown_key"] = 1
            done.append(f"{where}.zz_unknown_key = 1")
        elif op == "empty" and isinstance(cur, (dict, list)):
            parent[key] = type(cur)()
            done.append(f"{where} = {type(cur)()!r}")
        elif op == "double" and isinstance(cur, list) and cur:
            cur.append(copy.deepcopy(cur[draw(st.integers(0, len(cur) - 1))]))
            done.append(f"{where} += a copy of one item")
        elif op == "wrap":
            parent[key] = [cur] if draw(st.booleans()) else {"value": cur}
            done.append(f"{where} wrapped")
        else:
            value = draw(st.sampled_from(pool))
            parent[key] = copy.deepcopy(value)
            done.append(f"{where} = {value!r}")
    return done


@st.composite
def scenario_files(draw, pool=WILD, skip=frozenset(), huge=True):
    """(file name, YAML text, what was done) of a mutated bundled scenario."""
    name = draw(st.sampled_from(BUNDLED))
    data = raw(name)
    if skip:  # runs: no warm-up (the airport's is 60 s)
        data["warmup"] = 0.0
    done = mutate(draw, data, pool, set(skip), huge)
    if draw(st.booleans()) and not any(d.startswith("del ") for d in done):
        # as a user writes it: the bundled scenario as the base, the top-level keys that changed given whole
        original = raw(name)
        changed = {k: v for k, v in data.items() if original.get(k) != v}
        text = dump({"base": name, **changed})
    else:
        text = dump(data)
    return name, text, done


@fuzz(ci=100)
@given(case=scenario_files())
def test_a_mutated_scenario_is_validated_or_refused_in_one_line(case):
    name, text, done = case
    with Folder() as cwd:
        path = cwd / f"{name}_mutated.yaml"
        path.write_text(text, encoding="utf-8")
        o = check(["validate-scenario", path.name], cwd, precious=[path], limit=60)
        event(f"exit {o.rc}")  # shown by pytest --hypothesis-show-statistics
        if o.rc == 0:
            assert "valid scenario" in o.out, o.report()


@fuzz(ci=3, share=0.05, shrink=False)
@given(case=scenario_files(pool=TAME, skip=frozenset(KEEP_FOR_RUNS), huge=False))
def test_a_mutated_scenario_that_validates_runs_with_sane_output(case):
    name, text, done = case
    with Folder() as cwd:
        path = cwd / f"{name}_mutated.yaml"
        path.write_text(text, encoding="utf-8")
        o = check(["validate-scenario", path.name], cwd, precious=[path], limit=60)
        event(f"validate-scenario: exit {o.rc}")
        assume(o.rc == 0)  # the examples counted are those that validate, and run
        o = check(["run", path.name, "--duration", "0.2", "--quiet", "--out", "out"], cwd, precious=[path],
                  outputs=["out"], need=RUN_FILES, limit=120)
        event(f"run: exit {o.rc}")


# -- (b) PedSim XML ----------------------------------------------------------------------------------------------

XML_VALUES = ["", "-1", "0", "-0", "1e308", "-1e308", "nan", "inf", "-inf", "x", "99999999", "1e-300", "1e8", "1e20",
              "2.5", "ü日", "&quot;", "&amp;", "&lt;", "0x10", " 3 ", "1" * 400]


@st.composite
def pedsim_files(draw):
    name = draw(st.sampled_from(PEDSIM_FILES))
    text = (PEDSIM / name).read_bytes().decode("utf-8")
    done = []
    for _ in range(draw(st.integers(1, 3))):
        op = draw(st.sampled_from(["value", "value", "value", "drop_attr", "drop_line", "double_line", "unknown",
                                   "cut", "byte"]))
        attrs = list(re.finditer(r'(\w+)="([^"]*)"', text))
        lines = text.split("\n")
        if op == "value" and attrs:
            m = draw(st.sampled_from(attrs))
            v = draw(st.sampled_from(XML_VALUES))
            text = text[:m.start(2)] + v + text[m.end(2):]
            done.append(f"{m.group(1)}={v!r} at {m.start()}")
        elif op == "drop_attr" and attrs:
            m = draw(st.sampled_from(attrs))
            text = text[:m.start()] + text[m.end():]
            done.append(f"dropped {m.group(0)}")
        elif op in ("drop_line", "double_line") and len(lines) > 2:
            k = draw(st.integers(1, len(lines) - 2))
            lines[k:k + 1] = [] if op == "drop_line" else [lines[k], lines[k]]
            text = "\n".join(lines)
            done.append(f"{op} {k + 1}")
        elif op == "unknown":
            text = text.replace("</scenario>", '<teleporter x="1" y="nan"/></scenario>', 1)
            done.append("unknown element")
        elif op == "cut":
            k = draw(st.integers(0, len(text)))
            text = text[:k]
            done.append(f"cut at {k}")
        elif op == "byte" and text:
            k = draw(st.integers(0, len(text) - 1))
            text = text[:k] + draw(st.sampled_from(["\udcff", "\x00", "\udce9"])) + text[k + 1:]
            done.append(f"byte at {k}")
    return name, text.encode("utf-8", "surrogateescape"), done


@fuzz(ci=60)
@given(case=pedsim_files())
def test_a_mutated_pedsim_file_is_validated_or_refused_in_one_line(case):
    name, data, done = case
    with Folder() as cwd:
        path = cwd / Path(name).name
        path.write_bytes(data)
        o = check(["validate-scenario", path.name], cwd, precious=[path], limit=60)
        event(f"exit {o.rc}")  # shown by pytest --hypothesis-show-statistics
        if o.rc == 0:
            assert "valid scenario" in o.out, o.report()


# -- (c) evaluate's CSVs --------------------------------------------------------------------------------------------

GT_TEXT = (REPRO / "gt.csv").read_text()
TRACKS_TEXT = (REPRO / "tracks.csv").read_text()
CELLS = ["nan", "NaN", "inf", "-inf", "Infinity", "1e400", "", "abc", "100000000000000000000", "9007199254740993",
         "-1", "0", "1.5", " 2", "0x10", "1_000", "1e308", "-0", '"1"', "caf\udce9"]


def mutate_csv(draw, text: str) -> tuple[str, str]:
    op = draw(st.sampled_from(["cell", "cell", "cell", "drop_column", "bom", "bytes", "crlf", "cut", "double_row",
                               "shuffle", "empty", "header_only", "no_header", "nul", "semicolon"]))
    lines = text.rstrip("\n").split("\n")
    header = lines[0].split(",")
    if op == "cell" and len(lines) > 1:
        r = draw(st.integers(1, len(lines) - 1))
        row = lines[r].split(",")
        c = draw(st.integers(0, len(row) - 1))
        row[c] = draw(st.sampled_from(CELLS))
        lines[r] = ",".join(row)
        return "\n".join(lines) + "\n", f"line {r + 1}, field {c + 1} = {row[c]!r}"
    if op == "drop_column":
        c = draw(st.integers(0, len(header) - 1))
        return "\n".join(",".join(x for j, x in enumerate(line.split(",")) if j != c) for line in lines) + "\n", \
            f"dropped column {header[c]}"
    if op == "bom":
        return "\ufeff" + text, "BOM"
    if op == "bytes" and text:
        k = draw(st.integers(0, len(text) - 1))
        return text[:k] + "\udce9" + text[k:], f"byte 0xe9 at {k}"
    if op == "crlf":
        return text.replace("\n", "\r\n"), "CRLF"
    if op == "cut":
        k = draw(st.integers(0, len(text)))
        return text[:k], f"cut at {k}"
    if op == "double_row" and len(lines) > 1:
        r = draw(st.integers(1, len(lines) - 1))
        return "\n".join(lines[:r + 1] + lines[r:]) + "\n", f"line {r + 1} twice"
    if op == "shuffle" and len(lines) > 2:
        rows = draw(st.permutations(lines[1:]))
        return "\n".join([lines[0], *rows]) + "\n", "rows shuffled"
    if op == "empty":
        return "", "empty file"
    if op == "header_only":
        return lines[0] + "\n", "header only"
    if op == "no_header":
        return "\n".join(lines[1:]) + "\n", "no header"
    if op == "nul" and text:
        k = draw(st.integers(0, len(text) - 1))
        return text[:k] + "\x00" + text[k:], f"NUL at {k}"
    if op == "semicolon":
        return text.replace(",", ";"), "semicolons"
    return text, "unchanged"


def columns(text: str) -> dict[str, list[str]] | None:
    """The columns of a CSV as a reader that takes UTF-8 (a BOM too) would see them; None if it is not UTF-8."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:  # a lone surrogate: the byte that is not UTF-8
        return None
    lines = [line.rstrip("\r") for line in text.lstrip("\ufeff").split("\n") if line.strip()]
    if not lines:
        return {}
    header = lines[0].split(",")
    cols = {h: [] for h in header}
    for line in lines[1:]:
        for h, cell in zip(header, line.split(",")):
            cols[h].append(cell)
    return cols


def must_refuse(gt: str, tracks: str, occlusion: bool) -> str:
    """Why evaluate must refuse this pair (issue 28, point 4), or ''."""
    for what, text in (("gt", gt), ("tracks", tracks)):
        cols = columns(text)
        if cols is None:
            return f"{what}: not UTF-8"
        for col in ("x", "y"):
            for cell in cols.get(col, []):
                try:
                    value = float(cell)
                except ValueError:
                    continue
                if not math.isfinite(value):
                    return f"{what}: {col} = {cell!r}"
        for col in ("id", "frame"):
            for cell in cols.get(col, []):
                if re.fullmatch(r"\s*-?\d+\s*", cell) and abs(int(cell)) >= 2 ** 53:
                    return f"{what}: {col} = {cell!r}, beyond 2^53"
    gt_cols = columns(gt)
    if occlusion and gt_cols and len(gt_cols) > 1 and "visible" not in gt_cols:
        return "gt: no visible column while occlusion is on"
    return ""


@st.composite
def csv_pairs(draw):
    gt, tracks, done = GT_TEXT, TRACKS_TEXT, []
    for _ in range(draw(st.integers(1, 3))):
        if draw(st.booleans()):
            gt, what = mutate_csv(draw, gt)
            done.append(f"gt: {what}")
        else:
            tracks, what = mutate_csv(draw, tracks)
            done.append(f"tracks: {what}")
    occlusion = draw(st.booleans())
    return gt, tracks, occlusion, done


def write_text(path: Path, text: str) -> Path:
    path.write_bytes(text.encode("utf-8", "surrogateescape"))
    return path


@fuzz(ci=80)
@given(case=csv_pairs())
def test_mutated_csvs_are_scored_or_refused_in_one_line(case):
    gt, tracks, occlusion, done = case
    with Folder() as cwd:
        g, t = write_text(cwd / "gt.csv", gt), write_text(cwd / "tracks.csv", tracks)
        argv = ["evaluate", "--gt", "gt.csv", "--tracks", "tracks.csv", "--json", "m.json"]
        argv += [] if occlusion else ["--no-occlusion"]
        o = check(argv, cwd, precious=[g, t], outputs=["m.json"], limit=60)
        event(f"exit {o.rc}")
        why = must_refuse(gt, tracks, occlusion)
        if why:
            assert o.rc == 2, f"scored although {why}\n{o.report()}"


# -- (d) command lines ----------------------------------------------------------------------------------------------

SCENARIO = "base: passers_by\nwarmup: 0.0\n"
RELATIONS = "frame,t,track_a,track_b,strength\n1,0.04,7,8,0.25\n"
GROUPS = "frame,t,group,id,x,y,age\n"


def setup(cwd: Path) -> list[Path]:
    """The user's files in the folder a command runs in; all of them must stay as they are."""
    (cwd / "sc.yaml").write_text(SCENARIO)
    (cwd / "gt.csv").write_text(GT_TEXT)
    (cwd / "tracks.csv").write_text(TRACKS_TEXT)
    (cwd / "relations.csv").write_text(RELATIONS)
    (cwd / "groups.csv").write_text(GROUPS)
    (cwd / "mine.txt").write_text("precious\n")
    (cwd / "empty.yaml").write_text("")
    (cwd / "binary.bin").write_bytes(bytes(range(256)) * 4)
    (cwd / "full").mkdir()
    (cwd / "full" / "keep.txt").write_text("precious\n")
    (cwd / "emptydir").mkdir()
    return [p for p in cwd.rglob("*") if p.is_file()]


def opt(ok: list, bad: list):
    """A flag's value: (value, True when the issue says it must be refused)."""
    return st.one_of(st.sampled_from([(v, False) for v in ok]), st.sampled_from([(v, True) for v in bad]))


NEW_OUT = ["out/run", "emptydir", None]  # None: the default runs/<name>-<time>
BAD_OUT = ["", "/proc/x", "/sys/crowdsim_run", "mine.txt", "mine.txt/sub", "full", "/dev/null", "x" * 300,
           "out/" + "y" * 300, "/nonexistent-root-dir/run" if os.geteuid() != 0 else "/proc/self/x"]
NEW_FILE = ["new.json", "out.json"]
BAD_FILE = ["mine.txt", "/nonexistent/dir/x.json", "/proc/x.json", "full", "", "emptydir"]
DURATION_OK = ["0.2", "0.04", "1e-1"]
DURATION_BAD = ["0", "-5", "nan", "inf", "-0", "-inf"]


@st.composite
def command_lines(draw):
    """(argv, must be refused, the outputs a success writes)."""
    command = draw(st.sampled_from(["run", "navigate", "evaluate", "validate-scenario", "report", "evaluate-nav"]))
    bad, argv, outputs = False, [command], []

    def add(flag, strategy, optional=True):
        nonlocal bad
        if optional and draw(st.booleans()):
            return None
        value, wrong = draw(strategy)
        if value is None:
            return None
        argv.append(f"{flag}={value}" if flag else value)  # --flag=VALUE: a value such as -inf is no flag
        bad |= wrong
        return value

    if command == "run":
        add("", opt(["sc.yaml"],
                    ["missing.yaml", "emptydir", "", "/dev/null", "binary.bin", "empty.yaml", "no_such", "mine.txt"]),
            optional=False)
        add("--duration", opt(DURATION_OK, DURATION_BAD + ["1e-9"]), optional=False)
        add("--seed", opt(["0", "7", str(2 ** 32)], ["-1"]))
        out = add("--out", opt(NEW_OUT, BAD_OUT), optional=False)
        argv.append("--quiet")
        outputs = [out] if out else []  # the default runs/<name>-<time>: checked by the test
    elif command == "navigate":
        add("", opt(["sc.yaml"], ["missing.yaml", "emptydir", "", "airport_disembarkation", "empty.yaml"]),
            optional=False)
        add("--seeds", opt(["1"], ["0", "-2"]), optional=False)
        add("--duration", opt(DURATION_OK, DURATION_BAD), optional=False)
        add("--first-seed", opt(["1", "5"], ["-5"]))
        add("--workers", opt(["1"], ["0", "-1"]))
        add("--planner", opt(["zone", "nd", "straight", "social_force"], ["warp", "nomod:X", "os.path:join", ""]))
        out = add("--json", opt(NEW_FILE, BAD_FILE))
        argv.append("--quiet")
        outputs = [out] if out else []
    elif command == "evaluate":
        add("--gt", opt(["gt.csv"], ["missing.csv", "emptydir", "/dev/null", "", "binary.bin", "empty.yaml"]),
                 optional=False)
        add("--tracks", opt(["tracks.csv"], ["missing.csv", "emptydir", "", "binary.bin"]), optional=False)
        add("--threshold", opt(["1", "0.3", "inf"], ["nan", "-1", "0", "-0"]))
        add("--max-range", opt(["12", "inf"], ["-1", "nan", "0", "-0"]))
        occlusion = draw(st.booleans())
        # a visibility column that is not there, or none named, matters while occlusion is on
        add("--visible-column", opt(["visible", "visible_seed000"], ["seen", ""]) if occlusion else
            st.sampled_from([(v, False) for v in ("visible", "visible_seed000", "seen")]))
        if not occlusion:
            argv.append("--no-occlusion")
        if draw(st.booleans()):
            add("--relations", opt(["relations.csv"], ["missing.csv", "tracks.csv"]), optional=False)
            add("--groups", opt(["groups.csv"], ["missing.csv", "emptydir"]), optional=False)
        out = add("--json", opt(NEW_FILE, BAD_FILE))
        add("--motchallenge", opt(["mot", "emptydir"], ["", "mine.txt", "full", "/proc/mot", "gt.csv"]))
        outputs = [out] if out else []
    elif command == "validate-scenario":
        add("", opt(["sc.yaml", "passers_by"],
                    ["missing.yaml", "emptydir", "", "/dev/null", "binary.bin", "empty.yaml", "no_such", "mine.txt"]),
            optional=False)
        if draw(st.booleans()):
            argv.append("--allow-large")
    else:  # report, evaluate-nav: folders that are no run
        add("", st.sampled_from([(v, True) for v in ("missing", "emptydir", "full", "mine.txt", "", "/proc")]),
            optional=False)
    return argv, bad, outputs


@fuzz(ci=80)
@given(case=command_lines())
def test_a_command_line_is_done_or_refused_in_one_line(case):
    argv, bad, outputs = case
    with Folder() as cwd:
        precious = setup(cwd)
        o = check(argv, cwd, precious=precious, outputs=outputs, limit=60)
        event(f"{argv[0]}: exit {o.rc}")
        if bad:
            assert o.rc == 2, f"done although a value is wrong\n{o.report()}"
        if o.rc == 0 and argv[0] == "run" and not any(a.startswith("--out=") for a in argv):
            made = list((cwd / "runs").iterdir())
            assert len(made) == 1, o.report()
            assert not output_problems(made[0], RUN_FILES), (output_problems(made[0], RUN_FILES), o.report())


# values argparse itself refuses (no int, no float, unknown flag or command, a flag without its value)
ARGPARSE = [
    ["run", "passers_by", "--seed", "one"],
    ["run", "passers_by", "--duration", "ten"],
    ["run", "passers_by", "--duration", "-inf"],  # argparse takes -inf for a flag (--duration=-inf is a value)
    ["run", "passers_by", "--bogus"],
    ["run"],
    ["navigate", "passers_by", "--seeds", "x"],
    ["navigate", "passers_by"],
    ["evaluate", "--gt", "gt.csv", "--tracks", "tracks.csv", "--threshold", "abc"],
    ["evaluate", "--gt"],
    ["frobnicate"],
    [],
]


@pytest.mark.parametrize("argv", ARGPARSE, ids=lambda a: " ".join(a) or "<none>")
def test_argparse_refusals_are_one_error_line(tmp_path, argv):
    precious = setup(tmp_path)
    o = check(argv, tmp_path, precious=precious)
    assert o.rc == 2, o.report()
