"""Gait of a run's walkers against measured human gait (``crowdwalk gait-report RUN``).

Everything is measured from what ``crowdwalk run`` wrote: joint world positions and foot
contacts in ``poses.sqlite``, footholds in ``footsteps.csv``, trajectories, the scenario's
terrain. The measurement functions are public and work on one walker's
:class:`WalkerTrack` (any gait engine with the crowdwalk skeleton), so other reports can
reuse them. References (shipped derived figures, ``crowdwalk/data``): Winter (1991) joint
angles at slow / natural / fast cadence, Bovi et al. (2011) stair knee flexion, the WBDS
normal-mode relation (``planners.normal_mode``).

Conventions: sagittal angles in the pelvis's progression plane (forward = perpendicular to
the hip axis, horizontal); hip flexion = thigh elevation + pelvis anterior tilt, knee
flexion = thigh − shank elevation, ankle dorsiflexion = foot pitch − shank elevation with
the foot's pitch 0 when heel and ball touch level ground. Cycles run from one left-foot
contact onset to the next.
"""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass
from functools import cache
from importlib import resources
from pathlib import Path

import numpy as np

from crowdwalk.body import JOINT, LEG_JOINTS, PARENTS, PROPORTIONS, quaternion_to_matrix
from crowdwalk.steps import FootstepTable

__all__ = ["CycleKind", "GaitFigures", "WalkerTrack", "cycle_curves", "edge_clearance",
           "foot_points", "foot_yaw_from_rotations", "gait_figures", "heel_slides",
           "load_tracks", "references", "report_table",
           "sagittal_angles", "second_differences", "stance_runs", "swing_clearance",
           "winter_at"]

SAMPLES = 51  # stride fraction 0, 0.02, ..., 1 (Winter's grid)
LEVEL, STAIRS_UP, STAIRS_DOWN, OTHER = "level", "stairs_up", "stairs_down", "other"
CycleKind = str
#: Stair cycles are compared with Bovi over 0 .. STAIR_STANCE of the cycle as well: Bovi's
#: adult foot-off is at 70 % (up) and 71 % (down), and the recorded stair cycles do not
#: close (ascent knee 66 deg at 0 %, 19 deg at 100 %: the swing ends off the flight), so
#: a periodic step-over-step cycle cannot follow the terminal swing.
STAIR_STANCE = 0.6
_PELVIS, _LUMBAR = 0, 12  # HumanoidRoot, vl5


@dataclass(frozen=True)
class WalkerTrack:
    """One walker's stored poses: ``time`` (F,) [s], joint world ``positions`` (F, J, 3)
    [m], ``contact`` (F, 2) bool (left, right), ``body_height`` [m], ``fps`` [1/s];
    ``foot_yaw`` (F, 2) [rad] (left, right): the heading of each foot segment from the
    written joint rotations (:func:`foot_yaw_from_rotations`), None for a track given by
    positions only."""

    agent: int
    body_height: float
    time: np.ndarray
    positions: np.ndarray
    contact: np.ndarray
    fps: float
    foot_yaw: np.ndarray | None = None


#: The segment whose heading is a foot's yaw: the foot distal to the subtalar joint.
_FOOT_SEGMENT = LEG_JOINTS[:, 3]


def foot_yaw_from_rotations(root_quaternion: np.ndarray, joints: np.ndarray) -> np.ndarray:
    """Heading [rad] (F, 2) of the left and right foot segments from the written rotations:
    the root's world quaternion (F, 4) wxyz and the local joint quaternions (F, J, 4)
    composed down the skeleton (``R_world[j] = R_world[parent] @ R_local[j]``, the BVH
    semantics of :mod:`crowdwalk.body`).

    The heading is that of the foot's lateral (y) axis turned by −90°: pitching the foot
    (heel rise, push-off) turns about that axis and leaves it, so the yaw stays defined
    when the foot is plantarflexed past vertical, where a heading read from the ankle and
    ball positions flips by 180°. Unwrapped over time.
    """
    local = quaternion_to_matrix(np.asarray(joints, float))
    world = {0: quaternion_to_matrix(np.asarray(root_quaternion, float))}
    out = []
    for foot in _FOOT_SEGMENT.tolist():
        chain = []
        j = foot
        while j > 0:
            chain.append(j)
            j = int(PARENTS[j])
        r = world[0]
        for k in reversed(chain):
            r = r @ local[:, k]
        lateral = r[:, :, 1]
        out.append(np.unwrap(np.arctan2(-lateral[:, 0], lateral[:, 1])))
    return np.column_stack(out)


