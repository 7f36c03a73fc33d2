"""The crowd's speed model: how long a step takes.

Deviation from Chen & Li, whose Table 1 shortens the phases equally for up- and downhill:
the step duration is step length / speed with the agent's free speed scaled on stairs by
Weidmann's (1993) measured horizontal stair speeds (0.610 m/s up, 0.694 m/s down against
1.34 m/s level) and on slopes by Tobler's (1993) hiking function; a level step never
takes less than the walker's step time at its free speed (the body's normal-mode cadence,
``planners.normal_mode``, fitted to Fukuchi et al. 2018; or a locked step frequency,
``crowdwalk.style``), so short
steps in a queue are slow steps, not a shuffle at high cadence.

That floor holds for steps the planner did not plan (shortened in a queue, positioning)
only: a planned level step takes length / speed, so that a walker alone reaches its free
speed (with the floor on every step, lone walkers in a corridor walked at 0.947 of their
free speed on average, 0.880 at worst, because the planner's energy-optimal step is often
shorter than the WBDS step length at that speed; without it 1.000).

``CrowdParams.speed_model = "time_gap"`` adds :func:`time_gap_speed` (Tordeux et al.
2016): the step's speed is limited by the gap to the walker ahead, and its length to what
that speed covers in one step at the measured cadence for it.
``speed_model = "headway"`` (:func:`headway_speed`) uses Seyfried et al. 2005's
single-file required length d = a + b v instead, following only same-way walkers.
``speed_model = "contact_gap"`` (:func:`contact_gap_speed`) measures the gap as the
distance to the first contact along the walking line (Moussaïd et al. 2011's d_h), so a
walker beside-ahead counts by how far one can walk before touching it, and steering
scores every candidate direction at the step it allows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from crowdwalk.crowd.speed_kernels import route_lane_headway
from planners import normal_mode

__all__ = ["STAIR_UP_FACTOR", "STAIR_DOWN_FACTOR", "step_durations", "time_gap_speed",
           "contact_gap_speed", "headway_speed", "GapSteps"]

#: Weidmann (1993): horizontal speed on stairs, up and down, over level speed 1.34 m/s.
STAIR_UP_FACTOR = 0.610 / 1.34
STAIR_DOWN_FACTOR = 0.694 / 1.34


def step_durations(length: np.ndarray, rise: np.ndarray, *, free_speed: np.ndarray,
                   min_step_time: np.ndarray, stair_rise: float) -> np.ndarray:
    """Durations (k,) [s] of steps of ``length`` and ``rise`` (k,) [m] by walkers of
    ``free_speed`` (k,) [m/s] whose level steps take at least ``min_step_time`` (k,) [s]
    (0 for planned steps); a rise beyond ``stair_rise`` [m] is a stair step."""
    grade = rise / np.maximum(length, 1e-6)
    factor = np.where(rise > stair_rise, STAIR_UP_FACTOR,
                      np.where(rise < -stair_rise, STAIR_DOWN_FACTOR,
                               1.0 / np.maximum(1.0, np.exp(3.5 * (np.abs(grade + 0.05)
                                                                   - 0.05)))))
    stair = np.abs(rise) > stair_rise
    return np.where(stair, length / (free_speed * factor),
                    np.maximum(length / (free_speed * factor), min_step_time))


def time_gap_speed(*, position: np.ndarray, direction: np.ndarray, radius: np.ndarray,
                   others: np.ndarray, others_radius: np.ndarray, valid: np.ndarray,
                   free_speed: np.ndarray, time_gap: float) -> np.ndarray:
    """The collision-free speed model of Tordeux, Chraibi & Seyfried (2016, "Collision-free
    speed model for pedestrian dynamics", Traffic and Granular Flow '15, Eq. 2), per step:
    v = min(v0, max(0, (s − ℓ) / T)).

    s is the centre distance to the nearest neighbour ahead — in front of the walker
    (positive along its ``direction``) and closer to its walking line than ℓ = r_i + r_j,
    the two radii — and T the ``time_gap`` [s].

    Parameters
    ----------
    position : (k, 2) float
        Walkers [m].
    direction : (k, 2) or (k, C, 2) float
        Their unit step directions (C candidate directions each: speeds (k, C)).
    radius : (k,) float
        Their body radii [m].
    others, others_radius, valid : (k, m, 2), (k, m), (k, m)
        Each walker's m neighbours [m], their radii [m] and which are real.
    free_speed : (k,) float
        [m/s].

    Returns
    -------
    (k,) or (k, C) speeds [m/s].
    """
    if direction.ndim == 3:  # candidate directions (overtaking scores them): one at a time
        return np.stack([time_gap_speed(position=position, direction=direction[:, c],
                                        radius=radius, others=others,
                                        others_radius=others_radius, valid=valid,
                                        free_speed=free_speed, time_gap=time_gap)
                         for c in range(direction.shape[1])], axis=1).reshape(
                             direction.shape[:2])
    rel = others - position[:, None, :]
    along = np.einsum("kmj,kj->km", rel, direction)
    lateral = np.abs(rel[..., 0] * direction[:, None, 1] - rel[..., 1] * direction[:, None, 0])
    reach = radius[:, None] + others_radius
    ahead = valid & (along > 0) & (lateral < reach)
    gap = np.where(ahead, np.linalg.norm(rel, axis=-1) - reach, np.inf).min(axis=1)
    return np.minimum(free_speed, np.maximum(gap, 0.0) / time_gap)


def contact_gap_speed(*, position: np.ndarray, direction: np.ndarray, radius: np.ndarray,
                      others: np.ndarray, others_radius: np.ndarray, valid: np.ndarray,
                      free_speed: np.ndarray, time_gap: float) -> np.ndarray:
    """Speed [m/s] that keeps ``time_gap`` [s] to the first contact along the walking
    line: v = min(v0, d / T), d the distance the body can walk along ``direction`` before
    it touches a neighbour standing where it is (the distance to the first collision,
    d_h, of Moussaïd et al. 2011, PNAS 108:6884, heuristic 2). For a neighbour straight
    ahead d = s − ℓ, Tordeux et al.'s gap; for one off the line by b < ℓ = r_i + r_j,
    d = a − √(ℓ² − b²), a its distance along the line, so that a walker in the next lane
    of a zipper, beside-ahead, does not count as if straight ahead.

    ``direction`` is (k, 2) or (k, C, 2) (C candidate directions each); the result is
    (k,) or (k, C). Other arguments as :func:`time_gap_speed`.
    """
    d = direction if direction.ndim == 3 else direction[:, None, :]
    rel = (others - position[:, None, :])[:, None, :, :]  # (k, 1, m, 2)
    along = np.einsum("kcmj,kcj->kcm", rel, d)
    lateral = rel[..., 0] * d[:, :, None, 1] - rel[..., 1] * d[:, :, None, 0]
    reach = (radius[:, None] + others_radius)[:, None, :]
    ahead = valid[:, None, :] & (along > 0) & (np.abs(lateral) < reach)
    contact = along - np.sqrt(np.maximum(reach**2 - lateral**2, 0.0))
    gap = np.where(ahead, contact, np.inf).min(axis=2)  # (k, C)
    v = np.minimum(free_speed[:, None], np.maximum(gap, 0.0) / time_gap)
    return v if direction.ndim == 3 else v[:, 0]


def headway_speed(*, position: np.ndarray, direction: np.ndarray, radius: np.ndarray,
                  others: np.ndarray, others_radius: np.ndarray, valid: np.ndarray,
                  free_speed: np.ndarray, time_gap: float, lane: np.ndarray,
                  lane_direction: np.ndarray | None = None,
                  shift: np.ndarray | None = None) -> np.ndarray:
    """Speed [m/s] from the required length of Seyfried et al. (2005, "The fundamental
    diagram of pedestrian movement revisited", J. Stat. Mech. P10002): in single file a
    walker moving at v needs d = a + b v of line, a = 0.36 m and b = 1.06 s (their linear
    fit of the inverse density against speed), so v = min(v0, max(0, (s − a) / b)).

    s is the distance along the walking line to the nearest neighbour ahead whose centre
    lies within ``lane`` (k,) [m] of that line, and a = r_i + r_j, the two radii (0.36 m
    for two 1.71 m persons: the same standstill spacing). A neighbour further off the
    line is not followed: only the hard swept-body test keeps the two apart.
    ``time_gap`` is b. Shapes as :func:`contact_gap_speed`. ``lane_direction`` (k, 2)
    and ``shift`` (k,) [m] given: the leader is sought in the route lane the step goes
    into (:func:`_route_lane_headway`).
    """
    d = direction if direction.ndim == 3 else direction[:, None, :]
    if lane_direction is not None:
        return _route_lane_headway(position, d, others, radius, others_radius, valid,
                                   free_speed, time_gap, lane, lane_direction, shift,
                                   direction.ndim)
    rel = (others - position[:, None, :])[:, None, :, :]  # (k, 1, m, 2)
    need = (radius[:, None] + others_radius)[:, None, :]
    along = np.einsum("kcmj,kcj->kcm", rel, d)
    lateral = rel[..., 0] * d[:, :, None, 1] - rel[..., 1] * d[:, :, None, 0]
    ahead = valid[:, None, :] & (along > 0) & (np.abs(lateral) < lane[:, None, None])
    gap = np.where(ahead, along - need, np.inf).min(axis=2)  # (k, C)
    v = np.minimum(free_speed[:, None], np.maximum(gap, 0.0) / time_gap)
    return v if direction.ndim == 3 else v[:, 0]


def _route_lane_headway(position, d, others, radius, others_radius, valid, free_speed,
                        time_gap, lane, e, shift, ndim):
    """:func:`headway_speed` in the route lane the step goes into (``headway_route_lane``):
    the leader is the nearest neighbour ahead along the route direction ``e`` (k, 2)
    whose centre is within ``lane`` of the line parallel to ``e`` through the step's end
    (``shift`` (k,) [m] along each candidate ``d`` (k, C, 2)), and Seyfried's relation
    limits the speed along ``e`` only: v = min(v0, ((s − a) / b) / (d · e)), free for a
    step across or back (d · e ≤ 0). One compiled loop
    (:func:`~crowdwalk.crowd.speed_kernels.route_lane_headway`)."""
    f = np.ascontiguousarray
    v = np.empty(d.shape[:2])
    route_lane_headway(f(position, float), f(others, float), f(radius, float),
                       f(others_radius, float), f(valid, bool), f(d, float), f(e, float),
                       f(shift, float), f(lane, float), f(free_speed, float),
                       float(time_gap), v)
    return v if ndim == 3 else v[:, 0]


@dataclass(frozen=True, eq=False)
class GapSteps:
    """A gap speed model's step for m deciding walkers (struct-of-arrays).

    Attributes
    ----------
    position, radius : (m, 2), (m,)
        The walkers [m].
    others, others_radius : (m, K, 2), (m, K)
        Their neighbours where the gap is measured to [m], and radii [m].
    valid, followed : (m, K) bool
        The real neighbours (counted along candidate directions), and those the step's
        own speed counts.
    free_speed, leg_length : (m,)
        [m/s], [m].
    time_gap : float
        T [s] (b of the headway model).
    contact : bool
        :func:`contact_gap_speed` (else :func:`time_gap_speed`, one direction each).
    lane : (m,) float, optional
        Given: :func:`headway_speed` with this lateral extent [m].
    lane_direction, shift : (m, 2), (m,), optional
        Given (with ``lane``): the route-lane headway (unit route directions, and how far
        along a step the lane is taken [m]).
    """

    position: np.ndarray
    radius: np.ndarray
    others: np.ndarray
    others_radius: np.ndarray
    valid: np.ndarray
    followed: np.ndarray
    free_speed: np.ndarray
    leg_length: np.ndarray
    time_gap: float
    contact: bool = True
    lane: np.ndarray | None = None
    lane_direction: np.ndarray | None = None
    shift: np.ndarray | None = None

    def along(self, direction: np.ndarray, *, everyone: bool = False,
              same_time: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Speed [m/s] and longest step [m] along unit ``direction`` (m, 2) or (m, C, 2),
        each (m,) or (m, C): the step is what that speed covers in one step at the
        normal-mode cadence for it (WBDS relation), unlimited at the free speed.
        ``everyone``: count every neighbour, not only the followed ones. ``same_time``:
        what that speed covers in one step at the cadence of the free speed instead (so
        that directions compare by speed, not by step length: a slower step is also a
        longer one in time)."""
        speed = contact_gap_speed if self.contact else time_gap_speed
        extra = {}
        if self.lane is not None:
            speed, extra = headway_speed, {"lane": self.lane,
                                           "lane_direction": self.lane_direction,
                                           "shift": self.shift}
        v = speed(position=self.position, direction=direction, radius=self.radius,
                  others=self.others, others_radius=self.others_radius,
                  valid=self.valid if everyone else self.followed,
                  free_speed=self.free_speed, time_gap=self.time_gap, **extra)
        col = (slice(None),) + (None,) * (v.ndim - 1)
        pace = (np.broadcast_to(self.free_speed[col], v.shape) if same_time
                else np.maximum(v, 0.1))
        short = v / normal_mode.step_frequency(pace, self.leg_length[col])
        return v, np.where(v < self.free_speed[col], short, np.inf)
