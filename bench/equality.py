"""The same user commands run in two trees, their outputs compared field for field: the evidence that
a refactor kept behaviour (records, fits, exports equal to the tree before, except wall times).

    python bench/equality.py OLD NEW [--out DIR] [--deps DIR] [--cases eval,export,sysid,...] [--no-run]

OLD and NEW are commits (checked out as temporary `git worktree`s under /tmp, removed afterwards) or
paths of trees. Each tree runs with this interpreter and PYTHONPATH=<tree>, in its own directory
under OUT with the same relative paths, so path fields agree by construction. The commands:

- eval: `realm eval --policy expert`, 2 tasks x (Default, B-HOBJ) x 2 seeds, 120 steps,
  `--workers 1` and `--workers 2` (records.jsonl keyed by (task, perturbation, seed); metrics.json;
  run.json); each tree's workers 1 against its own workers 2 is reported too;
- export: `realm export` of 2 tasks x 2 seeds at 160x96 (parquet tables column by column, videos by
  hash, else by decoded frames; info/stats/sidecar/card);
- sysid, torque: `realm sysid synth` (position: hidden Coulomb friction, PhysX; torque: MuJoCo-native
  frictionloss, a torque log), then `compare`, `diagnose`, `fit --add coulomb_friction` in both trees
  on OLD's synthetic data (so a difference in synth does not hide what the verbs do); JSON outputs,
  the fitted MODEL.yaml and the terminal summaries. Sysid runs `--workers 1`: before d672c75 a
  replay's batches went to whichever worker was free, so `--workers 2` did not repeat bit for bit;
- auto: `realm sysid auto --generations 3 --max-steps 2` (auto has no --candidates) on the position
  data above and on the torque log (MuJoCo-native frictionloss): JSON, MODEL.yaml, printed lines;
- report: `realm sysid report` on the position data (self-contained HTML, plots as embedded PNGs;
  it carries no date, so nothing of it is ignored);
- droid: DROID-format episodes (`synth --engine mujoco --droid-space cartesian_position`, hidden
  latency 60 ms, written under npz/), then `compare` and `fit --add latency`, both `--command
  rebuild`, and `align` (its HTML and JSON);
- batched: `realm eval --policy expert` (as eval) `--backend batched --workers 2` against
  `--workers 1`, in each tree and across trees. CPU physics only (this machine has no GPU, and no
  Ray here): 2 groups of one sub-env stepped in turn in-process; the GPU batch of N sub-envs and the
  Ray backend are not exercised.

A tree whose `realm` refuses a case's command line (argparse: a verb or option it lacks) is named in
one note, and that case's later steps are not run there (its outputs show as "only in NEW").

Comparison is exact (floats included); IGNORED lists the only keys left out. A differing output shows
its first differing field with both values, how many fields were added, removed or changed, and the
largest |difference|; OUT/equality.json lists the first 20 differing fields of each file.
stdlib + numpy; pyarrow, PyAV and PyYAML (the venv's) read the formats the commands write.
"""

from __future__ import annotations

import argparse
import difflib
import hashlib
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]

# the only keys not compared, wherever they appear
IGNORED = {
    "wall_s": "an episode's wall time (eval records)",
    "code_version": "'realm-ms 0.1.0 (<commit>)': names the tree's commit (eval records)",
    "created": "the fit's date (MODEL.yaml provenance)",
    "seconds": "an alignment's wall time (align JSON; the flange runs in compare/fit/auto JSON write 0.0)",
}

TASKS = ["REALM-PickApple-v1", "REALM-PushSwitch-v1"]
EVAL = ["eval", "--policy", "expert", "--tasks", *TASKS, "--perturbations", "Default", "B-HOBJ",
        "--episodes", "2", "--seed", "1234", "--max-steps", "120", "--no-progress"]
EXPORT = ["export", "--tasks", *TASKS, "--episodes", "2", "--seed", "1234", "--max-steps", "120",
          "--width", "160", "--height", "96", "--out", "ds"]  # no --no-progress: 84c19c6's export lacks it


def synth(out: str = "syn") -> list[str]:
    return ["sysid", "synth", "--n-train", "2", "--n-heldout", "1", "--duration", "4", "--out", out]