def load_tracks(poses) -> dict[int, WalkerTrack]:
    """Every agent's :class:`WalkerTrack` from a :class:`~crowdwalk.record.Poses` reader,
    in one pass over the stored frames (``foot_yaw`` from the written joint rotations)."""
    acc: dict[int, tuple[list, list, list, list, list]] = {}
    for rec in poses:
        for i, agent in enumerate(rec.ids.tolist()):
            t, p, c, rq, jq = acc.setdefault(agent, ([], [], [], [], []))
            t.append(rec.time)
            p.append(rec.positions[i])
            c.append(rec.contact[i])
            rq.append(rec.root_quaternion[i])
            jq.append(rec.joints[i])
    return {a: WalkerTrack(agent=a, body_height=float(poses.body_heights[a]),
                           time=np.asarray(t), positions=np.asarray(p),
                           contact=np.asarray(c, bool), fps=float(poses.fps),
                           foot_yaw=foot_yaw_from_rotations(np.asarray(rq), np.asarray(jq)))
            for a, (t, p, c, rq, jq) in acc.items()}


# --- geometry of the stored skeleton ---------------------------------------------------


def _forward(positions: np.ndarray) -> np.ndarray:
    """Horizontal progression direction (F, 2): perpendicular to the left-right hip axis."""
    axis = positions[:, LEG_JOINTS[0, 0], :2] - positions[:, LEG_JOINTS[1, 0], :2]
    fwd = np.column_stack([axis[:, 1], -axis[:, 0]])
    return fwd / np.linalg.norm(fwd, axis=1, keepdims=True)


def _elevation(vec: np.ndarray, fwd: np.ndarray) -> np.ndarray:
    """Angle [rad] of ``vec`` (F, 3) from straight down, positive when pointing forward."""
    return np.arctan2(np.einsum("fi,fi->f", vec[:, :2], fwd), -vec[:, 2])


def _foot_pitch_rest(height: float) -> float:
    """Pitch [rad] of the ankle->ball vector below the horizontal with the foot flat."""
    return float(np.arctan2(PROPORTIONS["ankle_height"], PROPORTIONS["ball_offset"]))


def sagittal_angles(track: WalkerTrack, side: int = 0) -> np.ndarray:
    """Hip flexion, knee flexion and ankle dorsiflexion (F, 3) [deg] of one leg (0 left)."""
    p = track.positions
    hip, knee, ankle, _, ball = (p[:, j] for j in LEG_JOINTS[side])
    fwd = _forward(p)
    thigh = _elevation(knee - hip, fwd)
    shank = _elevation(ankle - knee, fwd)
    up = p[:, _LUMBAR] - p[:, _PELVIS]
    tilt = np.arctan2(np.einsum("fi,fi->f", up[:, :2], fwd), up[:, 2])  # anterior +
    foot = ball - ankle
    pitch = np.arctan2(foot[:, 2], np.einsum("fi,fi->f", foot[:, :2], fwd))
    pitch = pitch + _foot_pitch_rest(track.body_height)
    return np.rad2deg(np.column_stack([thigh + tilt, thigh - shank, pitch - shank]))


def foot_points(track: WalkerTrack, side: int) -> dict[str, np.ndarray]:
    """Heel, ball and toe-tip sole points (F, 3) [m] of one foot, from ankle and ball.

    The heel sole point lies ``heel_offset`` behind and ``ankle_height`` below the ankle in
    the foot's frame, the toe tip ``toe_offset`` ahead (toes taken straight).
    """
    h = track.body_height
    p = track.positions
    ankle, ball = p[:, LEG_JOINTS[side, 2]], p[:, LEG_JOINTS[side, 4]]
    b = ball - ankle
    b_hat = b / np.linalg.norm(b, axis=1, keepdims=True)
    lateral = np.cross(b_hat, [0.0, 0.0, 1.0])
    lateral /= np.linalg.norm(lateral, axis=1, keepdims=True)
    up_b = np.cross(lateral, b_hat)
    d = _foot_pitch_rest(h)
    fwd = np.cos(d) * b_hat + np.sin(d) * up_b
    up = -np.sin(d) * b_hat + np.cos(d) * up_b
    below = ankle - PROPORTIONS["ankle_height"] * h * up
    return {"heel": below - PROPORTIONS["heel_offset"] * h * fwd, "ball": ball,
            "toe": below + PROPORTIONS["toe_offset"] * h * fwd}


# --- events and cycles -------------------------------------------------------------------


def stance_runs(contact: np.ndarray) -> list[tuple[int, int]]:
    """Half-open frame ranges [start, stop) of consecutive True values in ``contact`` (F,)."""
    c = np.concatenate([[False], contact.astype(bool), [False]])
    edges = np.flatnonzero(np.diff(c.astype(int)))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))


