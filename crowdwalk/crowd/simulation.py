"""The crowd simulation: event-driven footsteps of many agents.

Each agent decides at its heel strikes. Per tick, every agent whose heel strike (or end
of a wait) falls in the tick decides, all of them in one batch:

1. route ahead — project onto its route polyline, test arrival, pick the route point
   ``target_distance`` ahead (:mod:`crowdwalk.crowd.navigation`);
2. local steering with the neighbours from one ``cKDTree`` query per tick
   (:mod:`crowdwalk.crowd.steering`): a step direction and the longest clear step;
3. footsteps: the next step of the agent's current plan while it keeps its line (Chen &
   Li plan n steps and walk them), else the ground profile along the local path and
   ``planners.plan_batch`` for all re-planning agents at once
   (:mod:`crowdwalk.crowd.footsteps`); a step longer than the clear length is shortened
   where the whole foot lands on even ground, else the agent waits; the exact sweep of
   the step is verified against the neighbours, then against the other agents deciding
   in the same tick;
4. the step's duration from the speed model (below) and the MetaGait/Animator command
   (batched per output frame).

Waiting agents bring their feet together (on even ground) or shift their weight to the
other foot; standing face to face, or wedged in a clog, they grow impatient and step
aside or back; without progress along the route for a while they re-route.

Between heel strikes the body (the midpoint between the two feet's centre-line
footholds) moves linearly from its position at the heel strike to the midpoint after the
new foothold. Ticks are aligned with output frames so frames are exact interpolations.

Speed model (deviation from Chen & Li, whose Table 1 shortens the phases equally for up-
and downhill): the step duration is step length / speed with the agent's free speed
scaled on stairs by Weidmann's (1993) measured horizontal stair speeds (0.610 m/s up,
0.694 m/s down against 1.34 m/s level) and on slopes by Tobler's (1993) hiking function;
a level step never takes less than 1/cadence at the free speed (Fukuchi et al. 2018
cadence fit), so short steps in a queue are slow steps, not a shuffle at high cadence.
"""

from __future__ import annotations

import time as _time
from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np
from scipy.spatial import cKDTree

from crowdwalk.crowd.clearance import ClearanceField
from crowdwalk.crowd.footsteps import FootstepPlanner
from crowdwalk.crowd.geometry import segment_distance, step_distance
from crowdwalk.crowd.navigation import RouteTable
from crowdwalk.crowd.steering import Neighbours, SteeringParams, choose_steps
from crowdwalk.errors import invalid
from crowdwalk.population import Population, cadence_at, step_length_at
from crowdwalk.sinks import Snapshot
from crowdwalk.steps import StepBatch

__all__ = ["CrowdParams", "CrowdSimulation", "WAITING", "ACTIVE", "ARRIVED"]

WAITING, ACTIVE, ARRIVED = 0, 1, 2

#: Fields of ``planners.Leg`` the crowd gathers per agent (``length`` = thigh + shank).
_LEG_FIELDS = ("thigh", "shank", "foot_length", "heel_offset", "toe_offset", "ankle_height",
               "length")

#: Weidmann (1993): horizontal speed on stairs, up and down, over level speed 1.34 m/s.
STAIR_UP_FACTOR = 0.610 / 1.34
STAIR_DOWN_FACTOR = 0.694 / 1.34


@dataclass(frozen=True)
class CrowdParams:
    """Crowd model parameters.

    Attributes
    ----------
    radius_ratio : float
        Body radius over body height [-] (0.105: 0.18 m for a 1.71 m person, so that two
        bodies standing one behind the other are 0.36 m apart, the standstill spacing
        Seyfried et al. (2005, J. Stat. Mech. P10002) measured in single file; a disc
        stands for a body about 0.26 H broad (Winter 2009) but only about half as deep.
        With 0.115 H (the shoulder half-breadth less some arm compression) the 1 m
        bottleneck passed 1.43 /s instead of Seyfried et al.'s (2009) 1.9 /s: two such
        discs abreast plus their wall clearance barely fit, so the two lanes of the
        "zipper" (Hoogendoorn & Daamen 2005) rarely formed).
    foot_half_width : float
        Lateral distance of each foot's centre from the walking line [m] (stride width
        about 0.1 m, normative.json).
    wait_time : float
        How long an agent stands before deciding again when it cannot step [s].
    target_distance : float
        How far ahead along the route the steering target lies [m].
    centre_pull : float
        Fraction of the lateral offset from the route's centre line the target corrects
        over ``target_distance`` [-].
    arrive_distance : float
        An agent has arrived within this distance of its route's end [m].
    neighbours : int
        Neighbours considered per deciding agent (nearest first).
    neighbour_range : float
        Search radius for neighbours [m].
    reroute_after : float
        Time without ``progress_step`` of progress along the route after which an agent
        looks for another route [s].
    progress_step : float
        Progress along the route that counts as getting on [m].
    stair_rise : float
        A step with a larger height change is a stair step (Weidmann speed) [m].
    planning_horizon : int
        Steps the footstep planner looks ahead (Chen & Li §4.2: three or four) [-].
    min_step_ratio : float
        Shortest planned step as a fraction of the leg length [-].
    replan_turn_deg : float
        A walker that turns by more than this at a heel strike re-plans; otherwise it
        takes the next step of its current plan [deg].
    steering : SteeringParams
    """

    radius_ratio: float = 0.105
    foot_half_width: float = 0.05
    wait_time: float = 0.25
    target_distance: float = 2.0
    centre_pull: float = 0.25
    arrive_distance: float = 0.6
    neighbours: int = 32
    neighbour_range: float = 3.0
    reroute_after: float = 8.0
    progress_step: float = 0.5
    stair_rise: float = 0.05
    planning_horizon: int = 3
    min_step_ratio: float = 0.15
    replan_turn_deg: float = 3.0
    steering: SteeringParams = field(default_factory=SteeringParams)


