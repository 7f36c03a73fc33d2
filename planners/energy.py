"""The energy model of Chen & Li, Eqs. (1)-(5), vectorised.

Units: ``En`` is Ralston's walking energy in cal/kg per step, ``Ev`` the printed stair
term of Eq. (2) (its own unit, h in cm), ``Ej`` J/kg per step from joint rotations [rad].
``total`` combines them with :class:`~planners.config.EnergyWeights` into J/kg per step.
"""

from __future__ import annotations

import numpy as np

from planners import normal_mode
from planners.config import EnergyWeights, PlannerConfig
from planners.kinematics import key_frames
from planners.leg import Leg

__all__ = ["walking_energy", "vertical_energy", "joint_energy", "total_energy",
           "frequency_energy", "normal_step", "step_energy", "flat_efficiency",
           "terminal_energy", "EV_PEAK_CM"]

#: Height [cm] where the printed quadratic of Eq. (2) peaks: 7.14 / (2 * 0.18).
EV_PEAK_CM = 7.14 / 0.36
_EV_PEAK = -0.18 * EV_PEAK_CM**2 + 7.14 * EV_PEAK_CM


def walking_energy(step_length: np.ndarray, speed: np.ndarray | float) -> np.ndarray:
    """Eq. (1): En = (32 + 0.005 v^2) / n per step [cal/kg].

    Parameters
    ----------
    step_length : array_like
        Step lengths [m].
    speed : array_like
        Walking speed [m/s], broadcast against ``step_length``.

    Notes
    -----
    Ralston's rate is in cal/(kg min) with v in m/min; the cadence n [steps/min] is
    v / step_length because the walker keeps its target speed, so En = rate * L / v.
    """
    v = 60.0 * np.asarray(speed, dtype=float)
    return (32.0 + 0.005 * v**2) * np.asarray(step_length, dtype=float) / v


def vertical_energy(rise: np.ndarray, down_ratio: float = 1.0 / 3.0,
                    model: str = "paper") -> np.ndarray:
    """Eq. (2): Ev = -0.18 h^2 + 7.14 h for a rise h [cm], in Eq. (2)'s unit.

    Parameters
    ----------
    rise : array_like
        Signed height change of the step [m]; positive is up.
    down_ratio : float
        Cost of stepping down relative to stepping up the same height [-].
    model : {"paper", "linear"}
        ``"paper"``: Eq. 2 as printed (continued above its peak, see Notes);
        ``"linear"``: 7.14 h, the quadratic's slope at h = 0 for every height (work
        against gravity at a constant muscle efficiency).

    Notes
    -----
    ``"paper"``: the printed quadratic peaks at h = 19.8 cm and falls after it. Above the
    peak we continue linearly with the quadratic's slope at h = 0 (7.14 per cm), so Ev
    is continuous and increasing, and a rise beyond a normal stair riser (a climb with a
    deeply bent loaded knee) costs more per cm than a normal riser (one 34 cm step costs
    more than two 17 cm steps). With either model, stepping down costs ``down_ratio``
    times stepping up the same height (negative work).
    """
    h = 100.0 * np.asarray(rise, dtype=float)
    a = np.abs(h)
    if model == "linear":
        up = 7.14 * a
    else:
        up = np.where(a <= EV_PEAK_CM, -0.18 * a**2 + 7.14 * a,
                      _EV_PEAK + 7.14 * (a - EV_PEAK_CM))
    return np.where(h >= 0, up, down_ratio * up)


def joint_energy(thigh_rotation: np.ndarray, calf_rotation: np.ndarray,
                 weights: EnergyWeights) -> np.ndarray:
    """Eq. (3): Ej = c_thigh (dθ1 + dθ3) + c_calf (dθ2 + dθ4) [J/kg].

    Parameters
    ----------
    thigh_rotation, calf_rotation : array_like
        Summed absolute rotation of both thighs and of both calves over the cycle [rad].
    """
    return weights.c_thigh * np.asarray(thigh_rotation) + weights.c_calf * np.asarray(
        calf_rotation)


def total_energy(En: np.ndarray, Ev: np.ndarray, Ej: np.ndarray,
                 weights: EnergyWeights) -> np.ndarray:
    """Eq. (4): E = alpha En + beta Ev + gamma Ej [J/kg per step]."""
    return weights.alpha * En + weights.beta * Ev + weights.gamma * Ej


def normal_step(leg, speed) -> np.ndarray:
    """Normal-mode step length [m] of ``leg`` (a Leg or leg arrays) at ``speed`` [m/s]
    (:mod:`planners.normal_mode`, WBDS)."""
    return normal_mode.step_length(speed, normal_mode.leg_length_of(leg))