def cycle_curves(values: np.ndarray, strikes: np.ndarray) -> np.ndarray:
    """``values`` (F, k) resampled over each cycle between consecutive ``strikes`` frame
    indices onto :data:`SAMPLES` points: (n_cycles, SAMPLES, k)."""
    grid = np.linspace(0.0, 1.0, SAMPLES)
    out = []
    for a, b in zip(strikes[:-1], strikes[1:], strict=True):
        s = (np.arange(a, b + 1) - a) / (b - a)
        out.append(np.column_stack([np.interp(grid, s, values[a:b + 1, k])
                                    for k in range(values.shape[1])]))
    return np.asarray(out).reshape(-1, SAMPLES, values.shape[1])


def _cycle_kinds(strike_times: np.ndarray, steps: FootstepTable) -> list[CycleKind]:
    """Level / stairs_up / stairs_down / other for each cycle, from the step heights of the
    footholds placed within it (``footsteps.csv`` rows of this agent)."""
    kinds = []
    for t0, t1 in zip(strike_times[:-1], strike_times[1:], strict=True):
        h = steps.step_height[(steps.time > t0 - 0.02) & (steps.time <= t1 + 0.02)]
        if h.size and np.all(np.abs(h) < 0.02):
            kinds.append(LEVEL)
        elif h.size and np.all(h > 0.08):
            kinds.append(STAIRS_UP)
        elif h.size and np.all(h < -0.08):
            kinds.append(STAIRS_DOWN)
        else:
            kinds.append(OTHER)
    return kinds


# --- the figures ---------------------------------------------------------------------------


def second_differences(points: np.ndarray, fps: float) -> np.ndarray:
    """|p[i+1] − 2 p[i] + p[i−1]| (F−2,) [m] of ``points`` (F, 3), rescaled to 25 fps."""
    d2 = np.linalg.norm(points[2:] - 2 * points[1:-1] + points[:-2], axis=1)
    return d2 * (25.0 / fps) ** 2


