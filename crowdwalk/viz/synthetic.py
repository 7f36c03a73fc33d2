"""A synthetic walking crowd for benchmarks, tests and demos of the viewer.

Agents walk straight lines at constant speed with a sinusoidal leg and arm swing on a
the 20-joint H-Anim skeleton of ``crowdwalk.body``. This is not a gait
model — real runs carry MetaGait/ElevWalker poses — it only produces poses and
footsteps whose positions are known exactly, so render tests can check where agents and
footprints appear and the benchmark can time a 1,000-agent frame without running a
simulation.
"""

from __future__ import annotations

import numpy as np

from crowdwalk.body import JOINT_NAMES, PARENTS
from crowdwalk.errors import invalid
from crowdwalk.viz.footprints import Footsteps
from crowdwalk.viz.sources import ArrayPoses

__all__ = ["SKELETON_NAMES", "SKELETON_PARENTS", "synthetic_crowd", "walking_pose"]

SKELETON_NAMES = JOINT_NAMES
SKELETON_PARENTS = PARENTS

# Body-frame joint positions at rest [m] for a 1.75 m person: x forward, y left, z up,
# origin on the ground below the pelvis.
_REST = np.array([
    [0.0, 0.0, 0.95], [0.0, 0.0, 0.95],
    [0.0, 0.09, 0.92], [0.0, 0.09, 0.50], [0.0, 0.09, 0.08], [0.0, 0.09, 0.08],
    [0.128, 0.09, 0.012],
    [0.0, -0.09, 0.92], [0.0, -0.09, 0.50], [0.0, -0.09, 0.08], [0.0, -0.09, 0.08],
    [0.128, -0.09, 0.012],
    [0.0, 0.0, 1.04], [0.0, 0.0, 1.55],
    [0.0, 0.19, 1.45], [0.0, 0.21, 1.16], [0.0, 0.22, 0.90],
    [0.0, -0.19, 1.45], [0.0, -0.21, 1.16], [0.0, -0.22, 0.90],
])  # fmt: skip


def _swing(points: np.ndarray, pivot: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotate body-frame points (n, m, 3) about the y axis through pivot (n, 1, 3) by angle
    (n, 1) [rad]."""
    c, s = np.cos(angle), np.sin(angle)
    d = points - pivot
    x = pivot[..., 0] + c * d[..., 0] + s * d[..., 2]
    z = pivot[..., 2] - s * d[..., 0] + c * d[..., 2]
    return np.stack([x, np.broadcast_to(points[..., 1], x.shape), z], axis=-1)


def walking_pose(phase: np.ndarray, amplitude: float = 0.4) -> np.ndarray:
    """Body-frame joint positions (n, 20, 3) [m] at gait phases ``phase`` (n,) [rad].

    The left leg swings forward by ``amplitude`` [rad] at phase π/2, the right leg and the
    left arm in opposition; knees bend in the swing half of the cycle.
    """
    phase = np.asarray(phase, dtype=float)
    pose = np.broadcast_to(_REST, phase.shape + _REST.shape).copy()
    for side, sign in ((0, 1.0), (1, -1.0)):
        hip, knee, ankle = (2, 3, 4) if side == 0 else (7, 8, 9)
        leg = slice(knee, knee + 4)
        thigh = sign * amplitude * np.sin(phase)
        bend = 0.6 * np.clip(sign * np.cos(phase), 0.0, None)
        pose[:, leg] = _swing(pose[:, leg], pose[:, hip][:, None], thigh[:, None])
        shank = slice(ankle, ankle + 3)
        pose[:, shank] = _swing(pose[:, shank], pose[:, knee][:, None], (thigh - bend)[:, None])
        arm = slice(15, 17) if side == 0 else slice(18, 20)
        shoulder = 14 if side == 0 else 17
        pose[:, arm] = _swing(pose[:, arm], pose[:, shoulder][:, None], -thigh[:, None] * 0.8)
    return pose


def synthetic_crowd(
    n_agents: int,
    duration: float = 4.0,
    fps: float = 25.0,
    area: tuple[float, float] = (60.0, 40.0),
    speed: float = 1.3,
    seed: int = 0,
) -> tuple[ArrayPoses, Footsteps]:
    """Poses and footsteps of ``n_agents`` walking straight lines on flat ground (z = 0).

    Parameters
    ----------
    n_agents : int
        Number of agents.
    duration : float
        Simulated time [s].
    fps : float
        Output frame rate [1/s].
    area : (float, float)
        Extent in x and y of the start positions [m].
    speed : float
        Walking speed [m/s].
    seed : int
        Seed of the random start positions, headings and phases.

    Returns
    -------
    (ArrayPoses, Footsteps)
        Frames at ``arange(0, duration, 1/fps)``; footsteps every half stride.
    """
    if n_agents < 1:
        raise invalid("synthetic_crowd", "n_agents", ">= 1", n_agents)
    if not duration > 0 or not fps > 0:
        raise invalid("synthetic_crowd", "duration", "> 0 [s] with fps > 0 [1/s]",
                      (duration, fps))
    rng = np.random.default_rng(seed)
    start = rng.uniform([0.0, 0.0], area, size=(n_agents, 2))
    heading = rng.uniform(-np.pi, np.pi, n_agents)
    phase0 = rng.uniform(0, 2 * np.pi, n_agents)
    direction = np.column_stack([np.cos(heading), np.sin(heading)])
    cadence = speed / 0.7  # steps per second for a 0.7 m step
    rot = np.stack([np.stack([direction[:, 0], -direction[:, 1]], -1),
                    np.stack([direction[:, 1], direction[:, 0]], -1)], axis=1)  # (n, 2, 2)
    times = np.arange(0.0, duration, 1.0 / fps)
    ids = np.arange(n_agents)
    positions = []
    for t in times:  # frames, not agents: every frame is one batched call
        body = walking_pose(phase0 + np.pi * cadence * t)
        centre = start + speed * t * direction
        xy = np.einsum("nij,nkj->nki", rot, body[:, :, :2]) + centre[:, None]
        positions.append(np.concatenate([xy, body[:, :, 2:]], axis=-1))
    poses = ArrayPoses(times, [ids] * len(times), positions, SKELETON_PARENTS, SKELETON_NAMES)

    step_times = np.arange(0.0, duration, 1.0 / cadence)
    agent = np.repeat(ids, len(step_times))
    t = np.tile(step_times, n_agents)
    k = np.tile(np.arange(len(step_times)), n_agents)
    lateral = np.where(k % 2 == 0, 0.09, -0.09)
    along = start[agent] + speed * t[:, None] * direction[agent]
    normal = np.column_stack([-direction[agent, 1], direction[agent, 0]])
    xy = along + lateral[:, None] * normal
    energy = 40.0 + 10.0 * np.sin(0.1 * xy[:, 0]) + rng.normal(0.0, 1.0, len(t))
    planner = np.where(agent % 2 == 0, "best_first", "fixed")
    steps = Footsteps(agent, t, np.column_stack([xy, np.zeros(len(t))]), energy, planner,
                      heading[agent])
    return poses, steps
