"""Store the planner replay fixture ``data/replay.json`` (run once; see replay_cases).

``python tests/planners/make_replay.py`` from the repository root. The searches named in
the fixture are the names the plans were stored under.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from replay_cases import configs, profiles, walkers  # noqa: E402

from planners import plan_batch  # noqa: E402

#: Stored search -> the planner name it had when the fixture was made.
SEARCHES = {"best_first_multistart": "best_first", "fixed": "fixed", "optimal": "optimal"}


def main() -> None:
    grounds = profiles()
    legs, speeds, trailing = walkers(len(grounds))
    out = {"profiles": list(grounds), "plans": {}}
    for cname, config in configs().items():
        for stored, planner in SEARCHES.items():
            rows = []
            # each walker twice: its own trailing foot, and the default (None)
            for tr in (trailing, None):
                plans = plan_batch(list(grounds.values()), legs, speeds, planner, config,
                                   trailing=tr)
                rows += [{"status": p.status, "footholds_s": p.footholds_s.tolist(),
                          "footholds_z": p.footholds_z.tolist(), "E": p.E.tolist()}
                         for p in plans]
            out["plans"][f"{cname}/{stored}"] = rows
    path = Path(__file__).parent / "data" / "replay.json"
    path.write_text(json.dumps(out))
    print(f"wrote {path} ({path.stat().st_size} bytes)")


if __name__ == "__main__":
    main()
