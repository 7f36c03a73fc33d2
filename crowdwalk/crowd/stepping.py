"""The next step of each deciding agent: the next step of its footstep plan while it
keeps its line, else a new plan (Chen & Li plan n steps and walk them), and the fallback
steps where no planned step fits (shortened in a queue, positioning before a riser).

A :class:`StepPlan` is what is decided about a step before it is taken: its length, rise,
energy and swing curve, and whether it is taken at all.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np

from crowdwalk.crowd.legs import LegColumns

__all__ = ["StepPlan", "PlanQueue", "next_steps", "plan_or_reuse", "even_steps",
           "fallback_energy"]


@dataclass(frozen=True, eq=False)
class StepPlan:
    """Steps of k agents before they are taken (struct-of-arrays).

    Attributes
    ----------
    move : (k,) bool
        The step is taken (else the agent waits).
    length : (k,) float
        Step length along the walking direction [m].
    rise : (k,) float
        Height of the new foothold above the stance foothold [m].
    energy : (k,) float
        Energy of the step (Chen & Li Eq. 4) [J/kg].
    swing : (k, 4, 2) float
        Swing-ankle Bezier control points (s, z) relative to the stance ankle [m]; NaN
        where the planner gave none.
    shortened : (k,) bool
        Not the planner's step: shortened in a queue, or a positioning step (its cadence
        is at most the free-walking cadence, :func:`crowdwalk.crowd.speed.step_durations`).
    """

    move: np.ndarray
    length: np.ndarray
    rise: np.ndarray
    energy: np.ndarray
    swing: np.ndarray
    shortened: np.ndarray

    @classmethod
    def standing(cls, k: int) -> StepPlan:
        """k agents that do not step."""
        return cls(np.zeros(k, bool), np.zeros(k), np.zeros(k), np.zeros(k),
                   np.full((k, 4, 2), np.nan), np.zeros(k, bool))

    def put(self, rows: np.ndarray, other: StepPlan) -> StepPlan:
        """This plan with ``rows`` replaced by ``other`` (len(rows) steps)."""
        out = {}
        for name in ("move", "length", "rise", "energy", "swing", "shortened"):
            arr = getattr(self, name).copy()
            arr[rows] = getattr(other, name)
            out[name] = arr
        return StepPlan(**out)

    def take(self, rows: np.ndarray) -> StepPlan:
        """The steps at ``rows``."""
        return StepPlan(self.move[rows], self.length[rows], self.rise[rows],
                        self.energy[rows], self.swing[rows], self.shortened[rows])

    def with_move(self, move: np.ndarray) -> StepPlan:
        """This plan with another ``move`` (k,) mask."""
        return StepPlan(move, self.length, self.rise, self.energy, self.swing,
                        self.shortened)


class PlanQueue:
    """The rest of every agent's current footstep plan (H steps at most), n agents."""

    def __init__(self, n: int, horizon: int) -> None:
        self.length = np.zeros((n, horizon))
        self.rise = np.zeros((n, horizon))
        self.energy = np.zeros((n, horizon))
        self.swing = np.full((n, horizon, 4, 2), np.nan)
        self.size = np.zeros(n, dtype=np.int64)
        self.next = np.zeros(n, dtype=np.int64)
        self.direction = np.zeros((n, 2))
        self.anchor = np.full((n, 2), np.nan)  # stance where the next step starts [m]

    def clear(self, agents: np.ndarray) -> None:
        """Forget the plans of ``agents`` (they re-plan at their next step)."""
        self.size[agents] = 0


