"""Local steering: where does the next step go, given the neighbours and the walls?

A step-choice model after the Optimal Steps Model (Seitz & Köster 2012, "Natural
discretization of pedestrian movement in continuous space", Phys. Rev. E 86, 046108;
as implemented in Vadere): at each heel strike an agent scores candidate step
directions by a utility — distance to its route target, personal-space repulsion from
neighbours and walls — and takes the best one, or stays put when no step improves it.

Deviation from OSM, for the "bodies never overlap" guarantee: a candidate is *hard*
limited by a swept-body test in the spirit of velocity obstacles (Fiorini & Shiller 1998):
the body moving along its straight sweep during the step (a disc of the agent's radius)
must keep clear, at every instant from now on, of every neighbour moving along its
committed remaining sweep and standing at its end afterwards, and of the walls. Each
candidate gets the longest step that stays clear ("free length"); the footstep planner may
then shorten the step but never lengthen it beyond that. Because every agent only commits
motions that are clear of all committed motions (and an agent stands still until it
commits the next), no two bodies ever overlap. The test is in time, not against the
neighbour's whole sweep: a follower may step into the room its leader vacates during the
same step, as people walking in line do (they even fall into lockstep at high density,
Jelić et al. 2012, Phys. Rev. E 86, 046111); the whole-sweep test kept a follower about
a step further behind (through a 1 m opening 1.09 /s instead of 1.49 /s, all else equal).

Counterflow: neighbours moving towards the agent are also repelled at their position
``anticipation`` seconds ahead (anticipation as in Moussaïd et al. 2011 / Karamouzas et
al. 2014), and a small right-hand bias breaks the left/right symmetry so opposing streams
form lanes instead of deadlocking (Helbing & Molnár 1995 observe the same symmetry
breaking in real crowds).

Everything is vectorised over (deciding agents × candidate directions × step lengths ×
neighbours); no Python loop over agents.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from crowdwalk.crowd.clearance import ClearanceField
from crowdwalk.crowd.geometry import distance, point_segment_distance, segment_distance
from crowdwalk.crowd.shape import clear_runs, disc_centres
from crowdwalk.crowd.speed import GapSteps
from crowdwalk.errors import invalid

__all__ = ["SteeringParams", "Neighbours", "StepChoice", "choose_steps"]


@dataclass(frozen=True)
class SteeringParams:
    """Weights of the step utility, in metres of route progress they are worth.

    Attributes
    ----------
    offsets_deg : tuple of float
        Candidate step directions relative to the route direction [deg].
    step_lengths : tuple of float
        Step lengths at which the swept body is tested [m], increasing.
    min_step : float
        Shortest step an agent takes rather than waiting [m].
    foot_clearance : float
        Least distance of a new foothold's centre line from the walls [m].
    personal_weight, personal_range : float
        Neighbour repulsion ``w exp(-(d - r_i - r_j) / range)`` [m], [m].
    soft_neighbours : int
        Nearest neighbours in the repulsion and anticipation terms [-].
    anticipation : float
        How far ahead oncoming neighbours are extrapolated [s].
    oncoming_neighbours : int
        The nearest oncoming neighbours (among all gathered, not only the
        ``soft_neighbours``) in the anticipation term [-]. Before, only oncoming walkers
        among the 12 nearest counted: in a group the 12 nearest are its own members, so
        an oncoming group was seen only on contact. Counterflow 2 × 50 in 4 m within
        1.5 × the free walk: seeds 1–5 3 → 4 of 5, held-out seeds 6–10 0 → 4 of 5
        (with ``right_bias`` 0.09; docs/architecture.md).
    wall_weight, wall_range : float
        Wall repulsion ``w exp(-(clearance - r) / range)`` [m], [m].
    turn_weight : float
        Cost of turning away from the current heading, ``w (1 - cos Δψ)`` [m].
    right_bias : float
        Cost of stepping left of the route direction, ``w max(sin offset, 0)`` [m]:
        0.09, chosen on the counterflow seeds 1–5 (0.06: 2 of 5 within 1.5 × the free
        walk, 0.09: 4 of 5; 0.12 failed RiMEA 9, ratio 1.43), validated on seeds 6–10.
    wait_cost : float
        Cost of standing still for one decision [m].
    give_way_after, give_way_weight : float
        Standing face to face with another walker for longer than ``give_way_after`` [s]
        adds ``give_way_weight`` [m/s] per further second to the cost of standing.
    clog_after : float
        Standing longer than this [s] (whoever the neighbours are) adds the same cost.
    twists_deg : tuple of float
        Shoulder twists [deg] a walker tries (the way it is turned already, else to the
        left), after keeping its facing, when it cannot take its preferred step facing
        where it walks (:mod:`~crowdwalk.crowd.shape`).
    keep_facing : bool
        Whether a walker that cannot step ahead facing forward tries keeping its facing
        (False, with no ``twists_deg``: the torso always faces the step direction).
    twist_weight : float
        Cost of walking with the shoulders twisted by φ, ``w (1 - cos φ)`` [m].
    turn_limit_deg : float or None
        Turn limit (gaitlevel; Chen & Li §5.4, ``planners.split_turn``): a step may turn
        the walking direction by at most this much from the current heading [deg], so a
        larger turn is split over consecutive steps (§5.4's threshold 45°); a walker
        that was standing may turn as it likes. None (default): no limit. Opt-in,
        measured (docs/architecture.md "Turn limit"): at 45° the corner's worst pelvis
        second difference falls 14.7 -> 7.7 cm and the park's 14.0 -> 5.4 cm, but
        bottleneck flows fall below Seyfried's band at every width.
    turn_limit_spare : float
        A walker whose step straight on (its current heading) is cut below this fraction
        of its nominal step, by neighbours or walls, is spared the turn limit too [-]
        (manoeuvring in a queue or in front of an opening). 0 (default): only standing
        walkers are spared; 1.0 was measured to lose the corner's and park's gains and
        not to keep the bottleneck flows either.
    """

    offsets_deg: tuple[float, ...] = (0.0, -12.0, 12.0, -25.0, 25.0, -40.0, 40.0, -60.0,
                                      60.0, -90.0, 90.0)
    step_lengths: tuple[float, ...] = (0.15, 0.3, 0.45, 0.6, 0.75, 0.9)
    min_step: float = 0.15
    foot_clearance: float = 0.05
    personal_weight: float = 0.35
    personal_range: float = 0.2
    soft_neighbours: int = 12
    anticipation: float = 1.5
    oncoming_neighbours: int = 10
    wall_weight: float = 0.3
    wall_range: float = 0.1
    turn_weight: float = 0.05
    right_bias: float = 0.09
    wait_cost: float = 0.05
    give_way_after: float = 1.0
    give_way_weight: float = 0.3
    clog_after: float = 2.5
    twists_deg: tuple[float, ...] = (60.0,)
    keep_facing: bool = True
    twist_weight: float = 0.05
    turn_limit_deg: float | None = None
    turn_limit_spare: float = 0.0

    def __post_init__(self) -> None:
        t = self.turn_limit_deg
        if t is not None and not (np.isfinite(t) and 0.0 < t <= 180.0):
            raise invalid("SteeringParams", "turn_limit_deg", "None or in (0, 180] [deg]", t)
        if not (np.isfinite(self.turn_limit_spare) and self.turn_limit_spare >= 0.0):
            raise invalid("SteeringParams", "turn_limit_spare", "finite and >= 0 [-]",
                          self.turn_limit_spare)


@dataclass(frozen=True)
class Neighbours:
    """Neighbours of the m deciding agents, K per agent (padded).

    Attributes
    ----------
    valid : (m, K) bool
    now : (m, K, 2) float
        Neighbour positions now [m].
    end : (m, K, 2) float
        End of the neighbour's committed step (= ``now`` when standing) [m].
    velocity : (m, K, 2) float
        Neighbour velocity [m/s].
    radius : (m, K) float
        Neighbour body radius [m].
    heading : (m, K) float, optional
        Neighbour walking direction [rad] (tells who faces whom when both stand).
    remaining : (m, K) float, optional
        Time until the neighbour reaches ``end`` [s] (0 when standing). With it (and the
        deciding agents' step timing) the swept-body test is made in time: see
        :func:`choose_steps`.
    yaw_now, yaw_end : (m, K) float, optional
        Neighbour torso facing now and at ``end`` [rad] (default: ``heading``).
    shape : (m, K, 3) float, optional
        Neighbour outlines (:meth:`~crowdwalk.crowd.shape.BodyShape.packed` rows;
        default: discs of ``radius``).
    agent : (m, K) int, optional
        The neighbours' agent indices (padding: any index, marked not ``valid``).
    """

    valid: np.ndarray
    now: np.ndarray
    end: np.ndarray
    velocity: np.ndarray
    radius: np.ndarray
    heading: np.ndarray | None = None
    remaining: np.ndarray | None = None
    yaw_now: np.ndarray | None = None
    yaw_end: np.ndarray | None = None
    shape: np.ndarray | None = None
    agent: np.ndarray | None = None

    def outlines(self) -> np.ndarray:
        """(m, K, 3) the neighbours' outlines (discs of ``radius`` unless given)."""
        if self.shape is not None:
            return self.shape
        return np.stack([self.radius, self.radius, np.zeros_like(self.radius)], axis=-1)

    def yaws(self) -> tuple[np.ndarray, np.ndarray]:
        """(m, K) torso facing now and at ``end`` [rad] (default ``heading``, else 0)."""
        now = self.yaw_now if self.yaw_now is not None else self.heading
        now = np.zeros(self.valid.shape) if now is None else now
        return now, (now if self.yaw_end is None else self.yaw_end)


@dataclass(frozen=True)
class StepChoice:
    """Steering result for m agents: ``direction`` (m, 2) unit, ``free_length`` (m,)
    longest clear step along it [m], ``move`` (m,) False where the agent waits, ``yaw``
    (m,) the torso's facing at the step's end [rad] (unwrapped against the current one),
    ``utility`` (m,) the choice's cost [m] (lower is better)."""

    direction: np.ndarray
    free_length: np.ndarray
    move: np.ndarray
    yaw: np.ndarray
    utility: np.ndarray

    def take(self, rows: np.ndarray) -> StepChoice:
        """The choices at ``rows``."""
        return StepChoice(self.direction[rows], self.free_length[rows], self.move[rows],
                          self.yaw[rows], self.utility[rows])


def _rotate(v: np.ndarray, angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1]], axis=-1)