def heel_slides(track: WalkerTrack, side: int, *, tolerance: float = 0.005
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per stance of one foot: horizontal slide [m] of the planted heel or ball (the larger)
    while it is within ``tolerance`` [m] of its lowest height in that stance, the foot's
    yaw change [deg] while the ball is planted, and while the heel is (a turn that is not
    on the ball). Shapes (n_stances,).

    The yaw is ``track.foot_yaw`` (the written joint rotations) where the track has it;
    a track of positions only falls back to the heel -> toe direction, which flips by 180°
    once the foot is plantarflexed past vertical at push-off.
    """
    pts = foot_points(track, side)
    if track.foot_yaw is not None:
        yaw_all = np.asarray(track.foot_yaw, float)[:, side]
    else:
        f_all = pts["toe"] - pts["heel"]
        yaw_all = np.unwrap(np.arctan2(f_all[:, 1], f_all[:, 0]))
    slides, turns, heel_turns = [], [], []
    for a, b in stance_runs(track.contact[:, side]):
        worst = 0.0
        for name in ("heel", "ball"):
            p = pts[name][a:b]
            down = p[:, 2] <= p[:, 2].min() + tolerance
            q = p[down, :2]
            worst = max(worst, float(np.linalg.norm(q - q[0], axis=1).max()))
        down = pts["ball"][a:b, 2] <= pts["ball"][a:b, 2].min() + tolerance
        yaw = yaw_all[a:b]
        heel = pts["heel"][a:b, 2] <= pts["heel"][a:b, 2].min() + tolerance
        slides.append(worst)
        turns.append(float(np.rad2deg(np.ptp(yaw[down]))))
        heel_turns.append(float(np.rad2deg(np.ptp(yaw[heel]))))
    return np.asarray(slides), np.asarray(turns), np.asarray(heel_turns)


def swing_clearance(track: WalkerTrack, side: int, ground) -> tuple[np.ndarray, np.ndarray]:
    """Per swing of one foot: the toe tip's lowest height above the ground [m] in the middle
    third of the swing, and the whole sole's highest lowest-point [m] (how far the sole is
    lifted). ``ground(xy (n, 2)) -> z (n,)``. Shapes (n_swings,)."""
    pts = foot_points(track, side)
    gap = {k: v[:, 2] - ground(v[:, :2]) for k, v in pts.items()}
    sole = np.minimum(np.minimum(gap["heel"], gap["ball"]), gap["toe"])
    toe_min, lift = [], []
    for a, b in stance_runs(~track.contact[:, side]):
        if a == 0 or b == len(track.time) or b - a < 6:
            continue  # incomplete swing at either end of the track
        third = (b - a) // 3
        toe_min.append(float(gap["toe"][a + third:b - third].min()))
        lift.append(float(sole[a:b].max()))
    return np.asarray(toe_min), np.asarray(lift)


def _sole_samples(pts: dict[str, np.ndarray], count: int) -> np.ndarray:
    """Points (F, count, 3) [m] evenly along the sole, heel -> ball -> toe tip (a segment
    heel-ball, then ball-toe, split by their lengths)."""
    heel, ball, toe = pts["heel"], pts["ball"], pts["toe"]
    hb = np.linalg.norm(ball - heel, axis=1)
    bt = np.linalg.norm(toe - ball, axis=1)
    u = np.linspace(0.0, 1.0, count)[None, :] * (hb + bt)[:, None]  # (F, q) arc length
    w1 = np.clip(u / np.maximum(hb, 1e-9)[:, None], 0.0, 1.0)[..., None]
    w2 = np.clip((u - hb[:, None]) / np.maximum(bt, 1e-9)[:, None], 0.0, 1.0)[..., None]
    return heel[:, None] + w1 * (ball - heel)[:, None] + w2 * (toe - ball)[:, None]


def edge_clearance(track: WalkerTrack, side: int, ground, *, edge: float = 0.05,
                   samples: int = 27, substeps: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """How one foot passes and rests on step edges (stair nosings, curbs).

    The sole is sampled heel -> toe tip every ~1 cm and, in swing (the frames without
    contact), between frames (``substeps`` linear in-betweens). A sole *spans an edge*
    where the ground under it varies by more than ``edge`` [m].

    Returns
    -------
    clearance : (n_swings,) [m]
        Per complete swing, the sole's lowest height above the ground over the frames in
        which it spans an edge (the clearance over the nosing: the samples beyond the edge
        see the tread top); NaN for a swing that spans no edge. Negative: the foot cuts
        through the edge.
    across : (n_stances,) bool
        Per stance, the planted foot rests across an edge at mid-stance.
    """
    pts = foot_points(track, side)
    sole = _sole_samples(pts, samples)  # (F, q, 3)
    f = np.linspace(0.0, 1.0, substeps + 1)[:-1]
    clearance = []
    for a, b in stance_runs(~track.contact[:, side]):
        if a == 0 or b == len(track.time) or b - a < 2:
            continue
        seg = sole[a:b]  # swing frames only (in push-off the toes bend: not rigid)
        fine = (seg[:-1, None] * (1 - f)[None, :, None, None]
                + seg[1:, None] * f[None, :, None, None]).reshape(-1, samples, 3)
        g = np.asarray(ground(fine[..., :2].reshape(-1, 2)), float).reshape(fine.shape[:2])
        spans = np.ptp(g, axis=1) > edge
        clearance.append(float((fine[..., 2] - g)[spans].min()) if spans.any() else np.nan)
    across = []
    for a, b in stance_runs(track.contact[:, side]):
        mid = sole[(a + b) // 2]
        g = np.asarray(ground(mid[:, :2]), float)
        across.append(bool(np.ptp(g) > edge))
    return np.asarray(clearance), np.asarray(across, bool)


@cache
def references() -> dict:
    """The shipped joint-angle references (``crowdwalk/data/joint_references.json``)."""
    text = resources.files("crowdwalk").joinpath("data", "joint_references.json").read_text()
    return json.loads(text)


def winter_at(cadence: float) -> tuple[np.ndarray, np.ndarray]:
    """Winter's hip/knee/ankle mean and SD (3, SAMPLES) [deg], linearly interpolated by
    cadence [steps/min] between the slow, natural and fast groups (clamped)."""
    w = references()["winter"]
    names = ("slow", "natural", "fast")
    cad = np.array([w["cadence_steps_per_min"][n] for n in names])
    mean = np.array([[w[n][j]["mean"] for j in ("hip", "knee", "ankle")] for n in names])
    sd = np.array([[w[n][j]["sd"] for j in ("hip", "knee", "ankle")] for n in names])
    c = float(np.clip(cadence, cad[0], cad[-1]))
    k = min(int(np.searchsorted(cad, c, side="right")) - 1, 1)
    u = (c - cad[k]) / (cad[k + 1] - cad[k])
    return (1 - u) * mean[k] + u * mean[k + 1], (1 - u) * sd[k] + u * sd[k + 1]


def _rms_r(curve: np.ndarray, ref: np.ndarray) -> tuple[float, float]:
    return float(np.sqrt(np.mean((curve - ref) ** 2))), float(np.corrcoef(curve, ref)[0, 1])


@dataclass(frozen=True)
class GaitFigures:
    """One walker's gait figures (NaN where the run has no such cycles).

    Lengths [m], speeds [m/s], angles [deg], cadence [steps/min]; ``*_z`` are z-scores
    against the WBDS relation at the achieved speed; ``joint_rms``/``joint_r`` (3,) hip,
    knee, ankle vs Winter at the walker's level cadence; ``level_curves`` (3, SAMPLES).
    """

    agent: int
    body_height: float
    free_speed: float
    speed: float
    step_length: float
    step_length_z: float
    cadence: float
    cadence_z: float
    joint_rms: np.ndarray
    joint_r: np.ndarray
    level_curves: np.ndarray
    knee_at_strike: float
    toe_off_plantarflexion: float
    pelvis_excursion: float
    heel_slide_max: float
    stances_over_10mm: int
    stances_turning_over_10deg: int
    heel_down_turn_max: float
    spins_over_10deg: int
    stances: int
    pelvis_d2_max: float
    foot_d2_level: float
    foot_d2_other: float
    stairs_up_knee_rms: float
    stairs_up_knee_peak: float
    stairs_down_knee_rms: float
    stairs_down_knee_peak: float
    toe_drag_fraction: float
    high_lift_fraction: float
    swings: int
    stairs_up_knee_stance_rms: float = float("nan")
    stairs_down_knee_stance_rms: float = float("nan")
    edge_swings: int = 0
    edge_clearance_min: float = float("nan")
    edge_clearance_median: float = float("nan")
    edge_clearance_max: float = float("nan")
    stances_across_edge: int = 0
    pelvic_list_peak: float = float("nan")
    pelvic_list_peak_phase: float = float("nan")
    pelvic_list_mid_stance: float = float("nan")
    pelvic_rotation_at_strike: float = float("nan")
    trunk_rotation_at_strike: float = float("nan")


def pelvis_list_rotation(track: WalkerTrack, joints=None) -> np.ndarray:
    """Pelvic list and rotation (F, 2) [deg] of the left side from the hip joints (or the
    left/right ``joints`` pair, e.g. the shoulders): list + left above the right,
    rotation + left ahead along the pelvis's path (its displacement over ±0.5 s), Bovi
    2011's signs for the left leg."""
    p = track.positions
    left, right = (LEG_JOINTS[0, 0], LEG_JOINTS[1, 0]) if joints is None else joints
    axis = p[:, left] - p[:, right]
    flat = np.linalg.norm(axis[:, :2], axis=1)
    lst = np.arctan2(axis[:, 2], flat)
    pelvis = p[:, _PELVIS, :2]
    k = max(int(round(0.5 * track.fps)), 1)
    idx = np.arange(len(p))
    way = pelvis[np.minimum(idx + k, len(p) - 1)] - pelvis[np.maximum(idx - k, 0)]
    # left hip ahead: the axis (left - right) turned toward the way walked
    rot = np.arctan2(np.einsum("fi,fi->f", axis[:, :2], way) / np.maximum(flat, 1e-12),
                     np.abs(way[:, 0] * axis[:, 1] - way[:, 1] * axis[:, 0])
                     / np.maximum(flat, 1e-12))
    return np.rad2deg(np.column_stack([lst, rot]))


