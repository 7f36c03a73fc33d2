"""The crowd simulation: event-driven footsteps of many agents.

Each agent decides at its heel strikes. Per tick, every agent whose heel strike (or end
of a wait) falls in the tick decides, all of them in one batch, through a pipeline of
pure functions over arrays, one module each:

1. route ahead (:mod:`~crowdwalk.crowd.routing`): progress along its route polyline,
   arrival, the steering target ``target_distance`` ahead;
2. local steering with the neighbours from one uniform grid per tick
   (:mod:`~crowdwalk.crowd.neighbours`, :mod:`~crowdwalk.crowd.steering`): a step
   direction and the longest clear step;
3. footsteps (:mod:`~crowdwalk.crowd.stepping`): the next step of the agent's current
   plan while it keeps its line (Chen & Li plan n steps and walk them), else
   ``planners.plan_batch`` for all re-planning agents at once
   (:mod:`~crowdwalk.crowd.footsteps`); a step longer than the clear length is shortened
   where the whole foot lands on even ground, a failed plan is replaced by a short
   positioning step, else the agent waits;
4. the exact sweep of each step, in time, against the neighbours, then against the other
   agents deciding in the same tick (:mod:`~crowdwalk.crowd.conflicts`), with the step's
   duration from the speed model (:mod:`~crowdwalk.crowd.speed`);
5. the agents that do not step stand (:mod:`~crowdwalk.crowd.waiting`); those without
   progress for a while re-route (:class:`~crowdwalk.crowd.routing.Routes`); the others
   take their steps (:mod:`~crowdwalk.crowd.commit`), oriented by MetaGait (Sun &
   Metaxas 2001 §6.1, :meth:`crowdwalk.gait.metagait.MetaGait.orient`: the landing
   foot's toe-out for the turn ahead, spin turns on the stance foot), which leave as one
   :class:`~crowdwalk.steps.StepBatch` for the gait engine (batched per output frame) and
   for the run's sinks (:meth:`CrowdSimulation.take_steps`).
Ticks are aligned with output frames so frames are exact interpolations.
"""

from __future__ import annotations

import time as _time
from dataclasses import replace
from functools import partial

import numpy as np

from crowdwalk.crowd.commit import take_steps
from crowdwalk.crowd.conflicts import clashes_with_neighbours, same_tick_yielders
from crowdwalk.crowd.events import EventTimeline
from crowdwalk.crowd.holding import WaitingAreas
from crowdwalk.crowd.mouth_priority import MouthPriority, with_reservations
from crowdwalk.crowd.neighbours import gather_neighbours
from crowdwalk.crowd.openings import Openings
from crowdwalk.crowd.params import CrowdParams
from crowdwalk.crowd.routing import lane_runs_into_wall, route_progress, steering_targets
from crowdwalk.crowd.setup import CrowdParts, build_parts
from crowdwalk.crowd.shape import BodyShape
from crowdwalk.crowd.spawning import free_to_spawn, place
from crowdwalk.crowd.speed import GapSteps, step_durations
from crowdwalk.crowd.state import ACTIVE, ARRIVED, WAITING, AgentState
from crowdwalk.crowd.steering import choose_steps
from crowdwalk.crowd.stepping import PlanQueue, StepPlan, next_steps
from crowdwalk.crowd.waiting import stand
from crowdwalk.crowd.wake import WakeOnStep
from crowdwalk.crowd.zipper import ZipperEntry
from crowdwalk.errors import invalid
from crowdwalk.gait.datasets import normative
from crowdwalk.gait.metagait import MetaGait
from crowdwalk.population import Population
from crowdwalk.sinks import Snapshot
from crowdwalk.steps import StepBatch
from crowdwalk.style import LOCKS
from crowdwalk.workers import row_threads, split_rows
from planners import normal_mode

__all__ = ["CrowdParams", "CrowdParts", "CrowdSimulation", "build_parts", "WAITING",
           "ACTIVE", "ARRIVED"]


