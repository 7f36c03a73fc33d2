"""KLAW styles in a real `crowdwalk run` (issue 12): every attribute moves the joint angle
or point it controls, in the set direction and by about the set amount, measured in the
run's poses.sqlite / footsteps.csv / BVH; locomotion parameters reach the crowd's steps."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from crowdwalk.body import JOINT
from crowdwalk.cli import app
from crowdwalk.record import open_run
from crowdwalk.style import ATTRIBUTES, PRESETS

DEFAULTS = {a.name: a.default for a in ATTRIBUTES}
# one walker per (engine, changed attribute): the attribute set high, the rest default
CHANGES = {
    "shoulder_rotation": 15.0, "arm_swing": 35.0, "arm_out": 25.0, "elbow_min": 28.0,
    "elbow_max": 80.0, "torso_tilt": 15.0, "torso_sway": 8.0, "pelvic_rotation": 12.0,
    "pelvic_list": 9.0, "bounciness": 3.0, "knee_stance_min": 20.0, "knee_impact": 15.0,
    "toe_clearance": 0.05, "foot_angle": 20.0, "stride_width": 0.25,
}
# attributes the elevation-angle engine does not take (its knees follow measured data;
# its swing clearance is the planner's)
KLAW_ONLY = {"knee_stance_min", "knee_impact", "toe_clearance"}
LANE = 1.4


def _groups():
    out = [("klaw", "base", {}), ("elevation_angles", "base", {})]
    for name, value in CHANGES.items():
        out.append(("klaw", name, {name: value}))
        if name not in KLAW_ONLY:
            out.append(("elevation_angles", name, {name: value}))
    out += [("klaw", "marching", {"preset": "marching"}),
            ("elevation_angles", "tired", {"preset": "tired"}),
            ("elevation_angles", "proud", {"preset": "proud"})]
    return out


def _scenario(duration=7.0):
    groups, nodes, edges = [], [], []
    for i, (gait, label, style) in enumerate(_groups()):
        y = 1.0 + LANE * i
        nodes += [{"name": f"a{i}", "xy": [1.0, y],
                   "area": [[0.4, y - 0.4], [1.6, y - 0.4], [1.6, y + 0.4], [0.4, y + 0.4]]},
                  {"name": f"b{i}", "xy": [14.0, y]}]
        edges.append({"from": f"a{i}", "to": f"b{i}", "width": 1.0})
        groups.append({"name": f"{gait}-{label}", "count": 1, "spawn": f"a{i}",
                       "destinations": [f"b{i}"], "gait": gait, "planner": "fixed",
                       "body_height": {"mean": 1.75}, "free_speed": {"mean": 1.3},
                       "style": style})
    return {"name": "style-lanes", "terrain": {"extent": [0, 0, 15, 2.0 + LANE * len(groups)]},
            "routes": {"nodes": nodes, "edges": edges}, "groups": groups,
            "simulation": {"duration": duration, "seed": 4, "dt": 0.02, "fps": 50}}


@pytest.fixture(scope="module")
def lanes(tmp_path_factory):
    root = tmp_path_factory.mktemp("styles")
    path = root / "lanes.yaml"
    path.write_text(yaml.safe_dump(_scenario(), sort_keys=False))
    result = CliRunner().invoke(app, ["run", str(path), "--out", str(root / "run"), "--quiet"])
    assert result.exit_code == 0, result.output
    run = open_run(root / "run")
    poses = run.poses()
    names = {g["name"]: i for i, g in enumerate(_scenario()["groups"])}
    collected = {agent: ([], [], []) for agent in range(len(names))}
    for rec in poses:  # one pass over the frames for every agent
        for row, agent in enumerate(rec.ids.tolist()):
            for out, value in zip(collected[agent], (rec.time, rec.positions[row],
                                                     rec.contact[row]), strict=True):
                out.append(value)
    tracks = {agent: tuple(np.asarray(v) for v in values)
              for agent, values in collected.items()}
    return run, names, tracks, root


def _angle(u, v):
    cos = (u * v).sum(-1) / np.linalg.norm(u, axis=-1) / np.linalg.norm(v, axis=-1)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def _heading(p):
    """Unit walking direction per frame (k, 3), from the root's motion (smoothed)."""
    root = p[:, 0]
    d = np.gradient(root, axis=0)
    d[:, 2] = 0.0
    k = np.ones(15) / 15
    d = np.stack([np.convolve(d[:, i], k, mode="same") for i in range(3)], axis=1)
    return d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-9)