def gait_figures(track: WalkerTrack, steps: FootstepTable, *, free_speed: float,
                 ground, skip_cycles: int = 2) -> GaitFigures:
    """Measure one walker.

    Parameters
    ----------
    track : WalkerTrack
        The walker's stored poses.
    steps : crowdwalk.steps.FootstepTable
        This walker's ``footsteps.csv`` rows (columns ``time``, ``step_length``,
        ``step_height``).
    free_speed : float
        Requested free speed [m/s].
    ground : callable
        ``ground(xy (n, 2)) -> z (n,)`` [m], the run's terrain height.
    skip_cycles : int
        Cycles after the start left out of the level figures (acceleration).
    """
    from planners import normal_mode

    nan = float("nan")
    strikes = np.array([a for a, _ in stance_runs(track.contact[:, 0])][1:], dtype=int)
    kinds = _cycle_kinds(track.time[strikes], steps) if strikes.size > 1 else []
    angles = sagittal_angles(track, 0)
    curves = cycle_curves(angles, strikes) if strikes.size > 1 else np.zeros((0, SAMPLES, 3))
    kinds_arr = np.array(kinds, dtype=object)
    level = np.flatnonzero(kinds_arr == LEVEL)
    level = level[level >= skip_cycles] if (level >= skip_cycles).sum() >= 2 else level
    pelvis = track.positions[:, _PELVIS]

    speed = step_length = cadence = excursion = nan
    rms = r = np.full(3, nan)
    mean_curve = np.full((3, SAMPLES), nan)
    if level.size:
        a, b = strikes[level], strikes[level + 1]
        duration = float(np.sum(track.time[b] - track.time[a]))
        speed = float(np.sum(np.linalg.norm(pelvis[b, :2] - pelvis[a, :2], axis=1)) / duration)
        cadence = 120.0 * level.size / duration
        in_level = np.zeros(steps.time.shape, bool)
        for t0, t1 in zip(track.time[a], track.time[b], strict=True):
            in_level |= (steps.time > t0 + 0.02) & (steps.time <= t1 + 0.02)
        step_length = float(np.median(steps.step_length[in_level]))
        mean_curve = curves[level].mean(axis=0).T
        ref, _ = winter_at(cadence)
        rms, r = (np.array(v) for v in zip(*(_rms_r(mean_curve[j], ref[j]) for j in range(3)),
                                           strict=True))
        excursion = float(np.median([np.ptp(pelvis[strikes[k]:strikes[k + 1] + 1, 2])
                                     for k in level]))
    leg = float(normal_mode.leg_length_from_height(track.body_height))
    sl_z = cad_z = nan
    if np.isfinite(speed):
        sl_z = (step_length - float(normal_mode.step_length(speed, leg))) / (
            normal_mode.RESIDUAL_SD * leg)
        cad_z = (cadence / 60.0 - float(normal_mode.step_frequency(speed, leg))) / (
            normal_mode.CADENCE_RESIDUAL_SD)

    stair = {}
    stance = np.linspace(0.0, 1.0, SAMPLES) <= STAIR_STANCE
    for kind in (STAIRS_UP, STAIRS_DOWN):
        idx = np.flatnonzero(kinds_arr == kind)
        if idx.size:
            knee = curves[idx, :, 1].mean(axis=0)
            ref = np.asarray(references()["bovi"][kind]["knee"]["mean"])
            stair[kind] = (float(np.sqrt(np.mean((knee - ref) ** 2))), float(knee.max()),
                           float(np.sqrt(np.mean((knee - ref)[stance] ** 2))))
        else:
            stair[kind] = (nan, nan, nan)

    slides, turns, heel_turns = (np.concatenate(v) for v in zip(
        *(heel_slides(track, s) for s in (0, 1)), strict=True))
    spins = np.abs(steps.spin)  # NaN (no spin turn) in runs written before MetaGait
    toe, lift = (np.concatenate(v) for v in zip(*(swing_clearance(track, s, ground)
                                                  for s in (0, 1)), strict=True))
    over, across = (np.concatenate(v) for v in zip(*(edge_clearance(track, s, ground)
                                                     for s in (0, 1)), strict=True))
    over = over[np.isfinite(over)]
    # Foot second differences on level cycles vs everywhere else.
    on_level = np.zeros(len(track.time), bool)
    for k in level:
        on_level[strikes[k]:strikes[k + 1] + 1] = True
    d2_feet = np.maximum(*(second_differences(track.positions[:, LEG_JOINTS[s, 2]], track.fps)
                           for s in (0, 1)))
    inner = on_level[1:-1]
    return GaitFigures(
        agent=track.agent, body_height=track.body_height, free_speed=free_speed, speed=speed,
        step_length=step_length, step_length_z=sl_z, cadence=cadence, cadence_z=cad_z,
        joint_rms=rms, joint_r=r, level_curves=mean_curve,
        knee_at_strike=float(mean_curve[1, 0]) if level.size else nan,
        toe_off_plantarflexion=float(-mean_curve[2, 25:45].min()) if level.size else nan,
        pelvis_excursion=excursion,
        heel_slide_max=float(slides.max()) if slides.size else nan,
        stances_over_10mm=int((slides > 0.010).sum()),
        stances_turning_over_10deg=int((turns > 10.0).sum()),
        heel_down_turn_max=float(heel_turns.max()) if heel_turns.size else nan,
        spins_over_10deg=int((spins > np.deg2rad(10.0)).sum()), stances=int(slides.size),
        pelvis_d2_max=float(second_differences(pelvis, track.fps).max()),
        foot_d2_level=float(d2_feet[inner].max()) if inner.any() else nan,
        foot_d2_other=float(d2_feet[~inner].max()) if (~inner).any() else nan,
        stairs_up_knee_rms=stair[STAIRS_UP][0], stairs_up_knee_peak=stair[STAIRS_UP][1],
        stairs_down_knee_rms=stair[STAIRS_DOWN][0],
        stairs_down_knee_peak=stair[STAIRS_DOWN][1],
        toe_drag_fraction=float((toe < 0.002).mean()) if toe.size else nan,
        high_lift_fraction=float((lift > 0.09).mean()) if lift.size else nan,
        swings=int(toe.size),
        stairs_up_knee_stance_rms=stair[STAIRS_UP][2],
        stairs_down_knee_stance_rms=stair[STAIRS_DOWN][2],
        edge_swings=int(over.size),
        edge_clearance_min=float(over.min()) if over.size else nan,
        edge_clearance_median=float(np.median(over)) if over.size else nan,
        edge_clearance_max=float(over.max()) if over.size else nan,
        stances_across_edge=int(across.sum()),
        **_pelvis_figures(track, strikes, level),
    )