def plan_or_reuse(queue: PlanQueue, footsteps, *, agents: np.ndarray,
                  direction: np.ndarray, stance: np.ndarray, stance_z: np.ndarray,
                  trail: np.ndarray, leg: np.ndarray, speed: np.ndarray,
                  planner: np.ndarray, replan_turn_deg: float,
                  setting: np.ndarray | None = None,
                  threads=None) -> tuple[StepPlan, np.ndarray]:
    """The next step of k moving agents, and which of them planned anew (k,) bool.

    An agent takes the next step of its queued plan when the plan has one left, the
    stance foot is where the plan expected it and the step direction turned by at most
    ``replan_turn_deg`` [deg] (a turn of up to 3° moves the plan's footholds by < 0.14 %
    of their distance); the others plan with ``footsteps``
    (:class:`~crowdwalk.crowd.footsteps.FootstepPlanner`) in one batch and their plans
    are queued. ``direction`` (k, 2) unit, ``stance`` (k, 2) and ``trail`` (k, 2) [m]
    centre-line points of the stance and the trailing foot, ``stance_z`` (k,) [m],
    ``leg`` (k,) leg classes, ``speed`` (k,) [m/s], ``planner`` (k,) names, ``setting``
    (k,) the planner configuration of each (``FootstepPlanner.configs``; None: the first);
    ``threads`` (a :class:`crowdwalk.workers.RowThreads`, optional) finds the planners'
    ground profiles for parts of them at once (the same plans).
    """
    a = agents
    k = a.size
    plan = StepPlan.standing(k).with_move(np.ones(k, bool))
    q = queue.next[a]
    along = (np.einsum("ij,ij->i", queue.direction[a], direction)
             > np.cos(np.radians(replan_turn_deg)))
    reuse = ((q < queue.size[a]) & along
             & (np.linalg.norm(stance - queue.anchor[a], axis=1) < 1e-9))
    if reuse.any():  # the queued steps, and the queues move on
        _take_queued(np.ascontiguousarray(a, dtype=np.int64), q, reuse, queue.length,
                     queue.rise, queue.energy, queue.swing, queue.next, plan.length,
                     plan.rise, plan.energy, plan.swing)
    p = np.flatnonzero(~reuse)
    if p.size:
        ap = a[p]
        d = direction[p]
        trailing = -np.einsum("ij,ij->i", stance[p] - trail[p], d)
        planned = footsteps.plan(stance[p], stance_z[p], direction=d, leg=leg[p],
                                 speed=speed[p], planner=planner[p], trailing=trailing,
                                 setting=None if setting is None else setting[p],
                                 threads=threads)
        f = np.ascontiguousarray
        _queue_plans(p, f(ap, dtype=np.int64), f(planned.ok, dtype=bool),
                     f(planned.step_length, dtype=float), f(planned.step_height, dtype=float),
                     f(planned.energy, dtype=float), f(planned.swing, dtype=float),
                     f(d, dtype=float), plan.move, plan.length, plan.rise, plan.energy,
                     plan.swing, queue.length, queue.rise, queue.energy, queue.swing,
                     queue.size, queue.next, queue.direction)
    return plan, ~reuse


@nb.njit(cache=True, nogil=True)
def _take_queued(a, q, reuse, q_length, q_rise, q_energy, q_swing, q_next, length, rise,
                 energy, swing):
    """Rows ``reuse`` (k,) of :func:`plan_or_reuse`: step ``q`` (k,) of agent ``a``'s
    (k,) queue into the plan's rows, and the queue's next step one on (copies only)."""
    for r in range(a.size):
        if not reuse[r]:
            continue
        i, j = a[r], q[r]
        length[r], rise[r], energy[r] = q_length[i, j], q_rise[i, j], q_energy[i, j]
        swing[r] = q_swing[i, j]
        q_next[i] += 1


@nb.njit(cache=True, nogil=True)
def _queue_plans(rows, agents, ok, sl, sh, en, sw, d, move, length, rise, energy, swing,
                 q_length, q_rise, q_energy, q_swing, q_size, q_next, q_direction):
    """The new plans (m rows; ``ok``, step lengths ``sl``, rises ``sh``, energies ``en``
    (m, H), swings ``sw`` (m, H, 4, 2)) of ``agents`` (m,) along ``d`` (m, 2): their
    first steps into the plan's ``rows`` (m,), the whole plans into the queues (a failed
    plan's queue is empty); copies only."""
    horizon = sl.shape[1]
    for k in range(rows.size):
        r, i = rows[k], agents[k]
        move[r] = ok[k]
        length[r], rise[r], energy[r] = sl[k, 0], sh[k, 0], en[k, 0]
        swing[r] = sw[k, 0]
        q_length[i] = sl[k]
        q_rise[i] = sh[k]
        q_energy[i] = en[k]
        q_swing[i] = sw[k]
        q_size[i] = horizon if ok[k] else 0
        q_next[i] = 1
        q_direction[i, 0], q_direction[i, 1] = d[k, 0], d[k, 1]