def _steady(p):
    """Frames of steady walking: from 1.5 s on while the root moves."""
    speed = np.linalg.norm(np.diff(p[:, 0, :2], axis=0), axis=1) * 50
    moving = np.concatenate([speed > 0.6, [False]])
    moving[:75] = False
    return moving


def _measure(name, track, run, agent):
    """The quantity attribute ``name`` controls, measured on an agent's frames."""
    times, p, contact = track
    if name == "knee_impact":  # at the heel strikes of footsteps.csv, extrapolated from
        # the two frames before each (terminal swing is linear in the knee angle)
        steps = run.footsteps()
        mine = (steps.agent == agent) & (steps.time > times[0] + 1.5)
        out = []
        for t, foot in zip(steps.time[mine], steps.foot[mine], strict=True):
            i = np.searchsorted(times, t) - 1
            if i < 1 or i + 1 >= times.size:
                continue
            hip, knee, ankle = (p[i - 1:i + 1, JOINT[f"{foot[0]}_{j}"]]
                                for j in ("hip", "knee", "talocrural"))
            knee = _angle(knee - hip, ankle - knee)
            out.append(knee[1] + (knee[1] - knee[0]) * (t - times[i]) / (times[i] - times[i - 1]))
        return float(np.median(out))
    f = _heading(p)
    up = np.array([0.0, 0.0, 1.0])
    left = np.cross(up, f)
    j = JOINT
    steady = _steady(p)
    p, f, left, contact = p[steady], f[steady], left[steady], contact[steady]

    def sagittal(vec):  # elevation from the downward vertical, forward positive [deg]
        return np.degrees(np.arctan2((vec * f).sum(-1), -vec[:, 2]))

    if name == "arm_swing":
        return np.ptp(sagittal(p[:, j["l_elbow"]] - p[:, j["l_shoulder"]])) / 2
    if name == "arm_out":
        arm = p[:, j["l_elbow"]] - p[:, j["l_shoulder"]]
        return np.degrees(np.arctan2((arm * left).sum(-1), -arm[:, 2])).mean()
    if name in ("elbow_min", "elbow_max"):
        flex = _angle(p[:, j["l_elbow"]] - p[:, j["l_shoulder"]],
                      p[:, j["l_wrist"]] - p[:, j["l_elbow"]])
        return np.percentile(flex, 2 if name == "elbow_min" else 98)
    if name in ("torso_tilt", "torso_sway"):
        trunk = p[:, j["skullbase"]] - p[:, j["vl5"]]
        if name == "torso_tilt":
            return np.degrees(np.arctan2((trunk * f).sum(-1), trunk[:, 2])).mean()
        lean = np.degrees(np.arctan2((trunk * left).sum(-1), trunk[:, 2]))
        return np.ptp(lean) / 2
    if name in ("pelvic_rotation", "shoulder_rotation"):
        a, b = ("l_hip", "r_hip") if name == "pelvic_rotation" else ("l_shoulder", "r_shoulder")
        line = p[:, j[a]] - p[:, j[b]]
        yaw = np.degrees(np.arctan2(-(line * f).sum(-1), (line * left).sum(-1)))
        if name == "shoulder_rotation":  # relative to the pelvis
            hips = p[:, j["l_hip"]] - p[:, j["r_hip"]]
            yaw -= np.degrees(np.arctan2(-(hips * f).sum(-1), (hips * left).sum(-1)))
        return np.ptp(yaw) / 2
    if name == "pelvic_list":
        line = p[:, j["l_hip"]] - p[:, j["r_hip"]]
        return np.ptp(np.degrees(np.arcsin(line[:, 2] / np.linalg.norm(line, axis=1)))) / 2
    if name == "bounciness":
        return np.ptp(p[:, 0, 2])
    if name == "knee_stance_min":
        out = []
        for s, leg in ((0, "l"), (1, "r")):
            knee = _angle(p[:, j[f"{leg}_knee"]] - p[:, j[f"{leg}_hip"]],
                          p[:, j[f"{leg}_talocrural"]] - p[:, j[f"{leg}_knee"]])
            single = contact[:, s] & ~contact[:, 1 - s]
            out.append(knee[single].min())
        return float(np.min(out))
    if name == "toe_clearance":
        least = []
        for s, leg in ((0, "l"), (1, "r")):
            swing = ~contact[:, s]
            edges = np.flatnonzero(np.diff(swing.astype(int)))
            for a0, a1 in zip(edges[:-1], edges[1:], strict=True):
                if not swing[a0 + 1]:
                    continue
                mid = slice(a0 + 1 + int(0.3 * (a1 - a0)), a0 + 1 + int(0.85 * (a1 - a0)))
                ankle, ball = p[mid, j[f"{leg}_talocrural"]], p[mid, j[f"{leg}_metatarsal"]]
                rel = ball - ankle
                pitch = np.arctan2(rel[:, 2], np.hypot(rel[:, 0], rel[:, 1])) - math.atan2(
                    -0.039, 0.073)
                least.append((ball[:, 2] + 0.041 * 1.75 * np.sin(pitch)).min())
        return float(np.median(least))
    if name == "foot_angle":
        out = []
        for s, leg in ((0, "l"), (1, "r")):
            stance = contact[:, s] & ~contact[:, 1 - s]
            foot = p[stance, j[f"{leg}_metatarsal"]] - p[stance, j[f"{leg}_talocrural"]]
            sign = 1.0 if leg == "l" else -1.0
            out.append(sign * np.degrees(np.arctan2((foot * left[stance]).sum(-1),
                                                    (foot * f[stance]).sum(-1))).mean())
        return float(np.mean(out))
    if name == "stride_width":
        steps = run.footsteps()
        mine = steps.agent == agent
        xy = np.stack([steps.x[mine], steps.y[mine]], axis=1)[3:]
        h = steps.heading[mine][3:]
        d = np.diff(xy, axis=0)
        return float(np.median(np.abs(-np.sin(h[1:]) * d[:, 0] + np.cos(h[1:]) * d[:, 1])))
    raise KeyError(name)