def _pelvis_figures(track: WalkerTrack, strikes: np.ndarray, level: np.ndarray) -> dict:
    """Mean left-cycle pelvic list / rotation figures over the level cycles [deg]: list
    peak, its phase [1], list at 30-45 % (mid to late stance), rotation at heel strike."""
    if not level.size:
        return {}
    curves = cycle_curves(pelvis_list_rotation(track), strikes)[level].mean(axis=0)
    shoulders = cycle_curves(pelvis_list_rotation(track, (JOINT["l_shoulder"],
                                                          JOINT["r_shoulder"])),
                             strikes)[level].mean(axis=0)
    grid = np.linspace(0.0, 1.0, SAMPLES)
    first = grid < 0.5
    peak = int(np.argmax(np.abs(curves[first, 0])))
    late = (grid >= 0.30) & (grid <= 0.45)
    return {"pelvic_list_peak": float(abs(curves[peak, 0])),
            "pelvic_list_peak_phase": float(grid[peak]),
            "pelvic_list_mid_stance": float(np.abs(curves[late, 0]).max()),
            "pelvic_rotation_at_strike": float(0.5 * (curves[0, 1] + curves[-1, 1])),
            "trunk_rotation_at_strike": float(0.5 * (shoulders[0, 1] + shoulders[-1, 1]))}


