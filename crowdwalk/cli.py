"""The ``crowdwalk`` command line.

Every command imports its implementation lazily so ``--help`` is fast. Bad input ends
with one line on stderr and exit code 2 (130 on Ctrl-C), never a traceback.
"""

from __future__ import annotations

import functools
import sys
from pathlib import Path

import typer

app = typer.Typer(
    name="crowdwalk",
    help="Crowds of walking people that plan their footsteps.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def _fail(message: str, code: int) -> None:
    typer.echo(f"crowdwalk: {message}", err=True)
    raise typer.Exit(code)


def friendly_errors(func):
    """Turn bad input into one clear line and exit code 2."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        try:
            return func(*args, **kwargs)
        except typer.Exit:
            raise
        except KeyboardInterrupt:
            _fail("interrupted; files written so far stay readable.", 130)
        except FileNotFoundError as exc:
            _fail(f"file not found: {exc.filename or exc}", 2)
        except (ValueError, OSError) as exc:
            _fail(str(exc), 2)

    return wrapper


# --- scenario files -----------------------------------------------------------------


@app.command()
@friendly_errors
def validate(scenario: Path = typer.Argument(..., help="Scenario YAML file.")) -> None:
    """Check a scenario file against the schema and build its world."""
    from crowdwalk.scenario import load_scenario
    from crowdwalk.world import build_world

    sc = load_scenario(scenario)
    world = build_world(sc)
    n = sum(g.count for g in sc.groups)
    typer.echo(
        f"{scenario}: valid — {len(sc.groups)} group(s), {n} agent(s), "
        f"{world.routes.graph.number_of_nodes()} route nodes, "
        f"walkable area {world.routes.walkable_area.area:.1f} m²."
    )


@app.command()
@friendly_errors
def schema() -> None:
    """Print the scenario file's JSON Schema."""
    import json

    from crowdwalk.scenario import scenario_json_schema

    typer.echo(json.dumps(scenario_json_schema(), indent=2))


# --- planning (issue 3): plan -------------------------------------------------------


# --- simulation (issue 5): run, compare ---------------------------------------------


# --- gait export (issue 4): export-bvh ----------------------------------------------


# --- viewer (issue 6): view, render -------------------------------------------------


def main() -> None:
    """Entry point of the ``crowdwalk`` script."""
    app()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
