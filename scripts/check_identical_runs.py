"""Check that two versions of crowdwalk write identical run folders.

Runs quickstart, bottleneck, stairs_up_down, uneven_park and corner (all with poses) and a
20 s cut of stadium_egress (1,000 agents, no poses) with the code of a repository
checkout, then compares two such sets of run folders:

- ``footsteps.csv``: file bytes;
- ``trajectories.sqlite`` and ``poses.sqlite``: table contents (every row of every table
  in rowid order, values compared exactly); whether the file bytes agree too is printed
  (SQLite's page layout may differ for the same content);
- ``summary.json``: everything but ``timing`` (wall-clock times).

Usage::

    python scripts/check_identical_runs.py run --repo /path/to/checkout --out DIR
    python scripts/check_identical_runs.py compare DIR_A DIR_B

``run`` starts one Python process per scenario with ``PYTHONPATH`` set to the checkout
and the checkout as working directory, so the checkout's code (and its numba cache) is
what runs.
"""

from __future__ import annotations

import argparse
import json
import os
import sqlite3
import subprocess
import sys
import time
from contextlib import closing
from pathlib import Path

#: name -> (scenario file, RunOverrides keyword arguments)
RUNS = {
    "quickstart": ("scenarios/quickstart.yaml", {"poses": True}),
    "bottleneck": ("scenarios/bottleneck.yaml", {"poses": True}),
    "stadium_20s": ("scenarios/stadium_egress.yaml", {"duration": 20.0}),
    "stairs_up_down": ("scenarios/stairs_up_down.yaml", {"poses": True}),
    "uneven_park": ("scenarios/uneven_park.yaml", {"poses": True}),
    "corner": ("scenarios/corner.yaml", {"poses": True}),
}

_CHILD = """
import sys
from crowdwalk.crowd.run import RunOverrides, run_scenario
import crowdwalk
print(crowdwalk.__file__, file=sys.stderr)
run_scenario(sys.argv[1], sys.argv[2], overrides=RunOverrides(**eval(sys.argv[3])))
"""


def run(repo: Path, out: Path, names: list[str]) -> None:
    """Run the scenarios ``names`` with the code in ``repo`` into ``out/<name>``."""
    env = dict(os.environ, PYTHONPATH=str(repo))
    for name in names:
        scenario, overrides = RUNS[name]
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", _CHILD, str(repo / scenario), str(out / name),
                        repr(overrides)], cwd=repo, env=env, check=True)
        print(f"{name}: {time.perf_counter() - t0:.1f} s wall", flush=True)


def _tables(path: Path) -> dict[str, list[tuple]]:
    with closing(sqlite3.connect(f"file:{path}?mode=ro", uri=True)) as con:
        names = [r[0] for r in con.execute(
            "SELECT name FROM sqlite_master WHERE type='table' ORDER BY name")]
        return {t: con.execute(f"SELECT * FROM {t} ORDER BY rowid").fetchall() for t in names}


def _compare_sqlite(a: Path, b: Path) -> tuple[bool, str]:
    if a.exists() != b.exists():
        return False, "present in one run only"
    if not a.exists():
        return True, "absent in both"
    ta, tb = _tables(a), _tables(b)
    if ta.keys() != tb.keys():
        return False, f"tables differ: {sorted(ta)} vs {sorted(tb)}"
    for t in ta:
        if ta[t] != tb[t]:
            diff = next(i for i, (x, y) in enumerate(zip(ta[t], tb[t], strict=False))
                        if x != y) if len(ta[t]) == len(tb[t]) else "row count"
            sizes = f"{len(ta[t])} vs {len(tb[t])} rows"
            return False, f"table {t} differs (first at row {diff}; {sizes})"
    rows = sum(len(v) for v in ta.values())
    same_bytes = a.read_bytes() == b.read_bytes()
    layout = "identical" if same_bytes else "differ"
    return True, f"content identical ({rows} rows); file bytes {layout}"


def compare(a: Path, b: Path, names: list[str]) -> bool:
    """Print one line per file and run; True when everything agrees."""
    ok_all = True
    for name in names:
        ra, rb = a / name, b / name
        fa, fb = (ra / "footsteps.csv").read_bytes(), (rb / "footsteps.csv").read_bytes()
        rows = fa.count(b"\n") - 1
        checks = [("footsteps.csv", fa == fb,
                   f"bytes {'identical' if fa == fb else 'differ'} ({rows} rows)")]
        for f in ("trajectories.sqlite", "poses.sqlite"):
            checks.append((f, *_compare_sqlite(ra / f, rb / f)))
        sa = json.loads((ra / "summary.json").read_text())
        sb = json.loads((rb / "summary.json").read_text())
        sa.pop("timing"), sb.pop("timing")
        checks.append(("summary.json", sa == sb, "identical but timing" if sa == sb
                       else "differs (not counting timing)"))
        for f, ok, note in checks:
            ok_all &= ok
            print(f"{name:<12} {f:<20} {'OK ' if ok else 'BAD'} {note}")
    print("IDENTICAL" if ok_all else "DIFFERENT")
    return ok_all


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--repo", type=Path, required=True)
    r.add_argument("--out", type=Path, required=True)
    r.add_argument("--only", nargs="*", default=list(RUNS))
    c = sub.add_parser("compare")
    c.add_argument("a", type=Path)
    c.add_argument("b", type=Path)
    c.add_argument("--only", nargs="*", default=list(RUNS))
    args = ap.parse_args()
    if args.cmd == "run":
        run(args.repo.resolve(), args.out.resolve(), args.only)
    else:
        sys.exit(0 if compare(args.a, args.b, args.only) else 1)


if __name__ == "__main__":
    main()
