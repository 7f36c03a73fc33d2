"""Hostile and malformed scenario files: one located line, exit code 2, bounded time.

Two corpora, both generated here: named files for each class of attack or mistake (YAML
bombs, deep nesting, NaN and infinity, huge grids and crowds, run-time-only problems), and a
seeded mutation fuzz of the quickstart scenario (every kind of wrong value at random
fields). Each must end in :class:`InputError` whose message starts with ``file:line:``,
carries no numpy repr and no newline — within a time bound.
"""

from __future__ import annotations

import copy
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from crowdwalk.checks import world_and_population
from crowdwalk.errors import InputError
from crowdwalk.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[1]
QUICKSTART = ROOT / "scenarios" / "quickstart.yaml"
LOCATED = re.compile(r"^\S+\.yaml:\d+: \S.*\.$")


def _quickstart() -> dict:
    return yaml.safe_load(QUICKSTART.read_text())


def _with(path: tuple, value) -> str:
    d = _quickstart()
    node = d
    for p in path[:-1]:
        node = node[p]
    node[path[-1]] = value
    return yaml.safe_dump(d, sort_keys=False)


def _laughs(levels: int = 9) -> str:
    lines = ['a0: &a0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    for i in range(1, levels):
        refs = ", ".join([f"*a{i - 1}"] * 10)
        lines.append(f"a{i}: &a{i} [{refs}]")
    return "\n".join(lines) + "\n"


def _many_nodes(n: int) -> str:
    d = _quickstart()
    d["routes"]["nodes"] += [{"name": f"n{i}", "xy": [1 + i % 38, 1 + (i // 38) % 28]}
                             for i in range(n)]
    return yaml.safe_dump(d, sort_keys=False)


HOSTILE = {
    "billion_laughs": _laughs(),
    "recursive_alias": "terrain: &t {extent: [0, 0, 1, 1], features: [*t]}\n",
    "recursive_sequence": "groups: &g [*g]\n",
    "alias_chain_depth": "".join(f"a{i}: &a{i} [*a{i - 1}]\n" if i else "a0: &a0 [1]\n"
                                 for i in range(300)),
    "nested_500": "terrain: " + "[" * 500 + "]" * 500 + "\n",
    "nested_maps_600": "".join("  " * i + f"k{i}:\n" for i in range(600)) + "  " * 600 + "1\n",
    "not_a_mapping": "- 1\n- 2\n",
    "not_utf8": b"name: x\ndescription: \xff\xfe\n",
    "empty": "",
    "control_characters": "\x00\x01\x02 garbage {[",
    "nan_polygon_vertex": _with(("terrain", "features", 1, "footprint", 0, 0), float("nan")),
    "nan_node_area": _with(("routes", "nodes", 0, "area", 0, 0), float("nan")),
    "stairs_heading_inf": _with(("terrain", "features", 4, "heading"), float("inf")),
    "duration_inf": _with(("simulation", "duration"), float("inf")),
    "extent_neg_inf": _with(("terrain", "extent", 0), float("-inf")),
    "free_speed_crawl": _with(("groups", 2, "free_speed"), {"mean": 0.01, "sd": 0}),
    "spawn_outside_walkable": _with(("groups", 0, "spawn"),
                                    [[20, 25], [22, 25], [22, 27], [20, 27]]),
    "count_1e5": _with(("groups", 0, "count"), 100_000),
    "count_huge_int": _with(("groups", 0, "count"), 10**30),
    "rough_cell_tiny": _with(("terrain", "features"), [
        {"type": "rough", "origin": [0, 0], "size": [40, 30], "cell": 0.0001,
         "amplitude": 0.02}]),
    "rough_heights_nan": _with(("terrain", "features"), [
        {"type": "rough", "origin": [1, 1], "cell": 0.5, "heights": [[0, 0], [0, ".nan"]]}]),
    "route_nodes_10001": _many_nodes(10_001),
    "graphml_missing": _with(("routes",), {"graphml": "nowhere.graphml"}),
    "unknown_feature": _with(("terrain", "features", 0, "type"), "volcano"),
}


def _check(path: Path) -> None:
    world_and_population(load_scenario(path))


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_hostile_file_is_one_located_line(tmp_path, name):
    path = tmp_path / f"{name}.yaml"
    data = HOSTILE[name]
    path.write_bytes(data if isinstance(data, bytes) else data.encode())
    t0 = time.perf_counter()
    with pytest.raises((InputError, FileNotFoundError)) as err:
        _check(path)
    assert time.perf_counter() - t0 < 20.0, name  # a loaded 2-core machine: seconds
    if err.type is FileNotFoundError:
        return
    message = str(err.value)
    assert LOCATED.match(message), message
    assert str(path) in message and "np." not in message and "\n" not in message


def _leaves(d, path=()):
    if isinstance(d, dict):
        for k, v in d.items():
            yield from _leaves(v, (*path, k))
    elif isinstance(d, list):
        for i, v in enumerate(d):
            yield from _leaves(v, (*path, i))
    else:
        yield path


WRONG = [float("nan"), float("inf"), -float("inf"), 0, -1, 1e12, 1e-12, 10**30, "x", [], {},
         None, True]


def test_mutation_fuzz_of_the_quickstart(tmp_path):
    """Seeded mutations: each either validates (and then builds its population) or ends in
    one located line; nothing else escapes, and the whole corpus runs in bounded time."""
    base = _quickstart()
    leaves = list(_leaves(base))
    rng = np.random.default_rng(17)
    t0, outcomes = time.perf_counter(), {"ok": 0, "error": 0}
    for k in range(60):
        d = copy.deepcopy(base)
        path = leaves[rng.integers(len(leaves))]
        node = d
        for p in path[:-1]:
            node = node[p]
        node[path[-1]] = WRONG[rng.integers(len(WRONG))]
        file = tmp_path / f"m{k}.yaml"
        file.write_text(yaml.safe_dump(d, sort_keys=False))
        try:
            _check(file)
            outcomes["ok"] += 1
        except InputError as exc:
            assert LOCATED.match(str(exc)) and "np." not in str(exc), (path, str(exc))
            outcomes["error"] += 1
    assert outcomes["error"] > 30  # most mutations are errors, a few are harmless
    assert time.perf_counter() - t0 < 30.0


@pytest.mark.parametrize("command", ["run"])  # validate: the same path, in-process above
def test_cli_exit_2_one_line(tmp_path, command):
    path = tmp_path / "laughs.yaml"
    path.write_text(_laughs())
    args = [command, str(path)] + (["--out", str(tmp_path / "r")] if command == "run" else [])
    proc = subprocess.run([sys.executable, "-m", "crowdwalk.cli", *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and f"{path}:" in lines[0] and "alias" in lines[0], proc.stderr
