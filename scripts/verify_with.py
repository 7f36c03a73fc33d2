"""Run ``crowdwalk verify`` cases with any :class:`~crowdwalk.crowd.CrowdParams` fields
set (the CLI sets only ``--speed-model``), printing each row as verify does.

Usage: ``python scripts/verify_with.py --only rimea4,bottleneck,counterflow [--seeds 5]
[--full] --set speed_model='headway' headway_free_margin=1.0`` (``--set``: Python literals;
a bare word is taken as a string).
"""

from __future__ import annotations

import argparse
import ast
from dataclasses import replace

from crowdwalk.crowd import CrowdParams
from crowdwalk.verify import run_verification


def _value(text: str):
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return text


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", required=True, help="case names, comma-separated")
    ap.add_argument("--seeds", type=int, default=None, help="counterflow seeds 1..N")
    ap.add_argument("--full", action="store_true", help="full sizes")
    ap.add_argument("--set", nargs="*", default=[], metavar="FIELD=VALUE")
    args = ap.parse_args()
    fields = {k: _value(v) for k, v in (item.split("=", 1) for item in args.set)}
    params = replace(CrowdParams(), **fields)
    print(f"# CrowdParams overrides: {fields}")
    run_verification(full=args.full, only=args.only.split(","), seeds=args.seeds,
                     params=params)


if __name__ == "__main__":
    main()