SYNTH = synth()
POSITION = ["--hidden", "coulomb_friction:fc=0.3"]
TORQUE = ["--engine", "mujoco-native", "--hidden", "frictionloss", "--torque-only"]
VERBS = [
    ("compare", ["sysid", "compare", "data", "--workers", "1", "--json", "compare.json"]),
    ("diagnose", ["sysid", "diagnose", "data", "--workers", "1", "--json", "diagnose.json"]),
    ("fit", ["sysid", "fit", "data", "--add", "coulomb_friction", "--generations", "3", "--workers", "1",
             "--no-progress", "--out", "fit.yaml", "--json", "fit.json"]),
]
# torque space's diagnose fits every candidate fully: the whole library is minutes of CPU, these are seconds
TORQUE_CANDIDATES = "coulomb_friction,viscous_damping,stribeck_friction,smooth_friction,armature,payload"

# case -> steps (name, realm arguments); "data" = a copy of OLD's synth output, in both trees
CASES = {
    "eval": [("eval w1", EVAL + ["--workers", "1", "--out", "run_w1"]),
             ("eval w2", EVAL + ["--workers", "2", "--out", "run_w2"])],
    "export": [("export", EXPORT)],
    "sysid": [("synth", SYNTH + POSITION)] + VERBS,
    "torque": [("synth", SYNTH + TORQUE)]
    + [(n, a + ["--candidates", TORQUE_CANDIDATES] if n == "diagnose" else a) for n, a in VERBS],
    # auto has no --candidates: --max-steps 2 and 3 generations bound it
    "auto": [("synth", SYNTH + POSITION), ("synth torque", synth("syn_torque") + TORQUE)]
    + [(f"auto{s}", ["sysid", "auto", f"data{s}", "--generations", "3", "--max-steps", "2", "--workers", "1",
                     "--no-progress", "--out", f"auto{s}.yaml", "--json", f"auto{s}.json"]) for s in ("", "_torque")],
    "report": [("synth", SYNTH + POSITION),
               ("report", ["sysid", "report", "data", "--workers", "1", "--out", "report.html"])],
    # DROID-format episodes (15 Hz, commanded in Cartesian position through DROID's conversion) under synth's npz/
    "droid": [("synth", SYNTH + ["--engine", "mujoco", "--droid-space", "cartesian_position",
                                 "--hidden", "latency:delay=0.06"]),
              ("compare", ["sysid", "compare", "data/npz", "--command", "rebuild", "--workers", "1",
                           "--json", "compare.json"]),
              ("fit", ["sysid", "fit", "data/npz", "--add", "latency", "--command", "rebuild", "--generations", "3",
                       "--workers", "1", "--no-progress", "--out", "fit.yaml", "--json", "fit.json"]),
              ("align", ["sysid", "align", "data/npz", "--out", "align.html", "--json", "align.json"])],
    # CPU physics: the batched runner's single-sub-env groups, against the in-process run
    "batched": [("eval w1", EVAL + ["--workers", "1", "--out", "run_w1"]),
                ("eval batched", EVAL + ["--backend", "batched", "--workers", "2", "--out", "run_batched"])],
}
# each tree's runs of a case compared with each other too: case -> (run, run)
SELF = {"eval": ("run_w1", "run_w2"), "batched": ("run_w1", "run_batched")}


# --- trees ---------------------------------------------------------------------------------------

def git(*args: str, cwd: Path = REPO) -> str:
    return subprocess.run(["git", *args], cwd=cwd, check=True, capture_output=True, text=True).stdout.strip()


def open_tree(spec: str, scratch: Path) -> tuple[Path, str, bool]:
    """(tree, label, temporary): a path as it is, or a commit checked out under scratch."""
    p = Path(spec)
    if (p / "realm_ms").is_dir():
        sha = git("rev-parse", "--short=7", "HEAD", cwd=p)
        dirty = " + uncommitted changes" if git("status", "--porcelain", "--untracked-files=no", cwd=p) else ""
        return p.resolve(), f"{p} ({sha}{dirty})", False
    sha = git("rev-parse", "--verify", f"{spec}^{{commit}}")
    tree = scratch / sha[:12]
    git("worktree", "add", "--detach", str(tree), sha)
    return tree, sha[:7], True


def run_realm(tree: Path, cwd: Path, args: list[str], log: str, deps: Path | None) -> tuple[int, str, bool]:
    """Runs `realm ARGS` from tree in cwd; stdout to LOG.stdout (compared), stderr to LOG.stderr.
    (exit status, stderr's last line, whether argparse refused the command line)."""
    path = os.pathsep.join(str(p) for p in (tree, deps) if p)
    env = dict(os.environ, PYTHONPATH=path, MS_SKIP_ASSET_DOWNLOAD_PROMPT="1")
    with open(cwd / f"{log}.stdout", "w") as out, open(cwd.parent / f"{cwd.name}.{log}.stderr", "w") as err:
        rc = subprocess.run([sys.executable, "-m", "realm_ms.cli", *args], cwd=cwd, env=env,
                            stdout=out, stderr=err).returncode
    lines = (cwd.parent / f"{cwd.name}.{log}.stderr").read_text().strip().splitlines()
    last = lines[-1] if lines else ""
    return rc, last, rc == 2 and ": error: " in last and any(x.startswith("usage: ") for x in lines)


