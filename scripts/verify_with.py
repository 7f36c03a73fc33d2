"""Run ``crowdwalk verify`` cases with any :class:`~crowdwalk.crowd.CrowdParams` fields
set (the CLI sets only ``--speed-model``), printing each row as verify does.

Usage: ``python scripts/verify_with.py --only rimea4,bottleneck,counterflow [--seeds 5]
[--full] [--crowd-model headway_s175] --set speed_model='headway' headway_free_margin=1.0``
(``--crowd-model``: the named model the ``--set`` fields go over,
``crowdwalk.crowd.params.CROWD_MODELS``, default free; ``--set``: Python literals;
a bare word is taken as a string; ``steering.FIELD=V`` sets a
:class:`~crowdwalk.crowd.steering.SteeringParams` field). ``--counterflow-length L`` (default
the verified 50 m; 30 m: the former case) and ``--counterflow-density D`` change the
counterflow case's corridor length [m] and start the groups on a lattice at D [1/m²]
(``crowdwalk.verify.counterflow_scenario``; other than the defaults: measurements, not the
verified case).
"""

from __future__ import annotations

import argparse

from crowdwalk.crowd.params import crowd_model, parse_overrides
from crowdwalk.verify import COUNTERFLOW_LENGTH, run_verification


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", required=True, help="case names, comma-separated")
    ap.add_argument("--seeds", type=int, default=None, help="counterflow seeds 1..N")
    ap.add_argument("--full", action="store_true", help="full sizes")
    ap.add_argument("--crowd-model", default="free", metavar="NAME")
    ap.add_argument("--set", nargs="*", default=[], metavar="FIELD=VALUE")
    ap.add_argument("--counterflow-length", type=float, default=COUNTERFLOW_LENGTH,
                    metavar="M")
    ap.add_argument("--counterflow-density", type=float, default=None, metavar="PER_M2")
    args = ap.parse_args()
    fields = parse_overrides(args.set)
    params = crowd_model(args.crowd_model, fields)
    print(f"# crowd model {args.crowd_model}, CrowdParams overrides: {fields}; counterflow "
          f"length {args.counterflow_length} m, "
          f"start density {args.counterflow_density}")
    run_verification(full=args.full, only=args.only.split(","), seeds=args.seeds,
                     params=params, counterflow_length=args.counterflow_length,
                     counterflow_density=args.counterflow_density)


if __name__ == "__main__":
    main()
