"""MetaGait: step parameters from a path and the terrain (Sun & Metaxas 2001, §6).

At each heel strike MetaGait decides, for a batch of agents, the next step's heading ψ,
toe-out, spin turn, step length and step height, and returns them as a
:class:`~crowdwalk.gait.animator.StepCommand` for the Animator:

- **Path following (§6.1).** ``p0`` is the point of the path closest to the agent, ``p1``
  the point one step further along it; ψ is the direction of ``d = p1 − p0`` (the paper's
  ``atan2(−d_z, d_x)`` in its y-up frame is ``atan2(d_y, d_x)`` in ours, z up).
- **Toe-out and spin turns (§6.1).** With ``d'`` the direction one step later, a turn
  ``Δ`` beyond ``T`` (45°) adds ``Δ − T`` of toe-out toward the turn, at most ``T2`` (25°);
  the rest, ``Δ − T − T2``, is a spin turn on the stance foot when the next step begins.
- **Maximum step length (§6.1).** The step length is reduced by a fixed amount until the
  heading changes by less than ``Δψ_thresh`` over one gait cycle.
- **Uneven terrain (§6.2, Eqs. 11–12).** Predict the landing point, read the ground there,
  take the preferred step length for that slope (Sun et al. 1996, scaled to the agent's
  level step length), cap it at the maximum, and repeat.
- **With a footstep planner** the planner's step length and height are used as given
  (they are legal footholds); heading, toe-out and spin still follow the path.
- **In the crowd** (:meth:`MetaGait.orient`, called by the simulation for every step it
  decides) the planner and the steering own where each foot lands, so ψ is the step's
  direction (p0 the stance foot, p1 the planned foothold); MetaGait decides the landing
  foot's toe-out from the turn predicted for the next step and the spin turn of the
  stance foot (:func:`orient_steps`). Of a turn ahead the inside foot takes the toe-out
  and the outside foot steps straight (Chen & Li 2003, §5.4).

Paths are batched as (n, m, 2) polylines [m] (resample per agent to a common m).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from crowdwalk.errors import invalid
from crowdwalk.gait.foot import wrap_angle

__all__ = [
    "MetaGaitConfig",
    "MetaGait",
    "StepTurn",
    "orient_steps",
    "preferred_step_for_slope",
    "path_point",
    "closest_arc_length",
    "level_step_length",
    "animate_paths",
]


@dataclass(frozen=True)
class MetaGaitConfig:
    """Parameters of MetaGait (§6).

    Attributes
    ----------
    toe_out_threshold : float
        T: heading change between this step and the next that triggers toe-out [rad]
        (paper: 45°).
    toe_out_limit : float
        T2: largest toe-out adjustment; the excess becomes a spin turn [rad] (paper: 25°).
    max_heading_change : float
        Δψ_thresh: largest heading change per gait cycle (two steps) [rad]; the paper
        gives no value, 45° is used.
    step_reduction : float
        Fixed amount by which the step length is reduced while searching SL_max [m].
    min_step_length : float
        Shortest step MetaGait asks for [m].
    terrain_iterations : int
        Passes of the uneven-terrain loop (§6.2).
    step_width : float
        Lateral distance between the left and right foot lines, fraction of body
        height [1] (matches ``GaitStyle.step_width``).
    """

    toe_out_threshold: float = float(np.deg2rad(45.0))
    toe_out_limit: float = float(np.deg2rad(25.0))
    max_heading_change: float = float(np.deg2rad(45.0))
    step_reduction: float = 0.02
    min_step_length: float = 0.15
    terrain_iterations: int = 4
    step_width: float = 0.05

    def __post_init__(self) -> None:
        owner = "MetaGaitConfig"
        for name in ("toe_out_threshold", "toe_out_limit", "max_heading_change"):
            value = getattr(self, name)
            if not (np.isfinite(value) and 0 <= value <= np.pi):
                raise invalid(owner, name, "in [0, π] [rad]", value)
        for name in ("step_reduction", "min_step_length"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise invalid(owner, name, "finite and > 0 [m]", value)
        if self.terrain_iterations < 1:
            raise invalid(owner, "terrain_iterations", ">= 1", self.terrain_iterations)
        if not (np.isfinite(self.step_width) and self.step_width >= 0):
            raise invalid(owner, "step_width", "finite and >= 0 [1]", self.step_width)


@dataclass(frozen=True, eq=False)
class StepTurn:
    """MetaGait's orientation of k steps (§6.1).

    Attributes
    ----------
    toe_out : (k,) toe-out of the landing (swing) foot from the step's heading ψ,
        outward positive [rad].
    spin : (k,) spin turn of the stance foot about its ball during the step,
        counter-clockwise positive [rad].
    landing_yaw : (k,) direction the landing foot points, from +x [rad].
    """

    toe_out: np.ndarray
    spin: np.ndarray
    landing_yaw: np.ndarray


def orient_steps(*, heading: np.ndarray, heading_next: np.ndarray, stance_yaw: np.ndarray,
                 swing_left: np.ndarray, base_toe_out: np.ndarray,
                 config: MetaGaitConfig) -> StepTurn:
    """Toe-out and spin turn of k steps from their headings (§6.1, with §5.4 of Chen & Li).

    Parameters
    ----------
    heading : (k,) ψ of this step (direction of d = p1 − p0) [rad].
    heading_next : (k,) ψ expected for the step after it (d') [rad].
    stance_yaw : (k,) direction the stance foot points now [rad].
    swing_left : (k,) bool, the left foot swings.
    base_toe_out : (k,) the walker's toe-out on a straight path [rad].
    config : MetaGaitConfig

    Notes
    -----
    - *Spin turn*, when the step begins: ψ may turn at most T from the stance foot's own
      walking direction (its yaw less its toe-out); the rest, ``|twist| − T``, is spun on
      the ball of the stance foot. With the toe-out rule below this is the paper's
      ``Δ − T − T2``: the toe-out of the previous step took ``T2`` of a turn ``Δ`` and the
      spin the rest beyond ``T``. Here Δ is the turn the crowd actually decided (known
      when the step begins) rather than the one predicted a step earlier.
    - *Toe-out* for the next step: with Δ' the turn from ψ to ψ', beyond T the swing foot
      points ``min(|Δ'| − T, T2)`` toward the turn — when it is the inside foot; the
      outside foot steps straight and the inside foot turns with the next placement
      (Chen & Li §5.4, :func:`planners.split_turn`).
    """
    side_sw = np.where(np.asarray(swing_left, bool), 1.0, -1.0)
    base = np.asarray(base_toe_out, dtype=float)
    own = np.asarray(stance_yaw, dtype=float) + side_sw * base  # stance side = -side_sw
    twist = wrap_angle(np.asarray(heading, float) - own)
    spin = np.sign(twist) * np.maximum(np.abs(twist) - config.toe_out_threshold, 0.0)
    delta = wrap_angle(np.asarray(heading_next, float) - np.asarray(heading, float))
    inside = np.sign(delta) == side_sw
    adjust = np.where(inside, np.minimum(np.maximum(np.abs(delta) - config.toe_out_threshold,
                                                    0.0), config.toe_out_limit), 0.0)
    toe_out = base + adjust
    return StepTurn(toe_out=toe_out, spin=spin,
                    landing_yaw=wrap_angle(np.asarray(heading, float) + side_sw * toe_out))


def preferred_step_for_slope(level_step: np.ndarray, slope: np.ndarray) -> np.ndarray:
    """Preferred step length on a slope, Eq. 11 (Sun et al. 1996) [m].

    Eq. 11 gives 0.627 + 0.0075 ρ m downhill (ρ < 0) and 0.623 − 0.0019 ρ m uphill, ρ in
    degrees, for an average person; the relative change is applied to the agent's own
    level step length. The step shortens on any slope.

    Parameters
    ----------
    level_step : (n,) preferred step length on level ground [m].
    slope : (n,) ground slope ρ along the step, positive uphill [rad].
    """
    rho = np.rad2deg(np.asarray(slope, dtype=float))
    ratio = np.where(rho < 0, (0.627 + 0.0075 * rho) / 0.627, (0.623 - 0.0019 * rho) / 0.623)
    return np.asarray(level_step, dtype=float) * np.clip(ratio, 0.3, 1.0)


def _arc(path: np.ndarray) -> np.ndarray:
    seg = np.linalg.norm(np.diff(path, axis=1), axis=2)
    return np.concatenate([np.zeros((path.shape[0], 1)), np.cumsum(seg, axis=1)], axis=1)


def closest_arc_length(path: np.ndarray, point: np.ndarray) -> np.ndarray:
    """Arc length (n,) [m] of the point of each polyline (n, m, 2) closest to point (n, 2)."""
    a, b = path[:, :-1], path[:, 1:]
    ab = b - a
    length2 = np.maximum(np.einsum("nmi,nmi->nm", ab, ab), 1e-18)
    u = np.clip(np.einsum("nmi,nmi->nm", point[:, None] - a, ab) / length2, 0.0, 1.0)
    foot = a + u[..., None] * ab
    dist = np.linalg.norm(foot - point[:, None], axis=2)
    best = np.argmin(dist, axis=1)
    rows = np.arange(path.shape[0])
    arc = _arc(path)
    return arc[rows, best] + u[rows, best] * np.sqrt(length2[rows, best])


def path_point(path: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Points (n, 2) [m] at arc lengths s (n,) along polylines (n, m, 2), clamped to the
    ends (beyond the end the last segment is extended)."""
    arc = _arc(path)
    n, m = arc.shape
    seg = np.clip((arc <= s[:, None]).sum(axis=1) - 1, 0, m - 2)
    rows = np.arange(n)
    s0, s1 = arc[rows, seg], arc[rows, seg + 1]
    u = (s - s0) / np.maximum(s1 - s0, 1e-12)
    u = np.minimum(np.maximum(u, 0.0), np.where(seg == m - 2, np.inf, 1.0))
    return path[rows, seg] + u[:, None] * (path[rows, seg + 1] - path[rows, seg])


def _landing_xy(stance: np.ndarray, heading: np.ndarray, length: np.ndarray,
                lateral: np.ndarray) -> np.ndarray:
    """Points (n, 2) [m] ``length`` [m] ahead along ``heading`` [rad] and ``lateral`` [m]
    to the left of the stance footholds (n, 3) [m]."""
    c, s = np.cos(heading), np.sin(heading)
    return stance[:, :2] + np.stack([c * length - s * lateral, s * length + c * lateral], axis=1)


def _direction(path: np.ndarray, s_from: np.ndarray, s_to: np.ndarray) -> np.ndarray:
    d = path_point(path, s_to) - path_point(path, s_from)
    return np.arctan2(d[:, 1], d[:, 0])


class MetaGait:
    """High-level gait control for n agents (§6); keeps each agent's pending spin turn.

    Parameters
    ----------
    n : int
        Number of agents.
    config : MetaGaitConfig, optional
    base_toe_out : float
        Toe-out of a straight step [rad] (``GaitStyle.toe_out``).
    """

    def __init__(self, n: int, config: MetaGaitConfig | None = None,
                 base_toe_out: float = float(np.deg2rad(7.0))) -> None:  # fmt: skip
        if n < 1:
            raise invalid("MetaGait", "n", ">= 1", n)
        self.config = config or MetaGaitConfig()
        self.base_toe_out = float(base_toe_out)
        self._pending_spin = np.zeros(n)
        self.foot_yaw = np.full((n, 2), np.nan)  # left, right foot's direction [rad]

    def orient(self, agents: np.ndarray, *, swing_foot: np.ndarray, heading: np.ndarray,
               heading_next: np.ndarray, base_toe_out: np.ndarray) -> StepTurn:
        """Toe-out and spin turn of the steps the crowd decided for ``agents`` (k,)
        (:func:`orient_steps`); remembers where each foot then points.

        ``swing_foot`` (k,) 0 left / 1 right; ``heading`` (k,) the steps' directions,
        ``heading_next`` (k,) the direction expected one step later, ``base_toe_out``
        (k,) the walkers' own toe-out [rad]. An agent's first step starts from its feet
        pointing along its heading with their own toe-out.
        """
        a = np.asarray(agents)
        sw = np.asarray(swing_foot, dtype=np.intp)
        side_sw = np.where(sw == 0, 1.0, -1.0)
        stance = self.foot_yaw[a, 1 - sw]
        stance = np.where(np.isfinite(stance), stance, heading - side_sw * base_toe_out)
        turn = orient_steps(heading=heading, heading_next=heading_next, stance_yaw=stance,
                            swing_left=sw == 0, base_toe_out=base_toe_out, config=self.config)
        self.foot_yaw[a, 1 - sw] = wrap_angle(stance + turn.spin)
        self.foot_yaw[a, sw] = turn.landing_yaw
        return turn

    # -- the rules, each batched ------------------------------------------------------
    def heading(self, path: np.ndarray, position: np.ndarray, step_length: np.ndarray):
        """ψ from p0 (closest path point) and p1 (one step on) [rad], and the arc length
        of p0 [m]; shapes (n,)."""
        s0 = closest_arc_length(path, position)
        return _direction(path, s0, s0 + step_length), s0

    def turn(self, path: np.ndarray, s0: np.ndarray, step_length: np.ndarray):
        """Toe-out adjustment (signed yaw toward the turn) and spin turn [rad], (n,) each,
        from the heading change Δ between this step and the next (§6.1)."""
        cfg = self.config
        here = _direction(path, s0, s0 + step_length)
        later = _direction(path, s0 + step_length, s0 + 2.0 * step_length)
        delta = wrap_angle(later - here)
        excess = np.maximum(np.abs(delta) - cfg.toe_out_threshold, 0.0)
        yaw = np.sign(delta) * np.minimum(excess, cfg.toe_out_limit)
        spin = np.sign(delta) * np.maximum(excess - cfg.toe_out_limit, 0.0)
        return yaw, spin

    def max_step_length(self, path: np.ndarray, s0: np.ndarray, step_length: np.ndarray):
        """SL_max (n,) [m]: reduce the step by a fixed amount until ψ changes by less than
        Δψ_thresh over one gait cycle (§6.1)."""
        cfg = self.config
        sl = np.asarray(step_length, dtype=float).copy()
        for _ in range(int(np.ceil(sl.max() / cfg.step_reduction)) + 1):
            now = _direction(path, s0, s0 + sl)
            cycle = _direction(path, s0 + 2.0 * sl, s0 + 3.0 * sl)
            too_sharp = (np.abs(wrap_angle(cycle - now)) > cfg.max_heading_change) & (
                sl > cfg.min_step_length
            )
            if not too_sharp.any():
                break
            sl = np.where(too_sharp, np.maximum(sl - cfg.step_reduction, cfg.min_step_length), sl)
        return sl

    def terrain_step(
        self,
        stance: np.ndarray,
        heading: np.ndarray,
        lateral: np.ndarray,
        level_step: np.ndarray,
        max_step: np.ndarray,
        ground: Callable[[np.ndarray], np.ndarray],
    ):
        """Uneven-terrain loop (§6.2): step length, height [m] and landing foothold.

        ``p_sw = R(ψ)[SL, lateral] + p_st``; the ground height there gives the slope ρ,
        Eq. 11 the preferred length, ``SL = min(SL_pref, SL_max)``; repeated
        ``terrain_iterations`` times. Returns SL (n,), SH (n,), target (n, 3).
        """
        sl = np.minimum(level_step, max_step)
        for _ in range(self.config.terrain_iterations):
            xy = _landing_xy(stance, heading, sl, lateral)
            h = np.asarray(ground(xy), dtype=float) - stance[:, 2]
            rho = np.arctan2(h, sl)
            sl = np.maximum(np.minimum(preferred_step_for_slope(level_step, rho), max_step),
                            self.config.min_step_length)  # fmt: skip
        xy = _landing_xy(stance, heading, sl, lateral)
        z = np.asarray(ground(xy), dtype=float)
        return sl, z - stance[:, 2], np.column_stack([xy, z])

    # -- all together -----------------------------------------------------------------
    def next_step(
        self,
        agents: np.ndarray,
        time: np.ndarray,
        stance: np.ndarray,
        swing_foot: np.ndarray,
        path: np.ndarray,
        level_step: np.ndarray,
        speed: np.ndarray,
        body_height: np.ndarray,
        ground: Callable[[np.ndarray], np.ndarray],
        planned_length: np.ndarray | None = None,
        planned_height: np.ndarray | None = None,
        swing_bezier: np.ndarray | None = None,
    ):
        """The next step of m agents at their heel strikes (§6.1–6.3), a
        :class:`~crowdwalk.gait.animator.StepCommand`.

        Parameters
        ----------
        agents : (m,) agent indices.
        time : (m,) heel-strike times [s].
        stance : (m, 3) stance foothold [m].
        swing_foot : (m,) 0 = left swings next, 1 = right.
        path : (m, k, 2) path ahead of each agent [m].
        level_step : (m,) preferred level-ground step length [m].
        speed : (m,) walking speed [m/s]; the step lasts ``SL / speed``.
        body_height : (m,) [m], for the step width.
        ground : ``ground(xy (p, 2)) -> z (p,)`` [m].
        planned_length, planned_height : (m,), optional
            A footstep planner's step [m]; NaN rows use MetaGait's own rules.
        swing_bezier : (m, 4, 3), optional
            The planner's swing-ankle Bezier control points, passed on [m].
        """
        from crowdwalk.gait.animator import StepCommand

        agents = np.atleast_1d(np.asarray(agents))
        m = agents.size
        stance = np.asarray(stance, dtype=float).reshape(m, 3)
        path = np.asarray(path, dtype=float)
        if path.ndim != 3 or path.shape[0] != m or path.shape[1] < 2 or path.shape[2] != 2:
            raise invalid("MetaGait", "path", f"an ({m}, k >= 2, 2) array [m]", path.shape)
        speed = np.asarray(speed, dtype=float)
        if np.any(~np.isfinite(speed) | (speed <= 0)):
            raise invalid("MetaGait", "speed", "finite and > 0 [m/s]", speed.min())
        level = np.asarray(level_step, dtype=float)
        swing_left = np.asarray(swing_foot) == 0
        side_sw = np.where(swing_left, 1.0, -1.0)
        psi, s0 = self.heading(path, stance[:, :2], level)
        sl_max = self.max_step_length(path, s0, level)
        yaw, spin = self.turn(path, s0, level)
        lateral = side_sw * self.config.step_width * np.asarray(body_height, dtype=float)
        sl, sh, target = self.terrain_step(stance, psi, lateral, level, sl_max, ground)
        if planned_length is not None and planned_height is not None:
            pl = np.asarray(planned_length, dtype=float)
            ph = np.asarray(planned_height, dtype=float)
            use = np.isfinite(pl) & np.isfinite(ph) & (pl > 0)
            xy = _landing_xy(stance, psi, pl, lateral)
            planned_target = np.column_stack([xy, stance[:, 2] + ph])
            sl = np.where(use, pl, sl)
            sh = np.where(use, ph, sh)
            target = np.where(use[:, None], planned_target, target)
        toe_out = self.base_toe_out + side_sw * yaw  # toward the turn, per foot
        spin_now = self._pending_spin[agents].copy()
        self._pending_spin[agents] = spin
        return StepCommand(
            agent=agents,
            time=np.asarray(time, dtype=float),
            duration=np.maximum(sl, 1e-3) / speed,
            swing_foot=np.asarray(swing_foot, dtype=int),
            start=stance,
            target=target,
            heading=psi,
            step_length=sl,
            step_height=sh,
            swing_bezier=swing_bezier,
            toe_out=np.clip(toe_out, -1.0, 1.0),
            spin=spin_now,
            speed=np.broadcast_to(np.asarray(speed, dtype=float), sl.shape).copy(),
        )


def level_step_length(leg_length: np.ndarray, speed: np.ndarray) -> np.ndarray:
    """Preferred level-ground step length [m] for leg lengths (n,) [m] and speeds (n,)
    [m/s]: ``SL / L = 0.3049 + 0.9945 v / sqrt(g L)`` (Fukuchi et al. 2018, fitted in
    ``crowdwalk/data/normative.json``)."""
    from crowdwalk.gait.datasets import normative

    fit = normative()["step_length_vs_froude"]
    leg = np.asarray(leg_length, dtype=float)
    froude = np.asarray(speed, dtype=float) / np.sqrt(9.81 * leg)
    return leg * (fit["intercept"] + fit["slope"] * froude)


def animate_paths(
    body,
    paths: np.ndarray,
    ground: Callable[[np.ndarray], np.ndarray],
    speed: np.ndarray | float,
    duration: float,
    fps: float,
    animator=None,
    metagait: MetaGait | None = None,
    on_frame: Callable | None = None,
) -> list:
    """Walk n agents along paths: MetaGait decides each step, the Animator poses them.

    The paper's user-level interface ("follow this path"), without a crowd: every agent
    starts with its left foot as stance foot at the start of its path.

    Parameters
    ----------
    body : crowdwalk.body.Body
        n bodies.
    paths : (n, m, 2) polylines [m].
    ground : ``ground(xy (p, 2)) -> z (p,)`` [m].
    speed : float or (n,) walking speed [m/s].
    duration : float, simulated time [s].
    fps : float, output frames per second [1/s].
    animator : Animator, optional (default: a new one for ``body`` and ``ground``).
    metagait : MetaGait, optional.
    on_frame : callable, optional
        Called as ``on_frame(frame, animator)`` after every frame (diagnostics).

    Returns
    -------
    list of PoseFrame
        One per output frame, all agents.
    """
    from crowdwalk.gait.animator import Animator

    n = len(body)
    paths = np.asarray(paths, dtype=float)
    if paths.ndim != 3 or paths.shape[0] != n:
        raise invalid("animate_paths", "paths", f"an ({n}, m, 2) array [m]", paths.shape)
    if not (np.isfinite(duration) and duration > 0):
        raise invalid("animate_paths", "duration", "finite and > 0 [s]", duration)
    if not (np.isfinite(fps) and fps > 0):
        raise invalid("animate_paths", "fps", "finite and > 0 [1/s]", fps)
    speed = np.broadcast_to(np.asarray(speed, dtype=float), (n,)).copy()
    animator = animator or Animator(body, ground=ground)
    metagait = metagait or MetaGait(n, base_toe_out=animator.style.toe_out)
    level = level_step_length(body.leg_length, speed)
    start = paths[:, 0]
    d = paths[:, 1] - paths[:, 0]
    psi = np.arctan2(d[:, 1], d[:, 0])
    half = 0.5 * metagait.config.step_width * body.height
    xy = start + half[:, None] * np.stack([-np.sin(psi), np.cos(psi)], axis=1)
    stance = np.column_stack([xy, ground(xy)])
    swing_foot = np.ones(n, dtype=int)  # the right foot swings first
    next_time = np.zeros(n)
    agents = np.arange(n)
    frames = []
    for f in range(int(np.floor(duration * fps)) + 1):
        t = f / fps
        due = np.flatnonzero(next_time <= t + 1e-9)
        if due.size:
            cmd = metagait.next_step(
                agents[due], next_time[due], stance[due], swing_foot[due], paths[due],
                level[due], speed[due], body.height[due], ground,
            )  # fmt: skip
            animator.command(cmd)
            next_time[due] = cmd.time + cmd.duration
            stance[due] = cmd.target
            swing_foot[due] = 1 - swing_foot[due]
        frames.append(animator.pose(t))
        if on_frame is not None:
            on_frame(frames[-1], animator)
    return frames