def imports_from(tree: Path) -> str:
    env = dict(os.environ, PYTHONPATH=str(tree))
    r = subprocess.run([sys.executable, "-c", "import realm_ms; print(realm_ms.__file__)"], env=env,
                       cwd=tree, capture_output=True, text=True)
    if r.returncode or not Path(r.stdout.strip()).resolve().is_relative_to(tree):
        raise SystemExit(f"{tree} does not import as realm_ms: {(r.stderr or r.stdout).strip()[-300:]}")
    return r.stdout.strip()


# --- reading outputs -----------------------------------------------------------------------------

def read(path: Path):
    """An output file as comparable data (dicts, lists, numbers, strings, arrays)."""
    ext = path.suffix
    if ext == ".json":
        return json.loads(path.read_text())
    if ext == ".jsonl":
        rows = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
        if all({"task", "perturbation", "seed"} <= set(r) for r in rows):  # eval: the episode key, not line order
            return {f"{r['task']}|{r['perturbation']}|{r['seed']}": r for r in rows}
        return rows
    if ext == ".yaml":
        import yaml
        return yaml.safe_load(path.read_text())
    if ext == ".npz":
        with np.load(path) as z:
            return {k: z[k] for k in z.files}
    if ext == ".parquet":
        import pyarrow.parquet as pq
        t = pq.read_table(path)
        cols = {name: t.column(name).to_pylist() for name in t.column_names}
        return {"schema": [f"{f.name}: {f.type}" for f in t.schema], "columns": cols}
    if ext == ".mp4":
        return {"sha256": hashlib.sha256(path.read_bytes()).hexdigest()}
    return path.read_text().splitlines()


def frames(path: Path) -> np.ndarray:
    import av
    with av.open(str(path)) as c:
        return np.stack([f.to_ndarray(format="rgb24") for f in c.decode(video=0)])


# --- comparing -----------------------------------------------------------------------------------

class Absent:
    def __repr__(self):
        return "<absent>"


ABSENT = Absent()


class Diff:
    """Walks two values together: leaves compared, differing leaves, the first one, the largest gap."""

    def __init__(self):
        self.fields = 0
        self.differ = 0
        self.first: tuple[str, object, object] | None = None
        self.max_abs = 0.0
        self.paths: list[str] = []  # the first differing fields, for equality.json
        self.kinds = {"added": 0, "removed": 0, "changed": 0}

    def note(self, path: str, a, b, gap: float | None = None):
        self.differ += 1
        self.kinds["added" if a is ABSENT else "removed" if b is ABSENT else "changed"] += 1
        if self.first is None:
            self.first = (path, a, b)
        if len(self.paths) < 20:
            self.paths.append(f"{path.lstrip('.')}: {short(a)} -> {short(b)}")
        if gap is not None and np.isfinite(gap):
            self.max_abs = max(self.max_abs, gap)

    def walk(self, a, b, path: str = ""):
        if isinstance(a, dict) and isinstance(b, dict):
            for k in sorted(set(a) | set(b), key=str):
                if k in IGNORED:
                    continue
                if k not in a or k not in b:
                    self.fields += 1
                    self.note(f"{path}.{k}", a.get(k, ABSENT), b.get(k, ABSENT))
                else:
                    self.walk(a[k], b[k], f"{path}.{k}")
        elif isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
            self.array(np.asarray(a), np.asarray(b), path)
        elif isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
            for i, (x, y) in enumerate(zip(a, b)):
                self.walk(x, y, f"{path}[{i}]")
            if len(a) != len(b):  # after the common part, so a text's first differing line is named first
                self.fields += 1
                self.note(f"{path} length", len(a), len(b))
        else:
            self.fields += 1
            if not same(a, b):
                num = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in (a, b))
                self.note(path, a, b, abs(a - b) if num else None)

    def array(self, a: np.ndarray, b: np.ndarray, path: str):
        if a.shape != b.shape or a.dtype != b.dtype:
            self.fields += 1
            self.note(f"{path} shape/dtype", f"{a.shape} {a.dtype}", f"{b.shape} {b.dtype}")
            return
        self.fields += a.size
        eq = a == b
        if a.dtype.kind == "f":
            eq |= np.isnan(a) & np.isnan(b)
        if not eq.all():
            bad = np.argwhere(~eq)
            i = tuple(bad[0])
            gap = np.abs(a.astype(float) - b.astype(float))[~eq].max() if a.dtype.kind in "fiu" else None
            self.note(f"{path}{list(i)}", a[i].item(), b[i].item(), gap)
            self.differ += len(bad) - 1
            self.kinds["changed"] += len(bad) - 1


