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

The work is two compiled kernels over the deciding agents' rows
(:mod:`~crowdwalk.crowd.steering_kernels`: the candidates' clear lengths, then their
utilities and the choice), which hold no GIL, so the crowd's row threads steer on every
core at once; no Python loop over agents.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from crowdwalk.crowd.clearance import ClearanceField
from crowdwalk.crowd.speed import GapSteps
from crowdwalk.crowd.steering_kernels import step_limits, step_utility
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
    score_same_time: bool = False,
    limits: Neighbours | None = None,
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
    score_same_time : bool
        With ``gap``: each direction is scored at the distance its allowed speed covers
        in one step at the free cadence (``GapSteps.along(same_time=True)``), so that
        directions compare by speed (``CrowdParams.headway_same_time``).
    limits : Neighbours, optional
        The bodies of the hard step test (m, K'), when they are not ``neighbours``
        (``CrowdParams.mouth_priority``: the neighbours and the reserved next steps of
        those with priority, :mod:`~crowdwalk.crowd.mouth_priority`); the soft terms
        use ``neighbours``.

    Returns
    -------
    StepChoice
    """
    m = position.shape[0]
    if m == 0:
        return StepChoice(np.zeros((0, 2)), np.zeros(0), np.zeros(0, bool), np.zeros(0),
                          np.zeros(0))
    f = np.ascontiguousarray
    position, stance = f(position, float), f(stance, float)
    heading, radius = f(heading, float), f(radius, float)
    nominal_step = f(nominal_step, float)
    yaw = heading if yaw is None else f(yaw, float)
    shape = (np.column_stack([radius, radius, np.zeros(m)]) if shape is None
             else f(shape, float))
    speed = 2.0 * nominal_step if speed is None else f(speed, float)
    nbs = neighbours
    hard = nbs if limits is None else limits
    timed = hard.remaining is not None and step_time is not None
    n_k = nbs.valid.shape[1]
    nb_yaw_now, nb_yaw_end = hard.yaws()
    # zeros only where a term is absent (an (m, K) array per call otherwise unused)
    none = np.zeros((m, n_k)) if nbs.heading is None or (not timed and hard is nbs) else None
    remaining = (f(hard.remaining, float) if timed
                 else none if hard is nbs else np.zeros(hard.valid.shape))
    prm = params
    field = (clearance.distance, float(clearance.origin[0]), float(clearance.origin[1]),
             float(clearance.cell))
    # candidates and the longest step along each clear of the walls and the neighbours
    offsets, cand_heading, dirs, free, yaw_end = step_limits(
        position, stance, heading, f(route_direction, float), yaw, radius, shape, speed,
        f(step_time, float) if timed else np.zeros(m),
        np.zeros(m) if lag is None else f(lag, float), nominal_step, timed,
        f(hard.valid, bool), f(hard.now, float), f(hard.end, float), f(hard.radius, float),
        f(nb_yaw_now, float), f(nb_yaw_end, float),
        remaining, f(hard.outlines(), float), field[0],
        clearance.block_least, *field[1:], np.deg2rad(prm.offsets_deg),
        np.asarray(prm.step_lengths, float), float(prm.foot_clearance),
        float(np.deg2rad(25.0) + 1e-9), bool(prm.keep_facing), np.deg2rad(prm.twists_deg))
    # the utility at the end point of the preferred (or longest clear) step
    cap = np.full(free.shape, np.inf) if gap is None else f(
        gap.along(dirs, everyone=True, same_time=score_same_time)[1], float)
    ones = np.ones(m)
    weights = np.array([prm.personal_weight, prm.personal_range, prm.soft_neighbours,
                        prm.anticipation, prm.oncoming_neighbours, prm.wall_weight,
                        prm.wall_range, prm.turn_weight, prm.right_bias, prm.wait_cost,
                        prm.give_way_after, prm.give_way_weight, prm.clog_after,
                        prm.twist_weight, prm.min_step, np.pi / 2 + 1e-9], float)
    turn_limit = np.array([np.nan if prm.turn_limit_deg is None else
                           np.deg2rad(prm.turn_limit_deg) + 1e-9, prm.turn_limit_spare])
    direction, free_length, move, chosen_yaw, utility = step_utility(
        position, stance, f(target, float), heading, yaw, radius, speed, nominal_step,
        np.zeros(m) if stuck is None else f(stuck, float), offsets,
        cand_heading, dirs, free, yaw_end, cap, f(nbs.valid, bool), f(nbs.now, float),
        f(nbs.end, float), f(nbs.velocity, float), f(nbs.radius, float),
        none if nbs.heading is None else f(nbs.heading, float), nbs.heading is not None,
        ones if personal_scale is None else f(personal_scale, float),
        ones if wall_scale is None else f(wall_scale, float), *field, weights, turn_limit)
    return StepChoice(direction=direction, free_length=free_length, move=move,
                      yaw=chosen_yaw, utility=utility)