class AgentState:
    """Struct-of-arrays state of n agents (one array per field, leading dimension n)."""

    def __init__(self, n: int, horizon: int = 3) -> None:
        self.status = np.full(n, WAITING, dtype=np.int8)
        self.pos0 = np.zeros((n, 2))  # body position at the start of the current step [m]
        self.pos1 = np.zeros((n, 2))  # ... at its end [m]
        self.z0 = np.zeros(n)
        self.z1 = np.zeros(n)
        self.t0 = np.zeros(n)  # start of the current step or wait [s]
        self.t1 = np.zeros(n)  # its end = next decision [s]
        self.heading = np.zeros(n)  # [rad]
        self.stance = np.zeros((n, 2))  # centre-line point of the newest foothold [m]
        self.stance_z = np.zeros(n)
        self.trail = np.zeros((n, 2))  # centre-line point of the previous foothold [m]
        self.trail_z = np.zeros(n)
        self.foot = np.zeros(n, dtype=np.int8)  # foot that swings next: 0 left, 1 right
        self.stance_foot = np.zeros((n, 3))  # foothold of the stance foot (with offset) [m]
        self.animated = np.zeros(n, bool)  # has received a step command
        # the rest of the current footstep plan (H steps at most)
        self.queue_sl = np.zeros((n, horizon))
        self.queue_sh = np.zeros((n, horizon))
        self.queue_energy = np.zeros((n, horizon))
        self.queue_swing = np.full((n, horizon, 4, 2), np.nan)
        self.queue_len = np.zeros(n, dtype=np.int64)
        self.queue_next = np.zeros(n, dtype=np.int64)
        self.queue_dir = np.zeros((n, 2))
        self.queue_anchor = np.full((n, 2), np.nan)  # stance where the next step starts
        self.route = np.zeros(n, dtype=np.int64)
        self.segment = np.zeros(n, dtype=np.int64)
        self.progress = np.zeros(n)  # global route arc length [m]
        self.best_progress = np.full(n, -np.inf)  # furthest route arc length reached [m]
        self.progress_time = np.zeros(n)  # when it last grew by ``progress_step`` [s]
        self.steps = np.zeros(n, dtype=np.int64)
        self.distance = np.zeros(n)  # walked by the body [m]
        self.energy = np.zeros(n)  # [J/kg]
        self.climb = np.zeros(n)  # total rise [m]
        self.wait = np.zeros(n)  # total standing time [s]
        self.stuck = np.zeros(n)  # standing time since the last step [s]
        self.start_time = np.full(n, np.nan)
        self.arrival_time = np.full(n, np.nan)
        self.plans = np.zeros(n, dtype=np.int64)
        self.plan_failures = np.zeros(n, dtype=np.int64)
        self.shortened = np.zeros(n, dtype=np.int64)
        self.reroutes = np.zeros(n, dtype=np.int64)

    def position(self, t: float, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Body positions (k, 2) [m] and heights (k,) [m] of agents ``idx`` at time t."""
        span = self.t1[idx] - self.t0[idx]
        f = np.clip((t - self.t0[idx]) / np.where(span > 0, span, 1.0), 0.0, 1.0)
        xy = self.pos0[idx] + f[:, None] * (self.pos1[idx] - self.pos0[idx])
        return xy, self.z0[idx] + f * (self.z1[idx] - self.z0[idx])


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(n > 1e-12, n, 1.0)


def _left(d: np.ndarray) -> np.ndarray:
    return np.stack([-d[..., 1], d[..., 0]], axis=-1)


class CrowdSimulation:
    """Simulate a population on a world.

    Parameters
    ----------
    world : crowdwalk.world.World
        ``terrain`` and ``routes``.
    population : Population
    dt : float
        Decision tick [s] (rounded down so that output frames fall on ticks).
    fps : float
        Output frame rate [1/s].
    duration : float
        Simulated time limit [s].
    params : CrowdParams
    planner_config : planners.PlannerConfig or None
    gait : crowdwalk.gait.engine.GaitEngine or None
        Receives every decided step and answers :meth:`poses` (None: no poses).
    """

    def __init__(self, world, population: Population, *, dt: float = 0.05, fps: float = 10.0,
                 duration: float = 600.0, params: CrowdParams = CrowdParams(),
                 planner_config=None, gait=None) -> None:
        for name, value in (("dt", dt), ("fps", fps), ("duration", duration)):
            if not (np.isfinite(value) and value > 0):
                raise invalid("CrowdSimulation", name, "> 0", value)
        from crowdwalk.body import Body

        self.world = world
        self.terrain = world.terrain
        self.routes = world.routes
        self.pop = population
        self.params = params
        self.fps = float(fps)
        frame_dt = 1.0 / self.fps
        self.ticks_per_frame = max(1, int(np.ceil(frame_dt / dt - 1e-9)))
        self.dt = frame_dt / self.ticks_per_frame
        self.duration = float(duration)
        n = len(population)
        self.n = n
        self.radius = params.radius_ratio * population.body_height
        self.min_step_time = 1.0 / cadence_at(population.free_speed)
        self.nominal_step = step_length_at(population.free_speed) * population.body_height / 1.71
        # planning legs in 2 cm body-height classes (about 1 % of leg length)
        heights, self.leg_index = np.unique(np.round(population.body_height / 0.02) * 0.02,
                                            return_inverse=True)
        self.legs = Body.from_heights(heights).planning_legs()
        # the legs' segment lengths per class, gathered per agent as arrays [m]
        self._leg_columns = {name: np.array([getattr(leg, name) for leg in self.legs])
                             for name in _LEG_FIELDS}
        self.planner_of = population.planner
        self.clearance = ClearanceField.from_area(self.routes.walkable_area)
        if planner_config is None:
            from planners import PlannerConfig

            # Chen & Li plan "three or four" steps ahead (§4.2); three is an order of
            # magnitude cheaper on stairs than four, and the crowd re-plans often. The step
            # range reaches down to 0.15 leg lengths (planners' default 0.30): in queues
            # and when arriving close to a riser people take short steps.
            planner_config = PlannerConfig(n_steps=params.planning_horizon,
                                           min_step_ratio=params.min_step_ratio)
        self.footsteps = FootstepPlanner(self.terrain, self.legs, config=planner_config,
                                         horizon=planner_config.n_steps,
                                         clearance=self.clearance)
        self.state = AgentState(n, planner_config.n_steps)
        self.table = RouteTable()
        self._route_nodes: dict[int, list[str]] = {}
        self._assign_routes()
        self.gait = gait
        self.time = 0.0
        self.tick = 0
        self.wall_planning = 0.0
        self.wall_steering = 0.0
        self.wall_commands = 0.0  # gait engine step commands
        self._pending: list[StepBatch] = []  # steps not yet sent to the gait engine
        self._decided: list[StepBatch] = []  # steps not yet taken by the run's sinks
        self._edges: dict | None = None  # corridor sample points (_edge_samples)

    # -- setup ---------------------------------------------------------------------

    def _assign_routes(self) -> None:
        """One route polyline per distinct (origin, destinations, start): the smoothed
        graph paths to each destination in turn, concatenated."""
        keys: dict[tuple, int] = {}
        route = np.zeros(self.n, dtype=np.int64)
        starts = self.pop.route_start
        for i in range(self.n):  # setup only: a dict lookup per agent
            start = starts[i]
            key = (str(self.pop.origin[i]), tuple(self.pop.destinations[i]),
                   None if np.isnan(start).any() else tuple(start))
            if key not in keys:
                keys[key] = self._add_route(*key)
            route[i] = keys[key]
        self.state.route = route
        self.state.segment = self.table.start[route].copy()
        self.state.progress = self.table.s0[route].copy()

    def _add_route(self, origin: str, destinations: tuple, start) -> int:
        here, parts, nodes = origin, [], [origin]
        for k, dest in enumerate(destinations):
            if dest == here:
                continue
            kw = {"start": np.asarray(start)} if (k == 0 and start is not None) else {}
            line = self.routes.path(here, dest, **kw)
            parts.append(line if not parts else line[1:])
            nodes += self.routes.route(here, dest)[1:]
            here = dest
        if not parts:  # already at the destination
            p = self.routes.node_xy(origin) if start is None else np.asarray(start)
            parts = [np.stack([p, p])]
        rid = self.table.add(np.concatenate(parts))
        self._remember_nodes(rid, nodes)
        return rid

    def _remember_nodes(self, rid: int, nodes: list[str]) -> None:
        """Store a route's node names and their global arc lengths along it [m]."""
        vs = self.table.xy[self.table.start[rid]:self.table.stop[rid] + 1]
        ss = self.table.s[self.table.start[rid]:self.table.stop[rid] + 1]
        at, k0 = [], 0
        for v in nodes:  # nodes in route order; search forward only
            d = np.linalg.norm(vs[k0:] - self.routes.node_xy(v), axis=1)
            k0 += int(np.argmin(d))
            at.append(ss[k0])
        self._route_nodes[rid] = (nodes, np.asarray(at))

    # -- main loop ----------------------------------------------------------------

    @property
    def active(self) -> np.ndarray:
        """Indices of agents walking now."""
        return np.flatnonzero(self.state.status == ACTIVE)

    @property
    def remaining(self) -> int:
        """Agents not yet arrived (waiting to spawn or walking)."""
        return int(np.count_nonzero(self.state.status != ARRIVED))

    @property
    def finished(self) -> bool:
        """True when every agent has arrived or the time limit is reached."""
        return self.remaining == 0 or self.time >= self.duration - 1e-9

    def step(self) -> bool:
        """Advance one tick; returns True when the tick ends on an output frame."""
        t = (self.tick + 1) * self.dt
        self._spawn(t)
        st = self.state
        deciding = np.flatnonzero((st.status == ACTIVE) & (st.t1 <= t + 1e-9))
        if deciding.size:
            self._decide(deciding, t)
        self.tick += 1
        self.time = t
        return self.tick % self.ticks_per_frame == 0

    @property
    def frame(self) -> int:
        """Index of the output frame at the current time."""
        return self.tick // self.ticks_per_frame

    def snapshot(self) -> Snapshot:
        """The walking agents now (:class:`crowdwalk.sinks.Snapshot`)."""
        idx = self.active
        xy, z = self.state.position(self.time, idx)
        h = self.state.heading[idx]
        return Snapshot(frame=self.frame, agents=idx, xy=xy, z=z,
                        orientation=np.column_stack([np.cos(h), np.sin(h)]))

    def take_steps(self) -> StepBatch | None:
        """The steps decided since the last call (None: none)."""
        if not self._decided:
            return None
        batch = StepBatch.concat(self._decided)
        self._decided = []
        return batch

    # -- spawning -----------------------------------------------------------------

    def _spawn(self, t: float) -> None:
        st = self.state
        due = np.flatnonzero((st.status == WAITING) & (self.pop.spawn_time <= t + 1e-9))
        if due.size == 0:
            return
        xy = self.pop.spawn_xy[due]
        act = self.active
        free = np.ones(due.size, bool)
        if act.size:  # clear of the walking agents' remaining sweeps (nearest 16)
            now, _ = st.position(t, act)
            k = min(16, act.size)
            reach = 1.0 + 2 * float(self.radius.max())
            _, nb = cKDTree(0.5 * (now + st.pos1[act])).query(
                xy, k=k, distance_upper_bound=reach)
            nb = np.asarray(nb).reshape(due.size, k)
            valid = nb < act.size
            j = act[np.where(valid, nb, 0)]
            d = segment_distance(xy[:, None, :], xy[:, None, :], now[np.where(valid, nb, 0)],
                                 st.pos1[j])
            free = np.all((d >= self.radius[due][:, None] + self.radius[j]) | ~valid, axis=1)
        # among agents due together, one that overlaps an earlier one (lower index) waits
        # for a later tick
        cand = np.flatnonzero(free)
        if cand.size > 1:
            pairs = cKDTree(xy[cand]).query_pairs(2 * float(self.radius.max()),
                                                  output_type="ndarray")
            if len(pairs):
                i, j = cand[pairs[:, 0]], cand[pairs[:, 1]]
                clash = (np.linalg.norm(xy[i] - xy[j], axis=1)
                         < self.radius[due[i]] + self.radius[due[j]])
                free[np.maximum(i, j)[clash]] = False
        chosen = np.flatnonzero(free)
        if chosen.size == 0:
            return
        idx = due[chosen]
        p = self.pop.spawn_xy[idx]
        z = self.terrain.height(p)
        st.status[idx] = ACTIVE
        st.pos0[idx] = st.pos1[idx] = p
        st.z0[idx] = st.z1[idx] = z
        st.stance[idx] = st.trail[idx] = p
        st.stance_z[idx] = st.trail_z[idx] = z
        st.foot[idx] = 0  # the left foot swings first; the right one stands
        st.t0[idx] = st.t1[idx] = t
        st.start_time[idx] = t
        st.progress_time[idx] = t
        seg, s, _ = self.table.project(st.route[idx], st.segment[idx], p)
        st.segment[idx], st.progress[idx] = seg, s
        ahead = self.table.point_at(st.route[idx], s + 1.0)
        d = ahead - p
        st.heading[idx] = np.arctan2(d[:, 1], d[:, 0])
        right = -_left(np.column_stack([np.cos(st.heading[idx]), np.sin(st.heading[idx])]))
        st.stance_foot[idx] = np.column_stack([p + self.params.foot_half_width * right, z])

    # -- decisions ----------------------------------------------------------------

    def _neighbours(self, idx: np.ndarray, t: float) -> Neighbours:
        st = self.state
        act = self.active
        k = min(self.params.neighbours + 1, act.size)
        now, _ = st.position(t, act)
        tree = cKDTree(now)
        me, _ = st.position(t, idx)
        dist, nb = tree.query(me, k=k, distance_upper_bound=self.params.neighbour_range)
        dist, nb = np.atleast_2d(dist).reshape(len(idx), k), np.atleast_2d(nb).reshape(len(idx), k)
        valid = nb < act.size
        nb_safe = np.where(valid, nb, 0)
        agent = act[nb_safe]
        valid &= agent != idx[:, None]
        span = st.t1[agent] - st.t0[agent]
        moving = (st.t1[agent] > t) & (span > 0)
        vel = np.where(moving[..., None], (st.pos1[agent] - st.pos0[agent])
                       / np.where(span > 0, span, 1.0)[..., None], 0.0)
        return Neighbours(valid=valid, now=now[nb_safe], end=st.pos1[agent], velocity=vel,
                          heading=st.heading[agent],
                          radius=self.radius[agent],
                          remaining=np.where(moving, st.t1[agent] - t, 0.0))

    def _decide(self, idx: np.ndarray, t: float) -> None:
        st, prm = self.state, self.params
        te = st.t1[idx].copy()  # heel-strike (or wait-end) times, within this tick
        pos = st.pos1[idx]

        # 1. route ahead and arrival
        seg, s, _ = self.table.project(st.route[idx], st.segment[idx], pos)
        st.segment[idx], st.progress[idx] = seg, s
        gained = s >= st.best_progress[idx] + prm.progress_step
        st.best_progress[idx[gained]] = s[gained]
        st.progress_time[idx[gained]] = te[gained]
        end = self.table.xy[self.table.stop[st.route[idx]]]
        arrived = ((self.table.s1[st.route[idx]] - s <= prm.arrive_distance)
                   | (np.linalg.norm(end - pos, axis=1) <= prm.arrive_distance))
        if arrived.any():
            done = idx[arrived]
            st.status[done] = ARRIVED
            st.arrival_time[done] = te[arrived]
            idx, te, pos, s = idx[~arrived], te[~arrived], pos[~arrived], s[~arrived]
            if idx.size == 0:
                return
        # walk parallel to the route (a lane), pulled gently towards its centre line:
        # steering at the centre-line point ahead would funnel everybody into one file
        on_route = self.table.point_at(st.route[idx], s)
        ahead = self.table.point_at(st.route[idx], s + prm.target_distance)
        target = pos + (ahead - on_route) + prm.centre_pull * (on_route - pos)
        # ... unless that lane runs into a wall: then head for the centre line
        blind = self.clearance(target) < self.radius[idx]
        blind |= self.clearance(0.5 * (target + pos)) < self.radius[idx]
        target[blind] = ahead[blind]
        route_dir = _unit(target - pos)
        still = np.linalg.norm(target - pos, axis=1) < 1e-9
        heading_dir = np.column_stack([np.cos(st.heading[idx]), np.sin(st.heading[idx])])
        route_dir[still] = heading_dir[still]

        # 2. steering; a walker held up for long looks backwards on every other decision
        # (the candidate fan turned around), so that clogs can loosen
        clogged = st.stuck[idx] >= prm.steering.clog_after
        back = clogged & (np.round(st.stuck[idx] / prm.wait_time).astype(int) % 2 == 1)
        route_dir = np.where(back[:, None], -route_dir, route_dir)
        w0 = _time.perf_counter()
        nbs = self._neighbours(idx, t)
        choice = choose_steps(pos, st.stance[idx], st.heading[idx], self.radius[idx], route_dir,
                              target, self.nominal_step[idx], nbs, self.clearance,
                              prm.steering, speed=self.pop.free_speed[idx],
                              stuck=st.stuck[idx], step_time=self.min_step_time[idx],
                              lag=t - te)
        self.wall_steering += _time.perf_counter() - w0

        move = choice.move.copy()
        mv = np.flatnonzero(move)
        sl = np.zeros(idx.size)
        sh = np.zeros(idx.size)
        energy = np.zeros(idx.size)
        swing = np.full((idx.size, 4, 2), np.nan)
        # 3. footsteps: walk on along the current plan while the agent keeps its line
        # (Chen & Li plan n steps and walk them), else plan all movers at once
        if mv.size:
            a = idx[mv]
            q = st.queue_next[a]
            # a turn of up to 3° moves the plan's footholds by < 0.14 % of their distance
            along = (np.einsum("ij,ij->i", st.queue_dir[a], choice.direction[mv])
                     > np.cos(np.radians(prm.replan_turn_deg)))
            reuse = ((q < st.queue_len[a]) & along
                     & (np.linalg.norm(st.stance[a] - st.queue_anchor[a], axis=1) < 1e-9))
            ok = np.ones(mv.size, bool)
            r = np.flatnonzero(reuse)
            if r.size:
                ar, qr = a[r], q[r]
                sl[mv[r]], sh[mv[r]] = st.queue_sl[ar, qr], st.queue_sh[ar, qr]
                energy[mv[r]], swing[mv[r]] = st.queue_energy[ar, qr], st.queue_swing[ar, qr]
                st.queue_next[ar] += 1
            p = np.flatnonzero(~reuse)
            if p.size:
                w0 = _time.perf_counter()
                ap = a[p]
                d = choice.direction[mv[p]]
                trailing = -np.einsum("ij,ij->i", st.stance[ap] - st.trail[ap], d)
                planned = self.footsteps.plan(st.stance[ap], st.stance_z[ap], d,
                                              self.leg_index[ap], self.pop.free_speed[ap],
                                              self.planner_of[ap], trailing)
                self.wall_planning += _time.perf_counter() - w0
                st.plans[ap] += 1
                st.plan_failures[ap] += ~planned.ok
                ok[p] = planned.ok
                sl[mv[p]], sh[mv[p]] = planned.step_length[:, 0], planned.step_height[:, 0]
                energy[mv[p]], swing[mv[p]] = planned.energy[:, 0], planned.swing[:, 0]
                st.queue_sl[ap], st.queue_sh[ap] = planned.step_length, planned.step_height
                st.queue_energy[ap], st.queue_swing[ap] = planned.energy, planned.swing
                st.queue_len[ap] = np.where(planned.ok, planned.step_length.shape[1], 0)
                st.queue_next[ap] = 1
                st.queue_dir[ap] = d
            move[mv] = ok
            # a neighbour or wall closer than the planned step: a shorter step if the foot
            # lands on even ground, else wait
            free = choice.free_length
            short = mv[ok & (sl[mv] > free[mv] + 1e-9)]
            if short.size:
                self._shorten(idx, short, free[short], choice.direction, sl, sh, energy,
                              swing, move)
                st.queue_len[idx[short]] = 0
            # no legal plan from here (e.g. the stance foot just short of a riser, where
            # no step of the planner's range lands fully on the tread): a short
            # positioning step on even ground changes the approach, as people do
            failed = mv[~ok]
            for length in (0.3, 0.2):
                if failed.size == 0:
                    break
                stepped = self._shorten(idx, failed, np.minimum(free[failed], length),
                                        choice.direction, sl, sh, energy, swing, move)
                failed = np.setdiff1d(failed, stepped)
            # the exact step taken, in time (steering tested sampled lengths only): the
            # body moving along its sweep against each neighbour moving along its own
            go = np.flatnonzero(move)
            if go.size and nbs.valid.shape[1]:
                end = st.stance[idx[go]] + 0.5 * sl[go, None] * choice.direction[go]
                dur = self._durations(idx[go], sl[go], sh[go])
                gap = step_distance(pos[go, None, :], end[:, None, :], dur[:, None],
                                    (t - te[go])[:, None], nbs.now[go], nbs.end[go],
                                    nbs.remaining[go])
                clash = ((gap < self.radius[idx[go], None] + nbs.radius[go])
                         & nbs.valid[go]).any(axis=1)
                move[go[clash]] = False
                st.queue_len[idx[go[clash]]] = 0
        # 4. commit
        self._commit(idx, te, t, move, choice.direction, sl, sh, energy, swing)

    def _shorten(self, idx, rows, length, direction, sl, sh, energy, swing, move) -> np.ndarray:
        """Take steps of ``length`` (k,) [m] instead, for the agents at ``rows`` of
        ``idx``, where the whole foot (heel, ankle, toe) lands on even ground; the others
        wait. The step's energy is the planners' Eq. 4 for that step. Returns the rows
        that step."""
        st = self.state
        a = idx[rows]
        d = direction[rows]
        legs = self._legs_of(a)
        heel, toe = legs.heel_offset, legs.toe_offset
        c = st.stance[a] + length[:, None] * d
        pts = np.concatenate([c - heel[:, None] * d, c, c + toe[:, None] * d])
        z = self.terrain.height(pts).reshape(3, -1)
        even = (np.ptp(z, axis=0) <= 0.02) & (length >= self.params.steering.min_step)
        sl[rows] = np.where(even, length, 0.0)
        sh[rows] = z[1] - st.stance_z[a]
        energy[rows] = np.where(even, self._step_energy(a, length, sh[rows]), 0.0)
        swing[rows] = np.nan
        move[rows] = even
        st.shortened[a[even]] += 1
        return rows[even]

    def _legs_of(self, a: np.ndarray) -> SimpleNamespace:
        """The legs of agents ``a`` (k,) as a leg whose fields are (k,) arrays [m] (what
        the planners' vectorised functions accept in place of a ``planners.Leg``)."""
        k = self.leg_index[a]
        return SimpleNamespace(**{name: col[k] for name, col in self._leg_columns.items()})

    def _step_energy(self, a: np.ndarray, length: np.ndarray, rise: np.ndarray) -> np.ndarray:
        """Chen & Li Eq. 4 energy [J/kg] of steps not planned by the planner (shortened or
        positioning steps): the planners' energy model, one call for all legs."""
        from planners.energy import step_energy

        cfg = self.footsteps.config
        leg = self._legs_of(a)
        zero = np.zeros(a.size)
        summit = np.maximum(zero, rise) + leg.ankle_height + 0.75 * cfg.swing_lift
        return step_energy(zero, zero, length, rise, summit, leg, self.pop.free_speed[a],
                           cfg)[3]

    def _commit(self, idx, te, t, move, direction, sl, sh, energy, swing) -> None:
        st, prm = self.state, self.params
        # resolve conflicts between agents that decided in this same tick: each checked
        # the others' positions at their heel strike, not their new steps
        mv = np.flatnonzero(move)
        if mv.size > 1:
            a = idx[mv]
            new_c = st.stance[a] + sl[mv, None] * direction[mv]
            end = 0.5 * (st.stance[a] + new_c)
            start = st.pos1[a]
            mid = 0.5 * (start + end)
            half = 0.5 * np.linalg.norm(end - start, axis=1)
            tree = cKDTree(mid)
            pairs = tree.query_pairs(2 * (half.max() + self.radius[a].max()), output_type="ndarray")
            if len(pairs):
                i, j = pairs[:, 0], pairs[:, 1]
                # in time (from now on), as in the test against the neighbours
                dur = self._durations(a, sl[mv], sh[mv])
                gone = np.minimum(t - te[mv], dur)
                now = start + gone[:, None] * ((end - start) / dur[:, None])  # each one now
                gap = step_distance(start[i], end[i], dur[i], (t - te[mv])[i], now[j], end[j],
                                    (dur - gone)[j])
                bad = gap < self.radius[a[i]] + self.radius[a[j]]
                if bad.any():
                    # the later heel strike (then the higher id) yields and waits
                    later = np.where((te[mv[i]] > te[mv[j]])
                                     | ((te[mv[i]] == te[mv[j]]) & (a[i] > a[j])), i, j)
                    move[mv[np.unique(later[bad])]] = False

        wait = idx[~move]
        if wait.size:
            st.queue_len[wait] = 0
            st.pos0[wait] = st.pos1[wait]
            st.z0[wait] = st.z1[wait]
            st.t0[wait] = st.t1[wait]
            st.t1[wait] = t + prm.wait_time
            # standing still brings the feet together under the body (on level footing),
            # so the next step may go any way
            # (only where the whole foot, heel to toe, rests on even ground there)
            apart = wait[np.linalg.norm(st.stance[wait] - st.trail[wait], axis=1) > 1e-6]
            if apart.size:
                here = st.pos1[apart]
                d = np.column_stack([np.cos(st.heading[apart]), np.sin(st.heading[apart])])
                legs = self._legs_of(apart)
                heel, toe = legs.heel_offset, legs.toe_offset
                pts = np.concatenate([here - (heel + 0.03)[:, None] * d, here,
                                      here + (toe + 0.03)[:, None] * d])
                z = self.terrain.height(pts).reshape(3, -1)
                even = np.ptp(z, axis=0) <= 0.01
                level = apart[even]
                st.stance[level] = st.trail[level] = here[even]
                st.stance_z[level] = st.trail_z[level] = z[1, even]
                # where the feet cannot come together (the body over an edge), a walker
                # held up for a while shifts its weight to the other foot, so that its
                # next step may start from there (e.g. a step back off a curb)
                swap = apart[~even & (st.stuck[apart] >= prm.steering.give_way_after)]
                if swap.size:
                    st.stance[swap], st.trail[swap] = st.trail[swap], st.stance[swap].copy()
                    st.stance_z[swap], st.trail_z[swap] = (st.trail_z[swap],
                                                           st.stance_z[swap].copy())
                    st.foot[swap] = 1 - st.foot[swap]
                    st.queue_len[swap] = 0
            dur = t + prm.wait_time - st.t0[wait]
            st.wait[wait] += dur
            st.stuck[wait] += dur

        # blocked: no progress along the route for ``reroute_after`` seconds (side steps and
        # steps back in a jam do not count)
        blocked = idx[t - st.progress_time[idx] >= prm.reroute_after]
        if blocked.size:
            self._reroute(blocked, t)

        go = np.flatnonzero(move)
        if go.size == 0:
            return
        a = idx[go]
        d = direction[go]
        L, H = sl[go], sh[go]
        new_c = st.stance[a] + L[:, None] * d
        new_z = st.stance_z[a] + H
        duration = self._durations(a, L, H)
        t0 = te[go]
        end = 0.5 * (st.stance[a] + new_c)
        st.distance[a] += np.linalg.norm(end - st.pos1[a], axis=1)
        st.pos0[a] = st.pos1[a]
        st.z0[a] = st.z1[a]
        st.pos1[a] = end
        st.z1[a] = 0.5 * (st.stance_z[a] + new_z)
        st.t0[a] = t0
        st.t1[a] = t0 + duration
        st.heading[a] = np.arctan2(d[:, 1], d[:, 0])
        foot = st.foot[a].copy()
        side = np.where(foot == 0, 1.0, -1.0)
        foothold = new_c + (side * prm.foot_half_width)[:, None] * _left(d)
        st.trail[a], st.trail_z[a] = st.stance[a], st.stance_z[a]
        st.stance[a], st.stance_z[a] = new_c, new_z
        st.queue_anchor[a] = new_c
        st.foot[a] = 1 - foot
        st.steps[a] += 1
        st.energy[a] += energy[go]
        st.climb[a] += np.maximum(H, 0.0)
        st.stuck[a] = 0.0
        start = st.stance_foot[a].copy()
        target = np.column_stack([foothold, new_z])
        st.stance_foot[a] = target
        # stepped over: at most one longest step (1.05 leg lengths) along the direction
        stride = 1.05 * self._leg_columns["length"][self.leg_index[a]]
        kind, on_obstacle = self.terrain.footing(foothold, d, stride=stride)
        batch = StepBatch(
            agent=a, step=st.steps[a].copy(), start_time=t0, duration=duration, foot=foot,
            start=start, target=target, stance_centre=st.trail[a].copy(),
            heading=st.heading[a].copy(), length=L, rise=H, energy=energy[go],
            planner=self.planner_of[a].astype(str),
            group=np.asarray(self.pop.group_names, dtype=object)[self.pop.group[a]].astype(str),
            swing_bezier=self._swing_bezier(a, swing[go], d, side), kind=kind,
            on_obstacle=on_obstacle)
        self._decided.append(batch)
        if self.gait is not None:
            if self._pending and np.isin(a, np.concatenate([b.agent for b in self._pending])).any():
                self._flush_commands()  # an agent's earlier step must reach the engine first
            self._pending.append(batch)
            st.animated[a] = True

    def _durations(self, a: np.ndarray, L: np.ndarray, H: np.ndarray) -> np.ndarray:
        """Duration [s] of steps of length ``L`` and rise ``H`` (k,) [m] by agents ``a``."""
        prm = self.params
        # speed model: Weidmann stairs, Tobler slopes, cadence floor
        v0 = self.pop.free_speed[a]
        grade = H / np.maximum(L, 1e-6)
        factor = np.where(H > prm.stair_rise, STAIR_UP_FACTOR,
                          np.where(H < -prm.stair_rise, STAIR_DOWN_FACTOR,
                                   1.0 / np.maximum(1.0, np.exp(3.5 * (np.abs(grade + 0.05)
                                                                       - 0.05)))))
        stair = np.abs(H) > prm.stair_rise
        return np.where(stair, L / (v0 * factor),
                        np.maximum(L / (v0 * factor), self.min_step_time[a]))

    # -- poses ---------------------------------------------------------------------

    def _swing_bezier(self, a, swing, d, side) -> np.ndarray:
        """The planner's swing-ankle Bezier (k, 4, 2) in (s, z) relative to the stance
        ankle, as world xyz control points (k, 4, 3) [m] (rows of NaN without one)."""
        st = self.state
        stance_c = st.trail[a]  # centre-line point of the stance ankle (before this step)
        stance_z = st.trail_z[a]
        bez = np.full((a.size, 4, 3), np.nan)
        has = np.all(np.isfinite(swing), axis=(1, 2))
        if has.any():
            lat = (side[has] * self.params.foot_half_width)[:, None] * _left(d[has])
            s_, z_ = swing[has, :, 0], swing[has, :, 1]
            bez[has, :, :2] = (stance_c[has, None, :] + s_[..., None] * d[has, None, :]
                               + lat[:, None, :])
            bez[has, :, 2] = stance_z[has, None] + z_
        return bez

    def _flush_commands(self) -> None:
        """Send the buffered steps to the gait engine in one batch (an engine has a fixed
        cost per call, so the steps decided between two output frames go together)."""
        if not self._pending:
            return
        w0 = _time.perf_counter()
        batch = StepBatch.concat(self._pending)
        self._pending = []
        self.gait.command(batch)
        self.wall_commands += _time.perf_counter() - w0

    def poses(self):
        """Poses of the walking agents that have taken a step, at the current time
        (a :class:`crowdwalk.gait.engine.PoseFrame`), or None without a gait engine."""
        if self.gait is None:
            return None
        self._flush_commands()
        idx = self.active
        idx = idx[self.state.animated[idx]]
        if idx.size == 0:
            return None
        return self.gait.pose(self.time, idx)

    # -- re-routing ---------------------------------------------------------------

    def _edge_samples(self) -> dict:
        """Points about 1 m apart along every corridor of the route graph (k, 2) [m] and
        its width [m], by edge (computed once: the graph does not change)."""
        if self._edges is None:
            self._edges = {}
            for u, v, data in self.routes.graph.edges(data=True):
                line = data["geometry"]
                k = max(2, int(np.ceil(line.length)) + 1)
                pts = np.array([line.interpolate(f, normalized=True).coords[0]
                                for f in np.linspace(0, 1, k)])
                self._edges[(u, v)] = (pts, data["width"])
        return self._edges

    def _reroute(self, blocked: np.ndarray, t: float) -> None:
        """Agents without progress for ``reroute_after`` seconds look for a cheaper route from the
        last route node they passed, with every corridor's cost raised by the time its
        current occupants need to get through it (queue length over a specific flow of
        1.3 persons/(s·m), Weidmann 1993; converted to metres at 1.34 m/s). The agent
        switches only when that route differs from its own (rare: a Python loop over the
        blocked agents only)."""
        import networkx as nx

        st = self.state
        g = self.routes.graph
        act = self.active
        now, _ = st.position(t, act)
        tree = cKDTree(now)
        extra = {}
        for (u, v), (pts, width) in self._edge_samples().items():
            near = tree.query_ball_point(pts, r=max(0.5 * width, 0.5))
            count = len(set().union(*near)) if len(near) else 0
            extra[(u, v)] = count / (1.3 * width) * 1.34

        def weight(a, b, data):
            return data.get("cost", data.get("length", 1.0)) + extra.get((a, b), 0.0)

        for i in blocked:
            st.progress_time[i] = t  # look again only after another ``reroute_after``
            nodes, at = self._route_nodes.get(int(st.route[i]), ([], np.zeros(0)))
            if len(nodes) < 2:
                continue
            passed = int(np.searchsorted(at, st.progress[i], side="right")) - 1
            passed = min(max(passed, 0), len(nodes) - 2)
            rest = nodes[passed:]
            try:
                alt = nx.shortest_path(g, rest[0], rest[-1], weight=weight)
            except (nx.NetworkXNoPath, nx.NodeNotFound):
                continue
            if alt == rest or len(alt) < 2:
                continue
            # keep any later destinations of the route after the last node
            line = np.vstack([st.pos1[i][None, :], self.routes.raw_path(alt)])
            rid = self.table.add(line)
            self._remember_nodes(rid, alt)
            st.route[i] = rid
            st.segment[i] = self.table.start[rid]
            st.progress[i] = self.table.s0[rid]
            st.best_progress[i] = -np.inf
            st.reroutes[i] += 1