def same(a, b) -> bool:
    """Equal value and type (95 and 95.0 differ: the file changed); NaN equals NaN."""
    return type(a) is type(b) and (a == b or (isinstance(a, float) and a != a and b != b))


def text_diff(a: list[str], b: list[str]) -> Diff:
    """Lines as a diff sees them: one inserted line is one difference, not every line after it."""
    d = Diff()
    d.fields = max(len(a), len(b))
    for op, i1, i2, j1, j2 in difflib.SequenceMatcher(None, a, b, autojunk=False).get_opcodes():
        if op != "equal":
            for k in range(max(i2 - i1, j2 - j1)):
                x = a[i1 + k] if i1 + k < i2 else ABSENT
                y = b[j1 + k] if j1 + k < j2 else ABSENT
                d.note(f"line {min(i1 + k, len(a)) + 1}", x, y)
    return d


def compare_file(a: Path, b: Path) -> Diff:
    da, db = read(a), read(b)
    if all(isinstance(x, list) and all(isinstance(v, str) for v in x) for x in (da, db)):
        return text_diff(da, db)
    d = Diff()
    d.walk(da, db)
    if a.suffix == ".mp4" and d.differ:  # bytes differ: are the pictures the same?
        d = Diff()
        d.array(frames(a), frames(b), "frames")
    return d


def outputs(root: Path) -> set[str]:
    """Files a case wrote (relative paths), without its input copy."""
    return {str(p.relative_to(root)) for p in root.rglob("*") if p.is_file()
            and not p.relative_to(root).parts[0].startswith("data")}


def group(rel: str) -> str:
    return re.sub(r"(?<=[-_])\d{3,}", "N", rel)  # file-000.parquet .. file-003.parquet: one row


def short(v) -> str:
    s = repr(v.item() if isinstance(v, np.generic) else v)
    return s if len(s) <= 40 else s[:37] + "..."


def rows_for(case: str, a_root: Path, b_root: Path) -> list[dict]:
    """One row per group of output files: files, fields compared, files differing, the first difference."""
    fa, fb = outputs(a_root), outputs(b_root)
    groups: dict[str, dict] = {}
    for rel in sorted(fa | fb):
        g = groups.setdefault(group(rel), {"case": case, "output": group(rel), "files": 0, "fields": 0,
                                           "files_differ": 0, "fields_differ": 0, "first": None,
                                           "max_abs": 0.0, "added": 0, "removed": 0, "changed": 0,
                                           "differences": {}})
        g["files"] += 1
        if rel not in fa or rel not in fb:
            g["files_differ"] += 1
            g["first"] = g["first"] or f"{rel} only in {'NEW' if rel not in fa else 'OLD'}"
            continue
        d = compare_file(a_root / rel, b_root / rel)
        g["fields"] += d.fields
        if d.differ:
            g["files_differ"] += 1
            g["fields_differ"] += d.differ
            g["max_abs"] = max(g["max_abs"], d.max_abs)
            g["differences"][rel] = d.paths
            for k, n in d.kinds.items():
                g[k] += n
            if g["first"] is None:
                p, x, y = d.first
                g["first"] = f"{rel}: {p.lstrip('.')}: {short(x)} -> {short(y)}"
    return list(groups.values())


# --- the run -------------------------------------------------------------------------------------

def run_case(case: str, trees: dict[str, Path], out: Path, deps: Path | None) -> list[str]:
    """Runs a case's commands in both trees; the failures, one line each."""
    dirs = {side: out / side / case for side in trees}
    for d in dirs.values():
        d.mkdir(parents=True, exist_ok=True)
    notes, absent = [], set()  # absent: the trees that lack one of the case's commands or options
    for name, args in CASES[case]:
        for data in {m[1] for a in args if (m := re.fullmatch(r"(data\w*)(/.*)?", a))}:
            syn = dirs["old"] / data.replace("data", "syn", 1)
            if syn.is_dir() and not (dirs["old"] / data).exists():
                for d in dirs.values():  # the verbs read OLD's synthetic data in both trees
                    shutil.copytree(syn, d / data)
        log = re.sub(r"\W+", "_", name)
        for side, tree in trees.items():
            if side in absent:
                continue
            t = time.perf_counter()
            rc, last, usage = run_realm(tree, dirs[side], args, log, deps)
            print(f"  {case}/{name} {side.upper()}: rc {rc}, {time.perf_counter() - t:.0f} s", file=sys.stderr)
            if usage:  # argparse refused the command line: the rest of the case is not run in that tree
                absent.add(side)
                notes.append(f"{case}: {side.upper()}'s realm refuses step `{name}` ({last}): a verb or option "
                             "it lacks; the case's later steps not run there")
            elif rc:
                notes.append(f"{case}/{name} fails in {side.upper()} (rc {rc}): {last}")
    return notes