def frequency_energy(En: np.ndarray, step_length: np.ndarray, normal: np.ndarray,
                     weights: EnergyWeights) -> np.ndarray:
    """Step-frequency term [J/kg per step] (``PlannerConfig.step_model = "normal_mode"``).

    ``kappa * alpha * En * (normal / L - 1)^2``: at a given speed, a step of length L is
    taken at the frequency f = v / L, a fraction x = f / f* - 1 = normal / L - 1 off the
    normal-mode frequency f*; the step then costs ``kappa x^2`` times its Eq. 1 walking
    energy more. Deviation from Chen & Li, whose Eq. 1 (Ralston's rate per step) charges
    a metre the same at any step length, so that their optimal step does not change with
    speed (0.668 m for a 1.75 m body at 0.8-1.8 m/s), while people lengthen their steps
    with speed (WBDS: 0.51 to 0.78 m). People at a given speed choose the step frequency
    that minimises their metabolic rate (Zarrugh, Todd & Ralston 1974, Eur J Appl Physiol
    33:293; Umberger & Martin 2007, J Exp Biol 210:3255: the minimum lies 0.2 % from the
    preferred rate), so the term has its minimum at the measured preferred (normal-mode)
    step. Its weight kappa = 10 is not measured: it is the round value that puts the
    continuous optimum of the whole model on level ground within 2.9 % of the normal-mode
    step for bodies 1.50-1.95 m at 0.8-1.8 m/s (5.7 % with kappa = 5, 3.5 % with 8; the
    speed-free joint term Ej pulls towards 0.38 body heights), and keeps the planned step
    on the normal-mode grid node (within 0.3 %); ``scripts/normal_mode_steps.py`` prints
    the table.

    Parameters
    ----------
    En : array_like
        Eq. 1 energy of the steps [cal/kg].
    step_length, normal : array_like
        Step lengths and the normal-mode step at the walker's speed [m], broadcast.
    weights : EnergyWeights
    """
    x = np.asarray(normal, float) / np.maximum(np.asarray(step_length, float), 1e-6) - 1.0
    return weights.frequency * weights.alpha * np.asarray(En, float) * x**2


def step_energy(stance_s, stance_z, front_s, front_z, summit_z, leg, speed,
                config: PlannerConfig):
    """Energy terms of steps from the stance to the front foothold (Eqs. 1-4).

    Parameters
    ----------
    stance_s, stance_z, front_s, front_z : ndarray
        Footholds [m] (broadcast together).
    summit_z : ndarray
        Swing-ankle height at mid-swing, key frame K1 [m].
    leg : Leg
        Leg geometry [m]; fields may be arrays broadcasting with the steps.
    speed : float or ndarray
        Target speed [m/s].
    config : PlannerConfig

    Returns
    -------
    En, Ev, Ej, E : ndarray
        Eq. 1 [cal/kg], Eq. 2 [its unit], Eq. 3 [J/kg], Eq. 4 [J/kg] per step (E with
        :func:`frequency_energy` under ``step_model = "normal_mode"``).
    reachable : ndarray of bool
        Knee reachable at every key frame.
    """
    kf = key_frames(stance_s, stance_z, front_s, front_z, stance_s, summit_z, leg,
                    config.pelvis_height_ratio, config.knee_max_flexion,
                    leg.ankle_height + 0.75 * config.swing_lift)
    w = config.weights
    En = walking_energy(front_s - stance_s, speed)
    Ev = vertical_energy(front_z - stance_z, w.down_ratio, w.vertical)
    Ej = joint_energy(kf.thigh_rotation, kf.calf_rotation, w)
    E = total_energy(En, Ev, Ej, w)
    if config.step_model == "normal_mode":
        E = E + frequency_energy(En, front_s - stance_s, normal_step(leg, speed), w)
    return En, Ev, Ej, E, kf.reachable


def flat_efficiency(leg: Leg, speed: float, step_lengths,
                    config: PlannerConfig | None = None) -> np.ndarray:
    """Eq. 5 on flat ground: step length / E [m kg/J] for each step length [m] (Fig. 2).

    The swing ankle at mid-swing is at the summit of the initial §5.2 curve.
    """
    config = PlannerConfig() if config is None else config
    L = np.asarray(step_lengths, dtype=float)
    zero = np.zeros_like(L)
    summit = zero + leg.ankle_height + 0.75 * config.swing_lift
    _, _, _, E, _ = step_energy(zero, zero, L, zero, summit, leg, speed, config)
    return L / E


