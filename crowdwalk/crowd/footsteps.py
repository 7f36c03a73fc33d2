"""The footstep planner in the crowd: ground profiles along the agents' local paths,
batched ``planners.plan_batch`` calls, plan caching.

Chen & Li (§4.2) plan the next n steps and walk them. In a crowd the simulation walks the
planned steps while the agent keeps its line, and re-plans at a heel strike when steering
turns it (receding horizon). The planner is the cost centre, so identical planning
problems are answered from a cache. The key is the planner, the leg (2 cm body-height
classes), the speed (5 cm/s classes), the trailing foot (1 mm; left out on level ground,
where it only shapes a swing curve that has nothing to clear) and the ground profile
*relative to the stance foot* (s and z − z₀ rounded to 1 mm, straight runs merged; on
level ground only its height, since level ground is the same ground whatever the
profile's extent): a reused plan's footholds lie within 0.5 mm of where the planner
would put them on that ground. On level ground every step of every agent of a leg and
speed class is the same problem, so it is planned once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["PlannedSteps", "FootstepPlanner"]

_BEHIND = 1.0  # [m] of ground behind the stance foot in the profile (trailing swing foot)
_S_QUANTUM = 1e-3  # [m] rounding of profile arc lengths in the cache key
_Z_QUANTUM = 1e-3  # [m] rounding of profile heights in the cache key


@dataclass(frozen=True)
class PlannedSteps:
    """Planned steps of m agents (struct-of-arrays, H = planning horizon).

    Attributes
    ----------
    ok : (m,) bool
        A legal plan was found.
    step_length : (m, H) float
        Ankle-to-ankle step lengths along the local path [m].
    step_height : (m, H) float
        Height of each new foothold above the previous one [m].
    swing : (m, H, 4, 2) float
        Swing-ankle Bezier control points (s, z) relative to each step's stance ankle
        [m]; NaN when the planner gave none.
    energy : (m, H) float
        Energy of each step [J/kg].
    from_cache : (m,) bool
        The plan came from the cache.
    """

    ok: np.ndarray
    step_length: np.ndarray
    step_height: np.ndarray
    swing: np.ndarray
    energy: np.ndarray
    from_cache: np.ndarray


def _relative_profiles(profiles, stance_z: np.ndarray):
    """The agents' profiles relative to their stance feet, concatenated.

    Parameters
    ----------
    profiles : (s (V,), z (V,), sizes (m,))
        Ground profiles along the local paths [m], s = 0 ``_BEHIND`` behind the stance
        foot, concatenated (``Terrain.profiles_packed``; agent i's ``sizes[i]`` rows
        follow agent i - 1's).
    stance_z : (m,)
        Heights of the stance footholds [m].

    Returns
    -------
    s, z : (V,)
        Vertices of all profiles, s relative to the stance foot and z to its height [m];
        vertices where the ground runs on straight (same slope on both sides, no height
        jump) are dropped: they do not change the ground, only the cache key.
    bounds : (m + 1,) int
        Agent i's vertices are ``bounds[i]:bounds[i + 1]``.
    """
    s_rows, z_rows, sizes = profiles
    m = sizes.size
    agent = np.repeat(np.arange(m), sizes)
    s = s_rows - _BEHIND
    z = z_rows - stance_z[agent]
    inner = np.zeros(s.size, bool)
    if s.size > 2:
        ds0, ds1 = s[1:-1] - s[:-2], s[2:] - s[1:-1]
        dz0, dz1 = z[1:-1] - z[:-2], z[2:] - z[1:-1]
        inner[1:-1] = ((agent[:-2] == agent[1:-1]) & (agent[2:] == agent[1:-1])
                       & (ds0 > 0) & (ds1 > 0)
                       & (np.abs(dz0 * ds1 - dz1 * ds0) <= 1e-9 * ds0 * ds1))
    keep = ~inner
    bounds = np.concatenate([[0], np.cumsum(np.bincount(agent[keep], minlength=m))])
    return s[keep], z[keep], bounds


def _cache_keys(s, z, bounds, planner, leg, speed, trailing) -> list[bytes]:
    """Cache keys of m planning problems.

    Parameters
    ----------
    s, z, bounds
        The relative profiles of :func:`_relative_profiles`.
    planner, leg, speed, trailing : (m,) int
        Planner code, leg class, speed class (5 cm/s) and trailing foot [mm].

    Returns
    -------
    list of bytes
        Per agent the header (planner, leg, speed, level flag, trailing foot, vertex
        count) followed by the vertices' s and z rounded to ``_S_QUANTUM`` and
        ``_Z_QUANTUM``. Level ground (one straight horizontal segment) is the same
        ground whatever the profile's extent (planners.GroundProfile continues level
        past its ends): its key holds its height only. There the trailing foot changes
        only the first swing curve, which the Animator does not need (nothing to clear):
        it is left out as well.
    """
    m = bounds.size - 1
    count = np.diff(bounds)
    first, last = bounds[:-1], bounds[1:] - 1
    level = (count == 2) & (np.abs(z[last] - z[first]) < 1e-9)
    qs = np.round(s / _S_QUANTUM).astype(np.int64)
    qz = np.round(z / _Z_QUANTUM).astype(np.int64)
    n = np.where(level, 0, count)  # vertices in the key
    head = np.column_stack([planner, leg, speed, level, np.where(level, 0, trailing), n])
    width = head.shape[1] + np.where(level, 1, 2 * count)
    mat = np.zeros((m, int(width.max())), dtype=np.int64)
    mat[:, :head.shape[1]] = head
    agent = np.repeat(np.arange(m), count)
    j = np.arange(s.size) - first[agent]  # vertex index within its profile
    full = ~level[agent]
    col = head.shape[1] + j
    mat[agent[full], col[full]] = qs[full]
    mat[agent[full], (col + count[agent])[full]] = qz[full]
    mat[level, head.shape[1]] = qz[first[level]]
    row = mat.shape[1] * mat.itemsize  # each key: the first ``width`` items of its row
    buf = mat.tobytes()
    return [buf[i * row:i * row + w * mat.itemsize] for i, w in enumerate(width.tolist())]


class _PlanStore:
    """The cached plans' steps as growing arrays (rows), gathered per agent at once."""

    def __init__(self, horizon: int) -> None:
        self.size = 0
        self.ok = np.zeros(64, bool)
        self.sl = np.zeros((64, horizon))
        self.sh = np.zeros((64, horizon))
        self.swing = np.zeros((64, horizon, 4, 2))
        self.energy = np.zeros((64, horizon))

    def add(self, steps: tuple) -> int:
        """Append one plan's (ok, step lengths, heights, swings, energies); its row."""
        if self.size == self.ok.shape[0]:
            for name in ("ok", "sl", "sh", "swing", "energy"):
                old = getattr(self, name)
                setattr(self, name, np.concatenate([old, np.zeros_like(old)]))
        row = self.size
        self.ok[row], self.sl[row], self.sh[row], self.swing[row], self.energy[row] = steps
        self.size += 1
        return row

    def add_plans(self, plans: list) -> np.ndarray:
        """Append the steps of the planners' ``plans`` (:func:`_steps_of` of each); their
        rows (P,). Plans of at least H steps with swing curves and energies go in as
        whole arrays (the same values: ``np.diff`` and the subtraction per element),
        failed plans as empty rows, any other one by one."""
        h = self.sl.shape[1]
        while self.size + len(plans) > self.ok.shape[0]:
            for name in ("ok", "sl", "sh", "swing", "energy"):
                old = getattr(self, name)
                setattr(self, name, np.concatenate([old, np.zeros_like(old)]))
        rows = np.arange(self.size, self.size + len(plans))
        self.size += len(plans)
        whole, other = [], []
        for j, p in enumerate(plans):
            if getattr(p, "status", "ok") != "ok" or len(p.step_lengths) == 0:
                continue  # (False, zeros, NaN swings, zeros) as _steps_of gives
            ctrl, energy = getattr(p, "swing_controls", None), getattr(p, "E", None)
            if (len(p.step_lengths) >= h and ctrl is not None and len(ctrl) >= h
                    and energy is not None and np.size(energy) >= h):
                whole.append(j)
            else:
                other.append(j)
        self.ok[rows], self.sl[rows], self.sh[rows], self.energy[rows] = False, 0.0, 0.0, 0.0
        self.swing[rows] = np.nan
        for j in other:
            r = rows[j]
            self.ok[r], self.sl[r], self.sh[r], self.swing[r], self.energy[r] = _steps_of(
                plans[j], h)
        if whole:
            w, ps = rows[whole], [plans[j] for j in whole]
            fs = np.stack([np.asarray(p.footholds_s, float)[:h] for p in ps])
            fz = np.stack([np.asarray(p.footholds_z, float)[:h + 1] for p in ps])
            ctrl = np.stack([np.asarray(p.swing_controls, float)[:h] for p in ps])
            self.ok[w] = True
            self.sl[w] = np.stack([np.asarray(p.step_lengths, float)[:h] for p in ps])
            self.sh[w] = fz[:, 1:] - fz[:, :-1]
            self.swing[w] = ctrl - np.stack([fs, fz[:, :-1]], axis=-1)[:, :, None, :]
            self.energy[w] = np.stack([_step_energies(p)[:h] for p in ps])
        return rows

    def take(self, rows: np.ndarray) -> tuple:
        """(ok, sl, sh, swing, energy) of the plans at ``rows`` (m,) (copies)."""
        return (self.ok[rows], self.sl[rows], self.sh[rows], self.swing[rows],
                self.energy[rows])