def run_figures(run_dir: str | Path) -> list[GaitFigures]:
    """Gait figures of every walker with stored poses in a run folder."""
    from crowdwalk.record import open_run
    from crowdwalk.scenario import load_scenario
    from crowdwalk.world import build_world

    run = open_run(run_dir)
    poses = run.poses()
    if poses is None:
        raise ValueError(f"{run.poses_path}: no poses stored; run with outputs.poses: true.")
    terrain = build_world(load_scenario(run.scenario_path)).terrain
    steps = run.footsteps()
    free = {a["id"]: a["free_speed_m_s"] for a in run.summary.get("agents", [])}
    tracks = load_tracks(poses)
    poses.close()
    out = []
    for agent, track in sorted(tracks.items()):
        mine = steps.of_agent(agent)
        out.append(gait_figures(track, mine, free_speed=float(free.get(agent, np.nan)),
                                ground=terrain.height))
    return out


_ROWS = (  # (figure, target, values of one walker, format of those values)
    ("body height [m]", "", lambda f: (f.body_height,), "{:.2f}"),
    ("free / achieved speed [m/s] (%)", "within 5 %",
     lambda f: (f.free_speed, f.speed, (f.speed / f.free_speed - 1) * 100),
     "{:.2f}/{:.2f} ({:+.0f})"),
    ("step length [m] (z vs WBDS)", "|z| <= 2", lambda f: (f.step_length, f.step_length_z),
     "{:.3f} ({:+.1f})"),
    ("cadence [/min] (z vs WBDS)", "|z| <= 2", lambda f: (f.cadence, f.cadence_z),
     "{:.0f} ({:+.1f})"),
    ("hip RMS [deg] / r vs Winter", "<= 5 / >= 0.95", lambda f: (f.joint_rms[0], f.joint_r[0]),
     "{:.1f} / {:.3f}"),
    ("knee RMS [deg] / r", "<= 5 / >= 0.95", lambda f: (f.joint_rms[1], f.joint_r[1]),
     "{:.1f} / {:.3f}"),
    ("ankle RMS [deg] / r", "<= 5 / >= 0.95", lambda f: (f.joint_rms[2], f.joint_r[2]),
     "{:.1f} / {:.3f}"),
    ("knee at heel strike [deg]", "0-5", lambda f: (f.knee_at_strike,), "{:.1f}"),
    ("toe-off plantarflexion [deg]", "~15-20", lambda f: (f.toe_off_plantarflexion,), "{:.1f}"),
    ("pelvis vertical excursion [cm]", "3.5-5.5 (1.33 m/s)",
     lambda f: (f.pelvis_excursion * 100,), "{:.1f}"),
    ("pelvic list peak [deg] at [% cycle]; 30-45 %", "Bovi ~5 at ~15; ~0",
     lambda f: (f.pelvic_list_peak, f.pelvic_list_peak_phase * 100, f.pelvic_list_mid_stance),
     "{:.1f} at {:.0f}; {:.1f}"),
    ("pelvic / shoulder rotation at heel strike [deg]", "Bovi ~4; Schwartz ~-5",
     lambda f: (f.pelvic_rotation_at_strike, f.trunk_rotation_at_strike), "{:.1f} / {:.1f}"),
    ("heel slide max [mm]; stances > 10 mm", "<= 10; 0",
     lambda f: (f.heel_slide_max * 1000, f.stances_over_10mm, f.stances), "{:.0f}; {:.0f}/{:.0f}"),
    ("stances turning > 10 deg; spin turns > 10 deg", "spin turns only",
     lambda f: (f.stances_turning_over_10deg, f.stances, f.spins_over_10deg),
     "{:.0f}/{:.0f}; {:.0f}"),
    ("stance turn with the heel down max [deg]", "0 (on the ball)",
     lambda f: (f.heel_down_turn_max,), "{:.1f}"),
    ("pelvis 2nd difference max [cm]", "<= 2", lambda f: (f.pelvis_d2_max * 100,), "{:.1f}"),
    ("foot 2nd diff level / elsewhere [cm] (x)", "elsewhere <= 1.5 x level",
     lambda f: (f.foot_d2_level * 100, f.foot_d2_other * 100,
                f.foot_d2_other / f.foot_d2_level), "{:.1f} / {:.1f} ({:.2f})"),
    ("stairs up knee RMS vs Bovi / peak [deg]", "<= 10 / ~68",
     lambda f: (f.stairs_up_knee_rms, f.stairs_up_knee_peak), "{:.1f} / {:.0f}"),
    ("  ... RMS over 0-60 % (stance) [deg]", "<= 10",
     lambda f: (f.stairs_up_knee_stance_rms,), "{:.1f}"),
    ("stairs down knee RMS vs Bovi / peak", "<= 10 / ~95",
     lambda f: (f.stairs_down_knee_rms, f.stairs_down_knee_peak), "{:.1f} / {:.0f}"),
    ("  ... RMS over 0-60 % (stance) [deg]", "<= 10",
     lambda f: (f.stairs_down_knee_stance_rms,), "{:.1f}"),
    ("sole over an edge min/median/max [cm]", "0 .. margin + 5",
     lambda f: (f.edge_clearance_min * 100, f.edge_clearance_median * 100,
                f.edge_clearance_max * 100, f.edge_swings),
     "{:.1f}/{:.1f}/{:.1f} ({:.0f} swings)"),
    ("stances across an edge", "0", lambda f: (f.stances_across_edge, f.stances),
     "{:.0f}/{:.0f}"),
    ("swings: toe < 2 mm mid-swing [%]", "<= 1 %",
     lambda f: (f.toe_drag_fraction * 100, f.swings), "{:.0f} % of {:.0f}"),
    ("swings: whole sole > 9 cm [%]", "", lambda f: (f.high_lift_fraction * 100,), "{:.0f}"),
)