def fallback_energy(length: np.ndarray, rise: np.ndarray, *, legs: LegColumns,
                    speed: np.ndarray, config) -> np.ndarray:
    """Chen & Li Eq. 4 energy (k,) [J/kg] of steps the planner did not plan (shortened
    or positioning): the planners' energy model for steps of ``length`` and ``rise``
    (k,) [m] at ``speed`` (k,) [m/s], the swing summit over the higher foothold."""
    from planners.energy import step_energy

    zero = np.zeros(length.size)
    summit = np.maximum(zero, rise) + legs.ankle_height + 0.75 * config.swing_lift
    return step_energy(zero, zero, length, rise, summit, legs, speed, config)[3]


def even_steps(terrain, *, stance: np.ndarray, stance_z: np.ndarray, direction: np.ndarray,
               length: np.ndarray, legs: LegColumns, speed: np.ndarray, config,
               min_step: float) -> StepPlan:
    """Steps of ``length`` (k,) [m] from ``stance`` (k, 2) [m] along ``direction`` (k, 2),
    taken where the whole foot (heel, ankle, toe) lands on even ground (within 2 cm) and
    the step is at least ``min_step`` [m]; the others wait. The energy is
    :func:`fallback_energy`; there is no swing curve."""
    d = direction
    heel, toe = legs.heel_offset, legs.toe_offset
    c = stance + length[:, None] * d
    pts = np.concatenate([c - heel[:, None] * d, c, c + toe[:, None] * d])
    z = terrain.height(pts).reshape(3, -1)
    even = (np.ptp(z, axis=0) <= 0.02) & (length >= min_step)
    rise = z[1] - stance_z
    energy = np.where(even, fallback_energy(length, rise, legs=legs, speed=speed,
                                            config=config), 0.0)
    return StepPlan(even, np.where(even, length, 0.0), rise, energy,
                    np.full((length.size, 4, 2), np.nan), even.copy())


def next_steps(state, queue: PlanQueue, *, agents: np.ndarray, choice, footsteps, legs,
               population, terrain, params, plan_speed: np.ndarray | None = None,
               setting: np.ndarray | None = None, threads=None) -> StepPlan:
    """The steps of k moving ``agents`` along their steering ``choice`` (a
    :class:`~crowdwalk.crowd.steering.StepChoice` of k rows): planned or reused
    (:func:`plan_or_reuse`); shortened to the free length where a neighbour or wall is
    closer than the planned step, if the foot lands on even ground (else the agent
    waits); where no legal plan exists (e.g. the stance foot just short of a riser, where
    no step of the planner's range lands fully on the tread) a short positioning step on
    even ground (0.3 m, else 0.2 m) changes the approach, as people do. Counts plans,
    failures and shortened steps in ``state``. ``plan_speed`` (n,) [m/s] is the speed
    the planner plans each walker's steps for (default its free speed) and ``setting``
    (n,) its planner configuration (crowdwalk.style: a held step length, toe clearance);
    ``threads`` as in :func:`plan_or_reuse`."""
    st, a = state, agents
    d, free = choice.direction, choice.free_length
    plan, planned = plan_or_reuse(
        queue, footsteps, agents=a, direction=d, stance=st.stance[a],
        stance_z=st.stance_z[a], trail=st.trail[a], leg=legs.index[a],
        speed=(population.free_speed if plan_speed is None else plan_speed)[a],
        planner=np.asarray(population.planner_names, dtype=object)[population.group[a]],
        replan_turn_deg=params.replan_turn_deg,
        setting=None if setting is None else setting[a], threads=threads)
    ok = plan.move
    st.plans[a[planned]] += 1
    st.plan_failures[a[planned & ~ok]] += 1

    def even(rows: np.ndarray, length: np.ndarray) -> StepPlan:
        r = a[rows]
        sub = even_steps(terrain, stance=st.stance[r], stance_z=st.stance_z[r],
                         direction=d[rows], length=length, legs=legs.of(r),
                         speed=population.free_speed[r], config=footsteps.config,
                         min_step=params.steering.min_step)
        st.shortened[r[sub.move]] += 1
        return sub

    short = np.flatnonzero(ok & (plan.length > free + 1e-9))
    if short.size:
        plan = plan.put(short, even(short, free[short]))
        queue.clear(a[short])
    failed = np.flatnonzero(~ok)
    for length in (0.3, 0.2):
        if failed.size == 0:
            break
        sub = even(failed, np.minimum(free[failed], length))
        plan = plan.put(failed, sub)
        failed = failed[~sub.move]
    return plan