# measured change / set change must lie in this band (direction and magnitude)
@pytest.mark.parametrize("gait", ["klaw", "elevation_angles"])
@pytest.mark.parametrize("name", list(CHANGES))
def test_attribute_changes_what_it_controls(lanes, gait, name):
    if gait == "elevation_angles" and name in KLAW_ONLY:
        pytest.skip("not an attribute of the elevation-angle engine")
    run, names, tracks, _ = lanes
    base, changed = names[f"{gait}-base"], names[f"{gait}-{name}"]
    m0 = _measure(name, tracks[base], run, base)
    m1 = _measure(name, tracks[changed], run, changed)
    set_change = CHANGES[name] - DEFAULTS[name]
    if name == "bounciness":  # vertical pelvis excursion [m]
        if gait == "klaw":  # §2.2: the dip below impact height is bounce_factor / 5 of the
            # rise from impact to mid swing, so the excursion scales as (1 + b / 5)
            assert m1 / m0 == pytest.approx((1 + 3 / 5) / (1 + 1 / 5), rel=0.15), (m0, m1)
        else:  # the stance hip lowered by (b - 1) 0.006 body heights at mid double support
            assert m1 - m0 == pytest.approx(2 * 0.006 * 1.75, rel=0.3), (m0, m1)
        return
    ratio = (m1 - m0) / set_change
    assert 0.6 < ratio < 1.4, f"{gait} {name}: base {m0:.3f}, set {CHANGES[name]}, got {m1:.3f}"


def _bvh_positions(path):
    """World positions (F, joints) per joint name from a BVH file read by bvhio, y up."""
    import bvhio

    root = bvhio.readAsHierarchy(str(path))
    frames = []
    for f in range(root.getKeyframeRange()[1] + 1):
        root.loadPose(f)
        frames.append({j.Name: np.array(j.PositionWorld) for j, *_ in root.layout()})
    return {name: np.array([fr[name] for fr in frames]) for name in frames[0]}