def _steps_of(plan, horizon: int) -> tuple:
    """(ok, step lengths (H,), heights (H,), swings (H,4,2) relative, energies (H,))."""
    sl, sh = np.zeros(horizon), np.zeros(horizon)
    swing, energy = np.full((horizon, 4, 2), np.nan), np.zeros(horizon)
    if getattr(plan, "status", "ok") != "ok" or len(plan.step_lengths) == 0:
        return (False, sl, sh, swing, energy)
    k = min(horizon, len(plan.step_lengths))
    fs = np.asarray(plan.footholds_s, float)
    fz = np.asarray(plan.footholds_z, float)
    sl[:k] = np.asarray(plan.step_lengths, float)[:k]
    sh[:k] = np.diff(fz)[:k]
    ctrl = getattr(plan, "swing_controls", None)
    if ctrl is not None and len(ctrl):
        swing[:k] = np.asarray(ctrl, float)[:k] - np.stack([fs[:k], fz[:k]], axis=1)[:, None, :]
    energy[:k] = _step_energies(plan)[:k]
    return (True, sl, sh, swing, energy)


def _step_energies(plan) -> np.ndarray:
    """Energies of the plan's steps [J/kg] (the planner's E of Eq. 4)."""
    value = getattr(plan, "E", None)
    if value is None:
        return np.full(len(plan.step_lengths), np.nan)
    return np.asarray(value, dtype=float).reshape(-1)