def terminal_energy(profile, start, stop, owner_start, legs, speeds, per_metre, neutral_step,
                    config: PlannerConfig):
    """Estimated energy [J/kg] of walking on from footholds ``start`` to ``stop``.

    The terminal cost of a plan (deviation from Chen & Li, see Notes): the energy the
    walker will still spend between the plan's last foothold and a point ``stop`` that
    every plan of the horizon reaches, so that plans are compared for the same progress.

    Parameters
    ----------
    profile : GroundProfile
        The (combined) ground profile [m].
    start : ndarray, shape (A, K)
        Last footholds of the plans [m] (absolute arc length on ``profile``).
    stop : ndarray, shape (A,)
        Common end of every plan of agent a [m], >= ``start[a]``.
    owner_start : ndarray, shape (A,)
        Ascending arc lengths where each agent's part of ``profile`` begins [m].
    legs : leg arrays
        Per-agent legs with ``take(rows)`` (:class:`planners.grids.LegArrays`).
    speeds : ndarray, shape (A,)
        Target speeds [m/s].
    per_metre : ndarray, shape (A,)
        Energy per metre of neutral steps on level ground [J/(kg m)].
    neutral_step : ndarray, shape (A,)
        Neutral step length [m].
    config : PlannerConfig

    Returns
    -------
    ndarray, shape (A, K)

    Notes
    -----
    Level ground costs ``per_metre``. A height change steeper than ``max_foot_slope`` (a
    riser, a curb) costs what one step up or down it costs beyond level walking of the
    same length, Eq. 4 for a step of length ``g`` (the distance to the next such change,
    i.e. the tread, at most the neutral step) minus ``per_metre * g``; a slope costs, per
    metre, what a neutral step on it costs beyond a level one. The estimate is exact for
    a flight of equal treads and for level ground, where it changes nothing (every plan
    is then charged ``per_metre`` for the distance it leaves to ``stop``, and the neutral
    step is the cheapest per metre).
    """
    s, z = np.asarray(profile.s, dtype=float), np.asarray(profile.z, dtype=float)
    A = start.shape[0]
    if s.size < 2:
        return per_metre[:, None] * (stop[:, None] - start)
    ds, dz = np.diff(s), np.diff(z)
    owner = np.clip(np.searchsorted(owner_start, 0.5 * (s[:-1] + s[1:]), side="right") - 1,
                    0, A - 1)
    leg = legs.take(owner)
    L0 = neutral_step[owner]
    lam = per_metre[owner]
    v = np.asarray(speeds, dtype=float)[owner]
    steep = np.abs(dz) > config.max_foot_slope * ds
    # the tread after a steep change: up to the next steep change (or a neutral step)
    where = np.flatnonzero(steep)
    nxt = np.searchsorted(where, np.arange(ds.size), side="right")
    if where.size:
        gap = np.where(nxt < where.size, s[where[np.minimum(nxt, where.size - 1)]] - s[1:],
                       np.inf)
    else:
        gap = np.full(ds.size, np.inf)
    lo = config.min_step_ratio * leg.length
    g = np.where(steep, np.clip(gap, lo, L0), L0)
    rise = np.where(steep, dz, dz / np.maximum(ds, 1e-12) * L0)
    zero = np.zeros_like(g)
    lift = leg.ankle_height + 0.75 * config.swing_lift
    _, _, _, E, _ = step_energy(zero, zero, g, rise, np.maximum(rise, 0.0) + lift, leg, v,
                                config)
    _, _, _, E0, _ = step_energy(zero, zero, L0, zero, zero + lift, leg, v, config)
    cost = np.where(steep, E - lam * g, (E - E0) / L0 * ds)
    # a low obstacle (a steep rise, then a steep drop within one longest step less a foot)
    # may be stridden over: it costs the cheaper of stepping on and off it and one step
    # over it, of at least the neutral length, with the swing ankle lifted over its top
    if where.size > 1:
        j = where[np.minimum(nxt, where.size - 1)]  # the next steep change after each
        longest = config.max_step_ratio * leg.length
        stride = np.maximum(L0, np.minimum(gap + leg.foot_length, longest))
        top = np.maximum(z[1:], z[j]) - z[:-1]
        _, _, _, Es, _ = step_energy(zero, zero, stride, zero, np.maximum(top, 0.0) + lift,
                                     leg, v, config)
        over = (steep & (dz > 0) & (nxt < where.size) & (dz[j] < 0)
                & (gap + leg.foot_length <= longest))
        i, j = np.flatnonzero(over), j[over]
        both, jump = cost[i] + cost[j], Es[i] - lam[i] * stride[i]
        cost[j] = np.where(both <= jump, cost[j], 0.0)
        cost[i] = np.minimum(both, jump) - cost[j]
    cost = np.where(np.isfinite(cost), cost, 0.0)  # e.g. the seams between agents' parts
    cum = np.concatenate([[0.0], np.cumsum(cost)])

    def F(x):
        k = np.clip(np.searchsorted(s, x, side="right") - 1, 0, s.size - 1)
        seg = np.minimum(k, ds.size - 1)
        inside = (k < s.size - 1) & (ds[seg] > 0)
        frac = np.where(inside, np.clip((x - s[k]) / np.where(inside, ds[seg], 1.0), 0, 1), 0)
        return cum[k] + cost[seg] * frac

    return (per_metre[:, None] * (stop[:, None] - start) + F(stop)[:, None] - F(start))