def test_marching_and_tired_are_told_apart_in_the_bvh(lanes):
    """Exported with `crowdwalk export-bvh`: marching (klaw) swings its arms far more and
    holds its trunk upright; tired (elevation angles) barely swings and leans forward."""
    run, names, tracks, root = lanes
    measured = {}
    for label in ("klaw-marching", "elevation_angles-tired"):
        out = root / f"{label}.bvh"
        result = CliRunner().invoke(app, ["export-bvh", str(root / "run"), "--agent",
                                          str(names[label]), "--out", str(out),
                                          "--names", "hanim"])
        assert result.exit_code == 0, result.output
        p = _bvh_positions(out)  # BVH: X forward here (heading +x), Y up, cm
        moving = np.flatnonzero(np.gradient(p["HumanoidRoot"][:, 0]) > 0.6)[40:]
        arm = p["l_elbow"][moving] - p["l_shoulder"][moving]
        trunk = p["skullbase"][moving] - p["vl5"][moving]
        measured[label] = (np.ptp(np.degrees(np.arctan2(arm[:, 0], -arm[:, 1]))) / 2,
                           np.degrees(np.arctan2(trunk[:, 0], trunk[:, 1])).mean())
    (arm_m, tilt_m), (arm_t, tilt_t) = measured["klaw-marching"], measured[
        "elevation_angles-tired"]
    assert arm_m == pytest.approx(PRESETS["marching"]["arm_swing"], abs=4.0)
    assert arm_t == pytest.approx(3.0, abs=2.5)  # tired: arm swing {mean 3}
    assert tilt_m == pytest.approx(0.0, abs=1.0)
    assert tilt_t == pytest.approx(PRESETS["tired"]["torso_tilt"], abs=1.0)


def test_locked_and_normal_mode_reach_the_steps(lanes):
    """marching locks 2 steps/s: its steps last 0.5 s whatever their length; proud holds
    its locked 0.75 m step; the others (normal mode) step at the measured cadence of their
    speed (planners.normal_mode)."""
    run, names, tracks, root = lanes
    steps = run.footsteps()
    summary = json.loads((root / "run" / "summary.json").read_text())
    agents = {a["id"]: a for a in summary["agents"]}
    march = agents[names["klaw-marching"]]
    assert march["cadence_steps_per_s"] == pytest.approx(2.0, abs=0.1)
    assert march["style"] == "marching" and march["gait"] == "klaw"
    base = agents[names["klaw-base"]]
    from planners.normal_mode import leg_length_from_height, step_frequency

    expected = step_frequency(base["free_speed_m_s"], leg_length_from_height(1.75))
    assert base["cadence_steps_per_s"] == pytest.approx(float(expected), rel=0.08)
    # proud: velocity 4 km/h locked, step length 0.75 m held by the planned footholds
    proud = agents[names["elevation_angles-proud"]]
    mine = (steps.agent == names["elevation_angles-proud"]) & (steps.step > 3)
    assert np.median(steps.step_length[mine]) == pytest.approx(0.75, abs=0.04)
    assert proud["free_speed_m_s"] == pytest.approx(1.11)
    assert "styles" in summary and summary["styles"]["marching"]["agents"] == 1


def test_same_seed_same_output(tmp_path):
    """Two runs of a styled scenario with spreads (both engines) write identical files."""
    data = _scenario(duration=3.0)
    data["groups"] = data["groups"][:2] + [dict(data["groups"][2], count=1, style={
        "preset": "loose", "arm_swing": {"mean": 30, "sd": 6}})]
    path = tmp_path / "seed.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    outs = []
    for k in range(2):
        out = tmp_path / f"run{k}"
        result = CliRunner().invoke(app, ["run", str(path), "--out", str(out), "--quiet"])
        assert result.exit_code == 0, result.output
        outs.append(out)
    for name in ("footsteps.csv", "trajectories.sqlite"):
        assert (outs[0] / name).read_bytes() == (outs[1] / name).read_bytes()
    a, b = open_run(outs[0]).poses(), open_run(outs[1]).poses()
    assert a.frames.size > 50
    for fa, fb in zip(a, b, strict=True):
        np.testing.assert_array_equal(fa.positions, fb.positions)