class CrowdSimulation:
    """Simulate a population on a world, tick by tick.

    Parameters
    ----------
    world : crowdwalk.world.World
        ``terrain`` and ``routes``.
    population : Population
    parts : CrowdParts
        Footstep planner, clearance field, legs and routes (:func:`build_parts`).
    dt : float
        Decision tick [s] (rounded down so that output frames fall on ticks).
    fps : float
        Output frame rate [1/s].
    duration : float
        Simulated time limit [s].
    params : CrowdParams, optional
    gait : crowdwalk.gait.engine.GaitEngine or None
        Receives every decided step and answers :meth:`poses` (None: no poses).
    workers : crowdwalk.workers.Workers or None
        Worker processes that steer parts of a tick's deciding walkers
        (:func:`crowdwalk.workers.split_rows`) when one of them does not pose (None: all
        in this process).
    threads : crowdwalk.workers.RowThreads, optional
        Threads of this process that gather the neighbours of, and steer, parts of a
        tick's deciding walkers at once (default :func:`crowdwalk.workers.row_threads`:
        one per core).
    """

    def __init__(self, world, population: Population, *, parts: CrowdParts,
                 dt: float = 0.05, fps: float = 10.0, duration: float = 600.0,
                 params: CrowdParams | None = None, gait=None, workers=None,
                 threads=None) -> None:
        for name, value in (("dt", dt), ("fps", fps), ("duration", duration)):
            if not (np.isfinite(value) and value > 0):
                raise invalid("CrowdSimulation", name, "> 0", value)
        self.terrain = world.terrain
        self.pop = population
        self.params = params = params or CrowdParams()
        self.fps = float(fps)
        frame_dt = 1.0 / self.fps
        self.ticks_per_frame = max(1, int(np.ceil(frame_dt / dt - 1e-9)))
        self.dt = frame_dt / self.ticks_per_frame
        self.duration = float(duration)
        self.n = n = len(population)
        h = population.body_height
        self.shape = BodyShape.from_axes(*params.body_axes(h))
        self.radius = self.shape.radius  # the centre disc's (half the depth) [m]
        # KLAW locomotion parameters (crowdwalk.style) at the free speed: normal mode is
        # the body's normal-mode step and cadence (planners.normal_mode, WBDS relation); a
        # lock holds its step length (the step aimed at) or frequency (the step time), and
        # a held step length is planned at the speed it is the normal-mode step of (the
        # planners' neutral step and step-frequency term then centre on it)
        style, v = population.style, population.free_speed
        self.leg_length = leg = normal_mode.leg_length_from_height(population.body_height)
        self.nominal_step, frequency = style.locomotion(v, population.body_height)
        normal = normal_mode.step_frequency(v, leg)
        self.min_step_time = 1.0 / np.where(style.lock == LOCKS.index("step_frequency"),
                                            frequency, np.maximum(frequency, normal))
        self.plan_speed = np.where(style.lock > 0, normal_mode.speed_from_step_length(
            self.nominal_step, leg), v)
        self.half_width = 0.5 * style.stride_width  # ankle line from the centre [m]
        self.step_speed = population.free_speed.copy()  # speed of the step decided [m/s]
        # the cadence floor holds for steps the planner did not plan, and for every step
        # of a walker whose style locks its step frequency
        self.hold_frequency = style.lock == LOCKS.index("step_frequency")
        # no step is quicker than the quickest measured (WBDS, 2.48 steps/s): a planned
        # step of 0.1 m at 1.3 m/s would otherwise last 0.08 s, two frames at 25 fps
        self.shortest_step = 1.0 / normative()["cadence_max"]["steps_per_s"]
        self.legs, self.clearance = parts.legs, parts.clearance
        self.footsteps, self.routes = parts.footsteps, parts.routes
        self.setting = self._style_settings()
        self.state = AgentState(n)
        self.metagait = MetaGait(n)  # orientation of every step (§6.1)
        self.queue = PlanQueue(n, self.footsteps.horizon)
        table = self.routes.table
        self.state.route = self.routes.of_agent.copy()
        self.state.segment = table.start[self.state.route].copy()
        self.state.progress = table.s0[self.state.route].copy()
        sc = world.scenario
        self.events = EventTimeline(sc, world.routes, population) if sc.events else None
        self.holding = WaitingAreas(sc.waiting_areas, world.routes, n) \
            if sc.waiting_areas else None
        self.openings = None
        if params.opening_ease:
            self.openings = Openings(world.routes, params.opening_width,
                                     params.opening_margin)
        self.free_zone = None  # headway_free_margin: where the headway model is off
        if params.speed_model == "headway" and params.headway_free_margin is not None:
            self.free_zone = Openings(world.routes, params.opening_width,
                                      params.headway_free_margin)
        self.zipper = None  # zipper: lane targets at openings
        if params.zipper:
            self.zipper = ZipperEntry(world.routes, params.opening_width)
        # wake_on_step: standing walkers decide at a neighbour's step; mouth_priority:
        # reserved next steps at mouths. Both act only in opening zones: without an
        # opening (the zones come from every corridor, shut or open) they are left out,
        # the same run without their per-tick work.
        self.wake = None
        if params.wake_on_step:
            wake = WakeOnStep(world.routes, params.opening_width)
            self.wake = None if wake.zone.empty else wake
        self.mouth_priority = None
        if params.mouth_priority:
            mouth = MouthPriority(world.routes, params.opening_width)
            self.mouth_priority = None if mouth.zone.empty else mouth
        self.gait = gait
        self.workers = workers
        self.threads = row_threads() if threads is None else threads
        # the workers that steer parts of a tick (not the one holding a remote gait engine)
        self._steer_on = [] if workers is None else [
            w for w in range(len(workers)) if w != getattr(gait, "worker", None)]
        if self._steer_on:
            workers.share(self.clearance)
        self.time = 0.0
        self.tick = 0
        self.wall_planning = 0.0
        self.wall_steering = 0.0
        self.wall_commands = 0.0  # gait engine step commands
        self._pending: list[StepBatch] = []  # steps not yet sent to the gait engine
        self._decided: list[StepBatch] = []  # steps not yet taken by the run's sinks
        self._directions: np.ndarray | None = None  # _route_directions of this decision

    # -- the loop --------------------------------------------------------------------

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

    @property
    def frame(self) -> int:
        """Index of the output frame at the current time."""
        return self.tick // self.ticks_per_frame

    def step(self) -> bool:
        """Advance one tick; returns True when the tick ends on an output frame."""
        t = (self.tick + 1) * self.dt
        if self.events is not None:
            self.events.apply(self, t)
        if self.holding is not None:
            self.holding.release(self, t)
        self._spawn(t)
        st = self.state
        deciding = np.flatnonzero((st.status == ACTIVE) & (st.t1 <= t + 1e-9))
        if deciding.size:
            self._decide(deciding, t)
        self.tick += 1
        self.time = t
        return self.tick % self.ticks_per_frame == 0

    def snapshot(self) -> Snapshot:
        """The walking agents now (:class:`crowdwalk.sinks.Snapshot`)."""
        idx = self.active
        xy, z = self.state.position(self.time, idx)
        h = self.state.yaw(self.time, idx)
        return Snapshot(frame=self.frame, agents=idx, xy=xy, z=z,
                        orientation=np.column_stack([np.cos(h), np.sin(h)]))

    def take_steps(self) -> StepBatch | None:
        """The steps decided since the last call (None: none)."""
        if not self._decided:
            return None
        batch = StepBatch.concat(self._decided)
        self._decided = []
        return batch

    def poses(self):
        """Poses of the walking agents that have taken a step, at the current time
        (a :class:`crowdwalk.gait.engine.PoseFrame`), or None without a gait engine."""
        return self.poses_later()()

    def poses_later(self):
        """A function returning :meth:`poses` of now; a gait engine with ``pose_async``
        (:class:`crowdwalk.gait.remote.RemoteEngine`) computes them meanwhile."""
        if self.gait is None:
            return lambda: None
        self._flush_commands()
        idx = self.active
        idx = idx[self.state.animated[idx]]
        if idx.size == 0:
            return lambda: None
        if hasattr(self.gait, "pose_async"):
            return self.gait.pose_async(self.time, idx)
        frame = self.gait.pose(self.time, idx)
        return lambda: frame

    # -- one tick ----------------------------------------------------------------------

    def _spawn(self, t: float) -> None:
        st = self.state
        due = np.flatnonzero((st.status == WAITING) & (self.pop.spawn_time <= t + 1e-9))
        if due.size == 0:
            return
        xy = self.pop.spawn_xy[due]
        # the outline's holding disc: a spawning walker's facing is not yet known
        free = free_to_spawn(st, due, t=t, walkers=self.active, xy=xy,
                             radius=self.shape.bound)
        idx = due[free]
        if idx.size:
            p = self.pop.spawn_xy[idx]
            place(st, idx, t=t, xy=p, z=self.terrain.height(p), table=self.routes.table,
                  foot_half_width=self.half_width[idx])

    def _style_settings(self) -> np.ndarray:
        """Planner configuration per walker (n,) (index into ``footsteps.configs``): the
        crowd's, with the style's toe clearance as swing clearance [m] (to 5 mm)."""
        from dataclasses import replace

        clearance = np.round(self.pop.style.toe_clearance / 0.005) * 0.005
        values, index = np.unique(clearance, return_inverse=True)
        base = self.footsteps.config
        return np.array([self.footsteps.add_config(replace(base, clearance=float(c)))
                         for c in values], dtype=np.int64)[index]

    def _durations(self, a: np.ndarray, plan: StepPlan) -> np.ndarray:
        return step_durations(plan.length, plan.rise, free_speed=self.step_speed[a],
                              min_step_time=np.where(plan.shortened | self.hold_frequency[a],
                                                     self.min_step_time[a],
                                                     self.shortest_step),
                              stair_rise=self.params.stair_rise)

    def _gap_steps(self, idx: np.ndarray, pos: np.ndarray, nbs,
                   walled: np.ndarray | None = None) -> GapSteps | None:
        """The gap speed model's steps for the deciders ``idx`` at ``pos`` (k, 2) [m]
        among ``nbs`` (None for ``speed_model="free"``); ``walled`` (k,) bool: deciders
        whose lane runs into a wall, who do not overtake (``headway_overtake_open_lanes``)."""
        prm = self.params
        if prm.speed_model == "free" or not nbs.valid.shape[1]:
            return None
        free, leg = self.pop.free_speed[idx], self.leg_length[idx]
        if prm.speed_model == "time_gap":  # Tordeux et al.: everybody ahead, now
            return GapSteps(pos, self.radius[idx], nbs.now, nbs.radius, nbs.valid,
                            nbs.valid, free, leg, prm.time_gap, contact=False)
        # the contact gap to where the neighbours' committed steps end; the step's speed
        # does not count walkers that come towards this one (steering avoids them, which
        # anticipates their motion; they are not followed)
        h = self.state.heading[idx]
        own = np.stack([np.cos(h), np.sin(h)], axis=-1)
        followed = nbs.valid & (np.einsum("kmj,kj->km", nbs.velocity, own) >= -0.1)
        if prm.speed_model == "headway":  # Seyfried et al. 2005's required length
            # followed: the neighbours walking (or facing, when standing) the same way;
            # the others are avoided by steering, not followed
            if prm.headway_same_way == "route":  # route-direction leaders
                e = self._route_directions()
                followed = nbs.valid & (np.einsum("kmj,kj->km", e[nbs.agent], e[idx]) > -0.5)
            elif nbs.heading is not None:
                followed = nbs.valid & (np.cos(nbs.heading - h[:, None]) > 0.0)
            # headway_overtake: candidate directions are scored at the step the model
            # allows counting only the leaders it follows (oncoming walkers are not)
            scored = followed if prm.headway_overtake else nbs.valid
            if walled is not None:  # no side lane to overtake in where the lane ends
                scored = scored & ~walled[:, None]
            if self.free_zone is not None:  # in and near openings: walk into free space
                free_here = self.free_zone.inside(pos)[:, None]
                followed &= ~free_here
                # nor does headway_steer score directions there at a headway step
                scored = scored & ~free_here
            lane = prm.headway_lane * self.shape.bound[idx]
            lane_dir = shift = None
            if prm.headway_route_lane:  # the route lane the step goes into
                lane_dir = (e if prm.headway_same_way == "route"
                            else self._route_directions())[idx]
                shift = self.nominal_step[idx]
            return GapSteps(pos, self.radius[idx], nbs.end, nbs.radius, scored, followed,
                            free, leg, prm.headway_time, lane=lane,
                            lane_direction=lane_dir, shift=shift)
        return GapSteps(pos, self.radius[idx], nbs.end, nbs.radius, nbs.valid, followed,
                        free, leg, prm.contact_time_gap)

    def _route_directions(self, agents: np.ndarray | None = None) -> np.ndarray:
        """The desired directions (..., 2) of ``agents`` (an index array of any shape;
        default every agent, (n, 2)): the unit direction of each one's current route
        segment. Within a decision (:meth:`_decide`, from its steering to its commit,
        where no segment or route changes) they are computed once for every agent."""
        if self._directions is None:  # once per decision: segments and routes are fixed
            st, table = self.state, self.routes.table
            seg = np.minimum(st.segment, table.stop[st.route] - 1)
            d = table.xy[seg + 1] - table.xy[seg]
            # row by row the same values as for any index array of agents (the norm's
            # two squares are added in one order whatever the array's shape)
            self._directions = d / np.maximum(np.linalg.norm(d, axis=-1), 1e-12)[..., None]
        return self._directions if agents is None else self._directions[agents]

    def _opening_scales(self, pos: np.ndarray) -> dict:
        """``opening_ease``: the factors on the soft wall and neighbour terms (k,) for
        deciders at ``pos`` (k, 2) [m] (empty without it)."""
        if self.openings is None:
            return {}
        inside = self.openings.inside(pos)
        prm = self.params
        return {"wall_scale": np.where(inside, prm.opening_wall_factor, 1.0),
                "personal_scale": np.where(inside, prm.opening_personal_factor, 1.0)}

    def _reservations(self, idx: np.ndarray, pos: np.ndarray, nbs):
        """``mouth_priority``: the reserved next steps (:class:`~crowdwalk.crowd.steering.
        Neighbours`, (k, K)) of the deciders ``idx`` at ``pos`` (k, 2) [m] among ``nbs``."""
        j = nbs.agent
        step = self.nominal_step[j]
        return self.mouth_priority.reservations(
            idx, pos, self._route_directions(idx), nbs, bound=self.shape.bound[idx],
            nb_direction=self._route_directions(j), nb_step=step,
            nb_time=np.maximum(step / self.pop.free_speed[j], self.min_step_time[j]))

    def _decide(self, idx: np.ndarray, t: float) -> None:
        st, prm, table = self.state, self.params, self.routes.table
        te = st.t1[idx].copy()  # heel-strike (or wait-end) times, within this tick
        pos = st.pos1[idx]
        ahead = route_progress(table, route=st.route[idx], segment=st.segment[idx],
                               best=st.best_progress[idx], xy=pos, params=prm)
        st.segment[idx], st.progress[idx] = ahead.segment, ahead.progress
        st.best_progress[idx[ahead.gained]] = ahead.progress[ahead.gained]
        st.progress_time[idx[ahead.gained]] = te[ahead.gained]
        st.gain_time[idx[ahead.gained]] = te[ahead.gained]
        if ahead.arrived.any():
            done = idx[ahead.arrived]
            st.status[done] = ARRIVED
            st.arrival_time[done] = te[ahead.arrived]
            keep = ~ahead.arrived
            idx, te, pos = idx[keep], te[keep], pos[keep]
            if idx.size == 0:
                return
        if self.holding is not None:  # walkers standing in a waiting area
            held = self.holding.hold(self, idx, t)
            if held.any():
                stand(st, self.queue, agents=idx[held], t=t, terrain=self.terrain,
                      legs=self.legs, params=prm)
                idx, te, pos = idx[~held], te[~held], pos[~held]
                if idx.size == 0:
                    return
        self._directions = None  # the segments are this decision's from here on
        target, route_dir = self.threads.map(
            partial(steering_targets, table, clearance=self.clearance, params=prm), idx.size,
            route=st.route[idx], progress=st.progress[idx], xy=pos, heading=st.heading[idx],
            radius=self.radius[idx], light=True)
        if np.isfinite(prm.sight_after):
            # stuck for ``sight_after`` with the target behind a wall (pushed into a side
            # room, say): head for the farthest point of the route it sees
            late = np.flatnonzero(t - st.gain_time[idx] >= prm.sight_after)
            graph = self.routes.graph
            k = late[~graph.sees_all(pos[late], target[late])]
            if k.size:
                seen = self.routes.farthest_visible(st, idx[k], prm.sight_reach)
                ok = np.isfinite(seen[:, 0]) & (np.linalg.norm(seen - pos[k], axis=1) > 1e-6)
                target[k[ok]] = seen[ok]
                route_dir[k[ok]] = (seen[ok] - pos[k[ok]]) / np.linalg.norm(
                    seen[ok] - pos[k[ok]], axis=1)[:, None]
        # a walker held up for long looks backwards on every other decision (the
        # candidate fan turned around), so that clogs can loosen
        clogged = st.stuck[idx] >= prm.steering.clog_after
        back = clogged & (np.round(st.stuck[idx] / prm.wait_time).astype(int) % 2 == 1)
        route_dir = np.where(back[:, None], -route_dir, route_dir)
        w0 = _time.perf_counter()
        nbs = gather_neighbours(st, idx, t=t, walkers=self.active, shape=self.shape,
                                count=prm.neighbours, reach=prm.neighbour_range,
                                threads=self.threads)
        if self.zipper is not None:  # staggered entry: the lane beside the leader's
            target = self.zipper.targets(table, self.clearance, route=st.route[idx],
                                         progress=st.progress[idx], xy=pos,
                                         radius=self.radius[idx], target=target, nbs=nbs)
        limits = None
        if self.mouth_priority is not None:  # give way to those nearer the mouth
            limits = with_reservations(nbs, self._reservations(idx, pos, nbs))
        outline = self.shape.packed(idx)
        walled = None
        if prm.speed_model == "headway" and prm.headway_overtake_open_lanes:
            walled = self.threads.map(
                partial(lane_runs_into_wall, table, clearance=self.clearance, params=prm),
                idx.size, route=st.route[idx], progress=st.progress[idx], xy=pos,
                radius=self.radius[idx], light=True)
        gap = self._gap_steps(idx, pos, nbs, walled)
        rows = dict(
            heading=st.heading[idx], radius=self.radius[idx],
            route_direction=route_dir, target=target, nominal_step=self.nominal_step[idx],
            neighbours=nbs, speed=self.pop.free_speed[idx], stuck=st.stuck[idx],
            step_time=self.min_step_time[idx], lag=t - te, shape=outline, yaw=st.yaw1[idx],
            gap=gap if (prm.speed_model == "contact_gap" or prm.headway_steer
                        or prm.headway_overtake) else None,
            score_same_time=prm.headway_same_time,
            **self._opening_scales(pos), **({} if limits is None else {"limits": limits}))
        if self._steer_on:  # worker processes (given, not posing); the field goes once
            choice = split_rows(self.workers, choose_steps, idx.size, pos, st.stance[idx],
                                clearance=self.clearance, params=prm.steering,
                                on=self._steer_on, **rows)
        else:  # the field and the parameters go whole, not cut by rows
            steer = partial(choose_steps, clearance=self.clearance, params=prm.steering)
            choice = self.threads.map(steer, idx.size, pos, st.stance[idx], **rows)
        self.wall_steering += _time.perf_counter() - w0
        if gap is not None:
            v, reach = gap.along(choice.direction)
            self.step_speed[idx] = np.maximum(v, 0.05)
            choice = replace(choice, free_length=np.minimum(choice.free_length, reach))
        plan = StepPlan.standing(idx.size)
        mv = np.flatnonzero(choice.move)
        if mv.size:
            w0 = _time.perf_counter()
            plan = plan.put(mv, next_steps(
                st, self.queue, agents=idx[mv], choice=choice.take(mv),
                footsteps=self.footsteps, legs=self.legs, population=self.pop,
                terrain=self.terrain, params=prm, plan_speed=self.plan_speed,
                setting=self.setting, threads=self.threads))
            self.wall_planning += _time.perf_counter() - w0
            # the exact step taken, in time, against each neighbour's committed step
            go = np.flatnonzero(plan.move)
            if go.size and nbs.valid.shape[1]:
                end = st.stance[idx[go]] + 0.5 * plan.length[go, None] * choice.direction[go]
                clash = self.threads.map(
                    partial(clashes_with_neighbours, nbs), go.size, go, start=pos[go], end=end,
                    duration=self._durations(idx[go], plan.take(go)), elapsed=t - te[go],
                    yaw=st.yaw1[idx[go]], yaw_end=choice.yaw[go], shape=outline[go],
                    light=True)
                move = plan.move.copy()
                move[go[clash]] = False
                plan = plan.with_move(move)
                self.queue.clear(idx[go[clash]])
        wake = None
        if self.wake is not None:
            j = nbs.agent
            wake = self.wake.times(t, self.dt, pos, nbs, bound=self.shape.bound[idx],
                                   nb_bound=self.shape.bound[j], step=self.nominal_step[idx],
                                   direction=self._route_directions(idx),
                                   nb_direction=self._route_directions(j))
        self._directions = None  # the commit re-routes
        self._commit(idx, te, t, choice.direction, choice.yaw, plan, wake)

    def _commit(self, idx, te, t, direction, yaw, plan: StepPlan,
                wake: np.ndarray | None = None) -> None:
        st, prm = self.state, self.params
        mv = np.flatnonzero(plan.move)
        if mv.size > 1:
            a = idx[mv]
            new_c = st.stance[a] + plan.length[mv, None] * direction[mv]
            yielders = same_tick_yielders(
                agent=a, start=st.pos1[a], end=0.5 * (st.stance[a] + new_c),
                duration=self._durations(a, plan.take(mv)), elapsed=t - te[mv],
                heel_strike=te[mv], yaw=st.yaw1[a], yaw_end=yaw[mv],
                shape=self.shape.packed(a))
            if yielders.size:
                move = plan.move.copy()
                move[mv[yielders]] = False
                plan = plan.with_move(move)
        wait = idx[~plan.move]
        if wait.size:
            stand(st, self.queue, agents=wait, t=t, terrain=self.terrain, legs=self.legs,
                  params=prm, wake=None if wake is None else wake[~plan.move])
        # blocked: no progress along the route for ``reroute_after`` seconds (side steps
        # and steps back in a jam do not count)
        blocked = idx[t - st.progress_time[idx] >= prm.reroute_after]
        if blocked.size:
            now, _ = st.position(t, self.active)
            self.routes.reroute(st, blocked, t=t, walkers=now)
        go = np.flatnonzero(plan.move)
        if go.size == 0:
            return
        a, steps = idx[go], plan.take(go)
        turn = self._orient(a, direction[go], steps.length)
        batch = take_steps(st, self.queue, agents=a, start_time=te[go], direction=direction[go],
                           yaw=yaw[go], plan=steps, duration=self._durations(a, steps),
                           terrain=self.terrain, legs=self.legs, population=self.pop,
                           foot_half_width=self.half_width[a], turn=turn, threads=self.threads)
        self._decided.append(batch)
        if self.gait is not None:
            if self._pending and np.isin(a, np.concatenate([b.agent for b in self._pending])).any():
                self._flush_commands()  # an agent's earlier step must reach the engine first
            self._pending.append(batch)
            st.animated[a] = True

    def _orient(self, a: np.ndarray, direction: np.ndarray, length: np.ndarray):
        """MetaGait's toe-out and spin turns (:class:`~crowdwalk.gait.metagait.StepTurn`)
        of the steps of agents ``a`` (k,) along ``direction`` (k, 2), ``length`` (k,) [m]:
        ψ is the step's direction; the next step's, d', is where the steering rule would
        head from the new foothold one step further along the route (neighbours aside)."""
        st = self.state
        heading = np.arctan2(direction[:, 1], direction[:, 0])
        body = st.stance[a] + (0.5 * length)[:, None] * direction
        _, ahead = self.threads.map(
            partial(steering_targets, self.routes.table, clearance=self.clearance,
                    params=self.params), a.size,
            route=st.route[a], progress=st.progress[a] + length, xy=body, heading=heading,
            radius=self.radius[a], light=True)
        return self.metagait.orient(a, swing_foot=st.foot[a], heading=heading,
                                    heading_next=np.arctan2(ahead[:, 1], ahead[:, 0]),
                                    base_toe_out=self.pop.style.foot_angle[a])

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