class FootstepPlanner:
    """Plans the next step of many agents at once.

    Parameters
    ----------
    terrain : crowdwalk.terrain.Terrain
        Ground (``profile(polyline)``).
    legs : sequence of planners.Leg
        Distinct legs; agents refer to them by index.
    lookahead : float
        Length of the local path ahead of the stance foot [m] (covers the planner's
        n steps of at most ``max_step_ratio`` leg lengths).
    config : planners.PlannerConfig or None
        Planner configuration (None: the planners' defaults).
    horizon : int
        Steps kept per plan (the planner's ``n_steps``).
    clearance : crowdwalk.crowd.clearance.ClearanceField, optional
        Walkable area; local paths end where they leave it.
    """

    def __init__(self, terrain, legs, lookahead: float = 3.0, config=None,
                 horizon: int = 3, clearance=None) -> None:
        self.terrain = terrain
        self.clearance = clearance
        self.legs = list(legs)
        self.lookahead = float(lookahead)
        self.config = config
        self.configs = [config]  # per-walker variants (add_config), index = setting
        self.horizon = int(horizon)
        self._cache: dict[bytes, int] = {}  # key -> row of ``_store``
        self._store = _PlanStore(self.horizon)
        self._planner_codes: dict[str, int] = {}
        self.calls = 0
        self.hits = 0
        self.retries = 0

    def add_config(self, config) -> int:
        """The setting index of planner configuration ``config`` (added if new)."""
        if config not in self.configs:
            self.configs.append(config)
        return self.configs.index(config)

    def _codes(self, names: np.ndarray, setting: np.ndarray) -> np.ndarray:
        """Stable integer codes (m,) of the (planner name (m,) str, setting (m,) int)
        pairs (for the cache keys; one code per distinct pair)."""
        kinds, kind = np.unique(names, return_inverse=True)
        width = int(setting.max()) + 1
        pairs, which = np.unique(kind.astype(np.int64) * width + setting, return_inverse=True)
        codes = np.empty(pairs.size, np.int64)
        for j, p in enumerate(pairs.tolist()):
            key = f"{kinds[p // width]}#{p % width}"
            codes[j] = self._planner_codes.setdefault(key, len(self._planner_codes))
        return codes[which.reshape(-1)]

    def _profiles(self, stance: np.ndarray, direction: np.ndarray) -> tuple:
        """The ground profiles along the local paths of agents at ``stance`` (m, 2) [m]
        heading along ``direction`` (m, 2): ``_BEHIND`` behind the stance foot to
        ``lookahead`` ahead, or to where the path leaves the walkable area; concatenated
        as s, z (V,) [m] and the rows of each (m,) (``Terrain.profiles_packed``)."""
        m = stance.shape[0]
        ahead = np.full(m, self.lookahead)
        if self.clearance is not None:
            # the local path ends where it leaves the walkable area: the walker turns
            # before a wall, so the ground beyond (a drop, a wall top) is not its plan's;
            # past the end the profile continues level (planners.GroundProfile)
            probe = np.arange(0.1, self.lookahead + 1e-9, 0.1)  # (P,)
            pts = stance[:, None, :] + probe[None, :, None] * direction[:, None, :]
            outside = self.clearance(pts) < 0.0  # (m, P)
            first = np.where(outside.any(axis=1), np.argmax(outside, axis=1), probe.size)
            ahead = np.maximum(np.where(first < probe.size, probe[np.minimum(
                first, probe.size - 1)] - 0.1, self.lookahead), 0.3)
        lines = np.stack([stance - _BEHIND * direction, stance + ahead[:, None] * direction],
                         axis=1)  # (m, 2, 2): one straight local path per agent
        if hasattr(self.terrain, "profiles_packed"):
            return self.terrain.profiles_packed(lines)  # one batched terrain pass
        if hasattr(self.terrain, "profiles"):
            arrays = self.terrain.profiles(lines)
        else:
            arrays = [self.terrain.profile_arrays(line) for line in lines]
        return (np.concatenate([a[0] for a in arrays]), np.concatenate([a[1] for a in arrays]),
                np.array([len(a[0]) for a in arrays], dtype=np.int64))

    def plan(
        self,
        stance: np.ndarray,
        stance_z: np.ndarray,
        *,
        direction: np.ndarray,
        leg: np.ndarray,
        speed: np.ndarray,
        planner: np.ndarray,
        trailing: np.ndarray | None = None,
        setting: np.ndarray | None = None,
        threads=None,
    ) -> PlannedSteps:
        """Plan the first step of m agents.

        Parameters
        ----------
        stance : (m, 2)
            Centre-line point of the stance foot's ankle [m].
        stance_z : (m,)
            Height of the stance foothold [m].
        direction : (m, 2)
            Unit walking direction of the local path.
        leg : (m,) int
            Index into ``legs``.
        speed : (m,)
            Walking speed given to the planner [m/s].
        planner : (m,) str
            Planner name per agent (``planners.PLANNERS``).
        trailing : (m,) float, optional
            Arc length of the trailing (swing) foot behind the stance foot [m], < 0.
        setting : (m,) int, optional
            Index into ``configs`` per agent (default 0, ``config``).
        threads : crowdwalk.workers.RowThreads, optional
            Finds the ground profiles of parts of the agents at once (the same result).
        """
        from planners import plan_batch

        m = stance.shape[0]
        if m == 0:
            return PlannedSteps(*self._store.take(np.zeros(0, dtype=np.int64)),
                                np.zeros(0, bool))
        if trailing is None:
            trailing = np.full(m, -0.6)
        # where the trailing foot is shapes the first swing curve, which must clear the
        # ground: planned at 1 mm (in the key only off level ground, see below)
        trailing = np.clip(np.round(np.asarray(trailing, float), 3), -2.9, -0.01)
        # speed classes of 5 cm/s for the planner (the walker keeps its own speed)
        speed_class = np.round(np.asarray(speed, float) / 0.05).astype(np.int64)
        speed = speed_class * 0.05
        if threads is None:
            profiles = self._profiles(stance, direction)
        else:  # row-independent: parts of the agents at once (numpy, the kernels and
            # shapely release the GIL), the same profiles (joined: concatenated)
            profiles = threads.map(self._profiles, m, stance, direction)
        s_all, z_all, bounds = _relative_profiles(profiles, np.asarray(stance_z, float))
        names = np.asarray(planner).astype(str)
        setting = np.zeros(m, np.int64) if setting is None else np.asarray(setting, np.int64)
        codes = self._codes(names, setting)
        keys = _cache_keys(s_all, z_all, bounds, codes, np.asarray(leg),
                           speed_class, np.round(trailing * 1000).astype(np.int64))
        rows = np.array([self._cache.get(k, -1) for k in keys], dtype=np.int64)
        todo = np.flatnonzero(rows < 0)
        self.calls += m
        self.hits += m - todo.size
        if todo.size:
            from planners import GroundProfile

            by_planner: dict[tuple[str, int], dict[bytes, int]] = {}
            for i in todo.tolist():  # the first agent of each new problem plans it
                by_planner.setdefault((str(names[i]), int(setting[i])), {}).setdefault(
                    keys[i], i)
            for (name, c), unique in by_planner.items():
                config = self.configs[c]
                first = list(unique.values())
                grounds = [GroundProfile(s_all[bounds[i]:bounds[i + 1]],
                                         z_all[bounds[i]:bounds[i + 1]]) for i in first]
                legs = [self.legs[leg[i]] for i in first]
                speeds = [float(speed[i]) for i in first]
                behind = [float(trailing[i]) for i in first]
                # a long stride's first swing curve (the trailing foot more than half a leg
                # behind) can fail the planner's clearance test even on near-level
                # ground; such steps are planned again from half a leg behind (the
                # Animator swings the real foot from where it is), so their failed
                # first plans are not diagnosed (the diagnosis evaluates the whole table)
                long = [b < -0.5 * leg_k.length for b, leg_k in zip(behind, legs, strict=True)]
                plans = plan_batch(grounds, legs, speeds, planner=name, config=config,
                                   trailing=behind, diagnose=[not x for x in long])
                retry = [k for k, p in enumerate(plans) if not p.ok and long[k]]
                if retry:
                    self.retries += len(retry)
                    again = plan_batch([grounds[k] for k in retry], [legs[k] for k in retry],
                                       [speeds[k] for k in retry], planner=name,
                                       config=config,
                                       trailing=[-0.5 * legs[k].length for k in retry])
                    for k, p in zip(retry, again, strict=True):
                        plans[k] = p
                for i, row in zip(first, self._store.add_plans(plans).tolist(), strict=True):
                    self._cache[keys[i]] = row
            rows[todo] = [self._cache[keys[i]] for i in todo.tolist()]
        cached = np.ones(m, bool)
        cached[todo] = False
        ok, sl, sh, swing, energy = self._store.take(rows)
        return PlannedSteps(ok, sl, sh, swing, energy, cached)