def compare_case(case: str, out: Path) -> list[dict]:
    rows = rows_for(case, out / "old" / case, out / "new" / case)
    if case in SELF:  # each tree against itself: in-process vs worker processes or the batched runner
        for side in ("old", "new"):
            a, b = (out / side / case / run for run in SELF[case])
            if a.is_dir() and b.is_dir():
                rows += rows_for(f"{side.upper()} {' vs '.join(SELF[case])}", a, b)
    return rows


def table(rows: list[dict]) -> str:
    lines = ["| case | output | files | fields compared | result | first difference (OLD -> NEW) |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        if r["files_differ"]:
            kinds = ", ".join(f"{r[k]} {k}" for k in ("added", "removed", "changed") if r.get(k))
            res = f"differs ({r['files_differ']}/{r['files']} files; {kinds or 'file missing'}"
            res += f", max abs {r['max_abs']:.3g})" if r["max_abs"] else ")"
        else:
            res = "equal"
        lines.append(f"| {r['case']} | {r['output']} | {r['files']} | {r['fields']} | {res} | {r['first'] or ''} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old", help="commit or tree path")
    ap.add_argument("new", help="commit or tree path")
    ap.add_argument("--out", type=Path, help="where both trees' outputs stay (default: a new /tmp directory)")
    ap.add_argument("--deps", type=Path, help="packages a tree needs that this venv lacks (pip install --target DIR; "
                    "84c19c6's export imports rich), after the tree on both trees' PYTHONPATH")
    ap.add_argument("--no-run", action="store_true", help="compare the outputs already in --out (runs nothing)")
    ap.add_argument("--cases", default=",".join(CASES), help=f"comma-separated, of {','.join(CASES)}")
    a = ap.parse_args(argv)
    cases = a.cases.split(",")
    if unknown := [c for c in cases if c not in CASES]:
        ap.error(f"unknown case(s) {', '.join(unknown)}; known: {', '.join(CASES)}")
    if a.no_run and not a.out:
        ap.error("--no-run needs --out, the outputs of an earlier run")
    out = (a.out or Path(tempfile.mkdtemp(prefix="realm-equality-"))).resolve()
    if a.no_run:
        labels, notes, wall = {"old": a.old, "new": a.new}, [], 0.0
    else:
        labels, notes, wall = run_trees(a, cases, out)
    rows = [r for case in cases for r in compare_case(case, out)]
    print(f"\nOLD = {labels['old']}, NEW = {labels['new']} ({wall / 60:.1f} min, outputs in {out})")
    print(f"ignored keys: {', '.join(IGNORED)}; all else exact" + (f"; --deps {a.deps}" if a.deps else "") + "\n")
    print(table(rows))
    for n in notes:
        print(f"- {n}")
    (out / "equality.json").write_text(json.dumps(
        {"old": labels["old"], "new": labels["new"], "ignored": IGNORED, "rows": rows, "notes": notes},
        indent=1, default=str))
    return 0


def run_trees(a, cases: list[str], out: Path) -> tuple[dict, list[str], float]:
    """Opens both trees, runs the cases in each, removes the worktrees it made."""
    scratch = Path(tempfile.mkdtemp(prefix="realm-equality-trees-"))
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))  # a kill still removes the worktrees
    opened = []
    try:
        trees, labels = {}, {}
        for side, spec in (("old", a.old), ("new", a.new)):
            tree, labels[side], temporary = open_tree(spec, scratch)
            if temporary:
                opened.append(tree)
            imports_from(tree)
            trees[side] = tree
        print(f"OLD {labels['old']}  NEW {labels['new']}  outputs in {out}", file=sys.stderr)
        t0 = time.perf_counter()
        notes = [n for case in cases for n in run_case(case, trees, out, a.deps)]
        return labels, notes, time.perf_counter() - t0
    finally:
        for tree in opened:
            git("worktree", "remove", "--force", str(tree))
        shutil.rmtree(scratch, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