def choose_steps(
    position: np.ndarray,
    stance: np.ndarray,
    *,
    heading: np.ndarray,
    radius: np.ndarray,
    route_direction: np.ndarray,
    target: np.ndarray,
    nominal_step: np.ndarray,
    neighbours: Neighbours,
    clearance: ClearanceField,
    params: SteeringParams = SteeringParams(),
    speed: np.ndarray | None = None,
    stuck: np.ndarray | None = None,
    step_time: np.ndarray | None = None,
    lag: np.ndarray | None = None,
    shape: np.ndarray | None = None,
    yaw: np.ndarray | None = None,
    gap: GapSteps | None = None,
    wall_scale: np.ndarray | None = None,
    personal_scale: np.ndarray | None = None,
) -> StepChoice:
    """Choose the next step direction for m deciding agents.

    Parameters
    ----------
    position : (m, 2)
        Body positions now (midpoint of the feet) [m].
    stance : (m, 2)
        Centre-line point of the stance foot [m]; a step of length L along ``d`` ends the
        body at ``stance + L/2 d``.
    heading : (m,)
        Current walking direction [rad].
    radius : (m,)
        Body radii [m].
    route_direction : (m, 2)
        Unit direction of the route ahead.
    target : (m, 2)
        Route point the agent heads for [m].
    nominal_step : (m,)
        Preferred free step length [m].
    neighbours : Neighbours
        K neighbours per agent.
    clearance : ClearanceField
        Wall distance field.
    params : SteeringParams
    speed : (m,), optional
        Walking speeds for the anticipation term [m/s] (default 2 nominal steps per s).
    stuck : (m,), optional
        How long each agent has been standing [s] (for giving way).
    step_time : (m,), optional
        Shortest step duration [s]; a step of length L lasts ``max(L / speed,
        step_time)``. Given with ``neighbours.remaining``, the hard test is made in time
        (the two bodies moving along their sweeps at the same time, each standing at its
        end afterwards) instead of against the neighbour's whole remaining sweep: a
        follower may step into the room its leader is vacating during the same step.
    lag : (m,), optional
        How long ago each agent's step would have started (its heel strike) [s].
    shape : (m, 3), optional
        The agents' outlines (:meth:`~crowdwalk.crowd.shape.BodyShape.packed` rows;
        default: discs of ``radius``). Used by the in-time test and the walls.
    yaw : (m,), optional
        Torso facing now [rad] (default: ``heading``).
    gap : crowdwalk.crowd.speed.GapSteps, optional
        The contact-gap model's steps: the utility then scores each candidate direction
        at the step the model allows along it (every neighbour counted), so that a
        walker falls in beside-behind the one ahead (the zipper) or steps round an
        oncoming one rather than close up behind.
    wall_scale : (m,), optional
        Factor on the soft wall term per agent (``CrowdParams.opening_ease``: eased
        inside openings); None: 1.
    personal_scale : (m,), optional
        Factor on the neighbour repulsion (not the anticipation of oncoming walkers) per
        agent, the same way; None: 1.

    Returns
    -------
    StepChoice
    """
    m = position.shape[0]
    if m == 0:
        return StepChoice(np.zeros((0, 2)), np.zeros(0), np.zeros(0, bool), np.zeros(0),
                          np.zeros(0))
    yaw = heading if yaw is None else np.asarray(yaw, dtype=float)
    shape = (np.column_stack([radius, radius, np.zeros(m)]) if shape is None
             else np.asarray(shape, dtype=float))
    speed = 2.0 * nominal_step if speed is None else np.asarray(speed, dtype=float)
    lengths = np.asarray(params.step_lengths)  # (L,)
    # candidates: fixed offsets from the route direction, plus keeping the current heading
    # (so a walker going straight keeps its exact line and its footstep plan)
    route_angle = np.arctan2(route_direction[:, 1], route_direction[:, 0])
    keep = (heading - route_angle + np.pi) % (2 * np.pi) - np.pi
    offsets = np.concatenate([np.broadcast_to(np.deg2rad(params.offsets_deg), (m, len(
        params.offsets_deg))), keep[:, None]], axis=1)  # (m, C)
    dirs = _rotate(route_direction[:, None, :], offsets)  # (m, C, 2)
    ends = stance[:, None, None, :] + 0.5 * lengths[None, None, :, None] * dirs[:, :, None, :]
    # (m, C, L, 2): body position at the end of a step of each length
    cand_heading = np.arctan2(dirs[..., 1], dirs[..., 0])  # (m, C)

    def facing(turned) -> np.ndarray:  # (m, C) torso facing at the step's end
        turn = cand_heading + turned - yaw[:, None]
        return yaw[:, None] + (turn + np.pi) % (2 * np.pi) - np.pi  # unwrapped

    # hard limits: walls (sampled at each length's end point and the sweep's midpoint)
    # a step may not bring the body closer to a wall than its radius, unless it was
    # already closer (then it may not get closer still: agents can leave a wall); and at
    # the sweep's quarters where the body passes near a wall (a straight sweep past a
    # convex corner dips closest between the samples: RiMEA 6 measured a body edge 1.6 cm
    # into the inner corner with end and midpoint alone); the new foothold itself must
    # lie inside the walkable area (one kernel: ClearanceField.step_walls)
    wall_ok, near = clearance.step_walls(position, stance, ends, dirs, lengths, radius,
                                         shape[:, 1] + 2 * shape[:, 2],
                                         params.foot_clearance)
    # hard limits: swept bodies of neighbours (only those a step could reach)
    timed = neighbours.remaining is not None and step_time is not None
    pa = np.zeros(0, dtype=np.int64)
    if neighbours.valid.shape[1]:
        need = radius[:, None] + neighbours.radius  # (m, K)
        if timed:  # the outlines' holding discs
            nb_shape = neighbours.outlines()
            need = (np.maximum(shape[:, 0], shape[:, 1] + shape[:, 2])[:, None]
                    + np.maximum(nb_shape[..., 0], nb_shape[..., 1] + nb_shape[..., 2]))
        gap0 = point_segment_distance(position[:, None, :], neighbours.now, neighbours.end)
        reach = distance(ends, position[:, None, None, :]).max(axis=(1, 2))
        relevant = neighbours.valid & (gap0 - need < reach[:, None] + 1e-9)
        # the relevant (agent, neighbour) pairs only, not every agent padded to the most
        # crowded one's count
        pa, pk = np.nonzero(relevant)  # (P,), agent-major
    n_c, n_l = dirs.shape[1], lengths.size

    def clear(rows: np.ndarray, yaw_end: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(r, C, L) bool: the steps of ``rows`` (ascending) clear of walls and
        neighbours, the torsos turning to ``yaw_end`` (m, C); and the same for the
        centre discs alone (no facing can do better)."""
        centre = wall_ok[rows]
        ok = centre & _shoulders_clear(
            position[rows], ends[rows], yaw=yaw[rows], yaw_end=yaw_end[rows],
            shape=shape[rows], clearance=clearance,
            near=near[rows])
        local = np.full(m, -1)
        local[rows] = np.arange(rows.size)
        sel = np.flatnonzero(local[pa] >= 0)
        if sel.size == 0:
            return ok, centre
        qa, qk = pa[sel], pk[sel]
        centre = centre.copy()
        if timed:
            # in time: both outlines move along their sweeps from now on and then stand
            # (the candidate's body from ``position`` to ``ends`` over the step, its
            # torso turning from ``yaw`` to ``yaw_end``)
            dur = np.maximum(lengths[None, :] / speed[:, None], step_time[:, None])
            nb_yaw, nb_yaw_end = neighbours.yaws()
            # only a run's lengths up to its first blocked one count (free_lengths): the
            # kernel stops there (the same result; 2.1 times faster on the 1,000-walker
            # stadium's calls; scripts/check_identical_runs.py: identical runs)
            a_ok = np.ones((m, n_c * n_l), bool)
            a_centre_ok = a_ok.copy()
            a_ok[rows] = ok.reshape(rows.size, -1)
            a_centre_ok[rows] = centre.reshape(rows.size, -1)
            # only the signs are kept, reduced over each walker's neighbours in the
            # kernel (clear_runs: the signs of body_gaps; identical runs)
            clear_runs(
                qa, a_start=position, a_yaw0=yaw, a_end=ends.reshape(m, n_c * n_l, 2),
                a_yaw1=np.repeat(yaw_end, n_l, axis=1), a_duration=np.tile(dur, (1, n_c)),
                a_elapsed=np.zeros(m) if lag is None else lag, a_shape=shape,
                b_now=neighbours.now[qa, qk], b_yaw_now=nb_yaw[qa, qk],
                b_end=neighbours.end[qa, qk], b_yaw_end=nb_yaw_end[qa, qk],
                b_remaining=neighbours.remaining[qa, qk], b_shape=nb_shape[qa, qk],
                runs=n_l, ok=a_ok, centre_ok=a_centre_ok)
            return (a_ok[rows].reshape(rows.size, n_c, n_l),
                    a_centre_ok[rows].reshape(rows.size, n_c, n_l))
        else:
            q0 = neighbours.now[qa, qk][:, None, None, :]  # (P, 1, 1, 2)
            q1 = neighbours.end[qa, qk][:, None, None, :]
            d = segment_distance(position[qa][:, None, None, :], ends[qa], q0, q1)
            blocked = centre_blocked = d < need[qa, qk][:, None, None]  # (P, C, L)
        first = np.flatnonzero(np.concatenate([[True], qa[1:] != qa[:-1]]))
        ok[local[qa[first]]] &= ~np.logical_or.reduceat(blocked, first, axis=0)
        centre[local[qa[first]]] &= ~np.logical_or.reduceat(centre_blocked, first, axis=0)
        return ok, centre

    def free_lengths(ok: np.ndarray) -> np.ndarray:  # feasible lengths from the short end
        n_free = np.cumprod(ok, axis=2).sum(axis=2)
        return np.where(n_free > 0, lengths[np.maximum(n_free - 1, 0)], 0.0)

    everyone = np.arange(m)
    yaw_end = facing(0.0)
    ok, centre = clear(everyone, yaw_end)
    free = free_lengths(ok)  # (m, C)
    if timed:
        # walkers who cannot take their preferred step ahead facing forward, where a
        # body as narrow as it is deep could, try keeping their facing (a side step or a
        # step back without turning: shuffling in a queue), then turning their shoulders
        # by each twist, the way they are turned already (else to the left; the outline
        # is symmetric): a candidate takes the first facing that lets it step strictly
        # further than facing forward
        ahead = np.abs(offsets) <= np.deg2rad(25.0) + 1e-9
        want = np.minimum(nominal_step, lengths[-1]) - 1e-9
        narrow = free_lengths(centre)  # no facing steps further
        rows = np.flatnonzero((np.where(ahead, free, 0.0).max(axis=1) < want)
                              & (narrow > free + 1e-9).any(axis=1))
        side = np.where(((yaw - heading + np.pi) % (2 * np.pi) - np.pi) < -1e-3, -1.0, 1.0)
        options = [np.broadcast_to(yaw[:, None], (m, n_c))] if params.keep_facing else []
        options += [facing(side[:, None] * phi) for phi in np.deg2rad(params.twists_deg)]
        for twisted in options if rows.size else ():
            reach_t = free_lengths(clear(rows, twisted)[0])
            r_, c_ = np.nonzero(reach_t > free[rows] + 1e-9)
            free[rows[r_], c_] = reach_t[r_, c_]
            yaw_end[rows[r_], c_] = twisted[rows[r_], c_]
    turned = (yaw_end - cand_heading + np.pi) % (2 * np.pi) - np.pi  # (m, C) twist [rad]

    # utility at the end point of the preferred (or longest clear) step
    use = np.minimum(free, nominal_step[:, None])  # (m, C)
    if gap is not None:
        use = np.minimum(use, gap.along(dirs, everyone=True)[1])
    end = stance[:, None, :] + 0.5 * use[..., None] * dirs  # (m, C, 2)
    cand = np.concatenate([end, position[:, None, :]], axis=1)  # (m, C+1, 2); last = wait
    utility = distance(target[:, None, :], cand)
    if neighbours.valid.shape[1]:
        # soft terms from the nearest ``soft_neighbours`` (sorted nearest first); the hard
        # limit above used every neighbour a step could reach
        ks = params.soft_neighbours
        nb = Neighbours(*(None if a is None else a[:, :ks] for a in (
            neighbours.valid, neighbours.now, neighbours.end, neighbours.velocity,
            neighbours.radius, neighbours.heading)))
        rr = radius[:, None, None] + nb.radius[:, None, :]
        gap_end = distance(cand[:, :, None, :], nb.end[:, None, :, :])
        rep = params.personal_weight * np.exp(-(gap_end - rr) / params.personal_range)
        if personal_scale is not None:
            rep = rep * np.asarray(personal_scale, float)[:, None, None]
        # anticipation: the closest approach within ``anticipation`` seconds if this agent
        # walked the candidate direction at its speed and the oncoming neighbour kept its
        # velocity (the time-to-collision idea of Karamouzas et al. 2014)
        utility += np.where(nb.valid[:, None, :], rep, 0.0).sum(axis=-1)
        # the nearest ``oncoming_neighbours`` oncoming walkers among all the neighbours
        # (not among the nearest few, who in a group walking together are its members)
        own_dir = np.stack([np.cos(heading), np.sin(heading)], axis=-1)
        oncoming = neighbours.valid & (np.einsum("mkj,mj->mk", neighbours.velocity,
                                                 own_dir) < -0.1)
        ka = min(params.oncoming_neighbours, oncoming.shape[1])
        pick = np.argsort(~oncoming, axis=1, kind="stable")[:, :ka]  # nearest first
        oncoming = np.take_along_axis(oncoming, pick, axis=1)
        on_v = np.take_along_axis(neighbours.velocity, pick[..., None], axis=1)
        on_p = np.take_along_axis(neighbours.now, pick[..., None], axis=1)
        on_r = np.take_along_axis(neighbours.radius, pick, axis=1)
        mine = speed[:, None, None] * dirs  # (m, C, 2) candidate velocities
        mine = np.concatenate([mine, np.zeros((m, 1, 2))], axis=1)  # waiting stands
        rel_p = (on_p - position[:, None, :])[:, None, :, :]  # (m, 1, K, 2)
        rel_v = on_v[:, None, :, :] - mine[:, :, None, :]  # (m, C+1, K, 2)
        vv = np.einsum("mckj,mckj->mck", rel_v, rel_v)
        t_close = np.clip(-np.einsum("mckj,mckj->mck", np.broadcast_to(rel_p, rel_v.shape),
                                     rel_v) / np.maximum(vv, 1e-12), 0.0, params.anticipation)
        closest = distance(rel_p, -t_close[..., None] * rel_v)  # |p + t v|
        ra = radius[:, None, None] + on_r[:, None, :]
        utility += np.where(oncoming[:, None, :], params.personal_weight
                            * np.exp(-(closest - ra) / params.personal_range), 0.0).sum(axis=-1)
    wall_gap = clearance(cand) - radius[:, None]  # soft term uses the full radius
    wall_w = params.wall_weight if wall_scale is None else params.wall_weight * np.asarray(
        wall_scale, float)[:, None]
    utility += wall_w * np.exp(-np.maximum(wall_gap, 0.0) / params.wall_range)
    utility[:, :-1] += params.twist_weight * (1.0 - np.cos(turned))
    utility[:, :-1] += params.turn_weight * (1.0 - np.cos(cand_heading - heading[:, None]))
    utility[:, :-1] += params.right_bias * np.maximum(np.sin(offsets), 0.0)
    utility[:, :-1] = np.where(np.abs(offsets) <= np.pi / 2 + 1e-9, utility[:, :-1], np.inf)
    utility[:, -1] += params.wait_cost
    if stuck is not None and neighbours.heading is not None and neighbours.valid.shape[1]:
        # two walkers standing face to face: after ``give_way_after`` seconds waiting gets
        # dearer every second, so a side step (which gains nothing towards the target)
        # wins and the pair passes; both have the same right-hand bias
        own_dir = np.stack([np.cos(heading), np.sin(heading)], axis=-1)
        facing = ((np.cos(neighbours.heading - heading[:, None]) < -0.5)
                  & (np.linalg.norm(neighbours.now - position[:, None, :], axis=-1) < 1.2)
                  & (np.einsum("mkj,mj->mk", neighbours.now - position[:, None, :], own_dir) > 0)
                  & neighbours.valid).any(axis=1)
        late = np.maximum(np.asarray(stuck, dtype=float) - params.give_way_after, 0.0)
        utility[:, -1] += np.where(facing, params.give_way_weight * late, 0.0)
    if stuck is not None:
        # a clog (walkers wedged against each other and the walls in front of a narrow
        # opening): after ``clog_after`` seconds every standing walker grows impatient,
        # so that steps aside or back (see CrowdSimulation: the backward fan) loosen it
        late = np.maximum(np.asarray(stuck, dtype=float) - params.clog_after, 0.0)
        utility[:, -1] += params.give_way_weight * late
    utility[:, :-1] = np.where(free >= params.min_step, utility[:, :-1], np.inf)
    if params.turn_limit_deg is not None:
        # the last candidate keeps the current heading: how far the walker can go on
        utility[:, :-1] = np.where(_within_turn_limit(
            cand_heading, heading, free[:, -1], nominal_step, stuck, params),
            utility[:, :-1], np.inf)

    n_dir = offsets.shape[1]
    best = np.argmin(utility, axis=1)
    move = best < n_dir
    pick = np.minimum(best, n_dir - 1)
    rows = np.arange(m)
    return StepChoice(
        direction=dirs[rows, pick],
        free_length=np.where(move, free[rows, pick], 0.0),
        move=move,
        yaw=np.where(move, yaw_end[rows, pick], yaw),
        utility=utility[rows, best],
    )


def _within_turn_limit(cand_heading, heading, ahead, nominal_step, stuck,
                       params: SteeringParams) -> np.ndarray:
    """(m, C) bool: candidates (headings (m, C) [rad]) within ``params.turn_limit_deg``
    of the current ``heading`` (m,) [rad], or spared: a walker whose step straight on,
    ``ahead`` (m,) [m], is shorter than ``turn_limit_spare`` × ``nominal_step`` (m,)
    [m], or that was standing (``stuck`` (m,) [s] > 0)."""
    turn = np.abs((cand_heading - heading[:, None] + np.pi) % (2 * np.pi) - np.pi)
    ok = turn <= np.deg2rad(params.turn_limit_deg) + 1e-9
    spared = ahead < params.turn_limit_spare * nominal_step - 1e-9
    if stuck is not None:
        spared |= np.asarray(stuck, dtype=float) > 0.0
    return ok | spared[:, None]


def _shoulders_clear(position, ends, *, yaw, yaw_end, shape, clearance,
                     near) -> np.ndarray:
    """(m, C, L) bool: the shoulder discs keep their radius (widened for the turn) from
    the walls at the step's end and halfway, or do not come closer than they are now.
    Only where the centre's clearance ``near`` (m, C, L) [m] (the smaller at the end and
    halfway) is within the outline's reach plus the largest widening are they tested
    (clearance grows by at most the distance moved)."""
    ok = np.ones(ends.shape[:-1], bool)
    offset = shape[:, 2]
    reach = shape[:, 1] + 2 * offset
    i, c, l = np.nonzero((near < reach[:, None, None]) & (offset > 0)[:, None, None])
    if i.size == 0:
        return ok
    y0, y1 = yaw[i], yaw_end[i, c]
    bend = offset[i] * (1.0 - np.cos(0.5 * (y1 - y0)))
    now = disc_centres(position[i], y0, offset[i])[:, 1:]  # (k, 2, 2): left, right
    end = disc_centres(ends[i, c, l], y1, offset[i])[:, 1:]
    r = shape[i, 1][:, None] + bend[:, None]
    r = np.minimum(r, clearance(now) - 1e-6)
    ok[i, c, l] = np.all((clearance(end) >= r) & (clearance(0.5 * (now + end)) >= r), axis=1)
    return ok