def report_table(figures: list[GaitFigures], *, max_columns: int = 4) -> str:
    """The figures as a text table with the issue's targets: one column per walker, or
    (more than ``max_columns`` walkers) the median, min and max over walkers."""
    if len(figures) <= max_columns:
        header = [f"agent {f.agent}" for f in figures]
        cells = [[fmt.format(*get(f)) for f in figures] for _, _, get, fmt in _ROWS]
    else:
        header = [f"median of {len(figures)}", "min", "max"]
        cells = []
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # rows without such cycles
            for _, _, get, fmt in _ROWS:
                values = np.array([get(f) for f in figures], dtype=float)
                cells.append([fmt.format(*agg(values, axis=0))
                              for agg in (np.nanmedian, np.nanmin, np.nanmax)])
    table = [["figure", "target", *header]]
    table += [[name, target, *row] for (name, target, _, _), row in zip(_ROWS, cells, strict=True)]
    widths = [max(len(row[k]) for row in table) for k in range(len(table[0]))]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip()
                     for row in table)


def plot_curves(figures: list[GaitFigures], path: str | Path) -> Path:
    """Hip, knee, ankle level-cycle curves of each walker with Winter's band at its
    cadence; writes a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.linspace(0, 100, SAMPLES)
    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    for f in figures:
        if not np.isfinite(f.cadence):
            continue
        ref, sd = winter_at(f.cadence)
        for j, ax in enumerate(axes):
            line, = ax.plot(t, f.level_curves[j], label=f"agent {f.agent} {f.speed:.2f} m/s")
            ax.fill_between(t, ref[j] - sd[j], ref[j] + sd[j], color=line.get_color(),
                            alpha=0.15)
            ax.plot(t, ref[j], "--", color=line.get_color(), lw=0.8)
    for ax, name in zip(axes, ("hip flexion", "knee flexion", "ankle dorsiflexion"),
                        strict=True):
        ax.set(title=name, xlabel="% stride (left heel strike)", ylabel="deg")
    axes[0].legend(fontsize=7)
    fig.suptitle("run (solid) vs Winter 1991 at the same cadence (dashed, ±1 SD)")
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
