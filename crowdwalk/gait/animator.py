"""The batched Animator the crowd drives: step commands in, full-body poses out.

The crowd calls :meth:`Animator.command` when agents start a step (at a heel strike) and
:meth:`Animator.pose` at every output frame (docs/architecture.md, "crowdwalk.gait").

Per step and agent, :class:`~crowdwalk.gait.elevinterp.ElevInterp` turns the commanded
step length and height into an elevation-angle dataset for the agent's body (§5), and
:func:`~crowdwalk.gait.elevwalker.elevwalker_pose` turns the dataset into poses (§4).
Around the walker the Animator adds what a crowd needs:

- **Seamless footholds.** Until toe-off (the data's stance fraction) the trailing foot
  rolls on the ground where it stood, from its ball (the §4.1 model) to its toe tip (IK
  on the swing leg); then the data-driven swing ankle is pulled, with IK, from there to
  where the heel strikes the commanded foothold: offsets measured once per step (walker
  evaluated at toe-off and at the end) blended with a smoothstep. The landing foot is
  the next stance foot, so it neither slides nor jumps. In a turn the pinned ankle's
  goal is corrected until the trailing ball stays put (``GaitStyle.pin_ball``), and a
  toe-off velocity jump above 2 m/s is partly carried into the swing
  (``GaitStyle.toe_off_c1``; docs/architecture.md "Toe-off hand-over and the trailing
  ball in turns").
- **Swing-foot clearance (issue item 6).** When the planner supplies a collision-free
  Bezier swing curve and the data-driven swing foot would come within 2 mm of the ground
  between toe-off and landing (stair nosings, blocks), the swing ankle follows the
  Bezier instead (blended in after toe-off, out before the landing) — with
  ``GaitStyle(lift_swing=False)``. By default (``lift_swing``, gait11) the swing keeps the
  data and the anticipated lift below raises it where the sole would come within
  ``GaitStyle.toe_clearance`` of the ground (the Bezier flexed the ascending swing knee
  to 110–115°; docs/architecture.md "Stair datasets closed over the swing"). Steps are
  "over uneven ground" when the ground rises above the line from the trailing foot to the
  stance foothold or from there to the target, along the ankles' or the toes' path.
- **Whole-sole clearance (deviation: the papers give none for unplanned steps).** The
  planner's Bezier is for the ankle of the steps it planned; shortened and positioning
  steps have none, and toes and the sole's middle can cut an edge the ankle clears.
  The swing sole is a segment, sampled heel → ball → toe tip, and sampled again
  finely (2 mm) between two samples whose ground differs (an edge between them). Over
  uneven ground, at the command, the final swing is sampled over the step (and
  linearly between the samples); where the sole would be below the ground the ankle
  goal is raised by a smooth envelope of bumps over the step's phase (gone at its start
  and over the last tenth, so the feet leave and land where the stance feet are).
  Every frame, a swing sole still below the ground is lifted by its depth (IK again),
  re-checked and lifted further, up to three times.
- **Level steps (docs/architecture.md, "Level steps").** The step asked of ElevInterp
  is shortened by the swing hip's lead at heel strike under the style's pelvic
  rotation (Eq. 10's pelvis term), and over level ground the swing knee flexes until the
  sole clears the floor by ``GaitStyle.toe_clearance`` mid-swing.
- **Continuous root.** Each step crossfades from the previous step's dataset to its own
  (``GaitStyle.step_crossfade``: the legs start where the last dataset left them); what
  still differs at the heel strike (landing corrections) is taken up by the stance hip,
  which starts where the previous step left the root and rejoins the data over the first
  half of the step, or over the whole step after a clamped one
  (``GaitStyle.clamped_join``; sagittal two-link IK of the stance leg).
- **Step-downs beyond the data.** When the landing foothold is out of the swing leg's
  reach, the stance leg bends and lowers the pelvis toward it over the second half of
  the step.
- **Stops (``GaitStyle.stop_settle``, off by default).** A walker whose step ends without a next one
  (the crowd stands it) carries its root on from the heel strike and brings it to rest
  at 10 m/s², both feet where they landed; its next step joins the root C¹ from there
  (docs/architecture.md "Stop settle").
- **Robustness (item 10).** An agent whose solve did not converge, or produced a
  non-finite value, keeps its previous frame's pose and is flagged in
  :attr:`PoseFrame.fallback`; no NaN reaches the output.

Curved paths turn the sagittal plane ψ smoothly from the previous heading to the
commanded one over the step (§4.4). Toe-out and spin turns are MetaGait's (§6.1, in the
crowd :meth:`crowdwalk.gait.metagait.MetaGait.orient`): a commanded spin turn rotates
the stance foot about its ball once the heel has risen off the ground (the data's heel
rise, :func:`_spin_start`), and the body with it; nothing else turns a planted foot.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from crowdwalk.body import JOINT_NAMES, LEG_JOINTS, PARENTS, Body, matrix_to_quaternion
from crowdwalk.errors import invalid
from crowdwalk.gait import animator_kernels as ak
from crowdwalk.gait.datasets import sample
from crowdwalk.gait.elevinterp import ElevInterp, lift_swing_toe
from crowdwalk.gait.elevwalker import (
    GaitStyle,
    StanceHalf,
    WalkerPose,
    WarmStart,
    elevwalker_pose,
    pelvis_shapes,
)
from crowdwalk.gait.engine import GroundHeight, PoseFrame
from crowdwalk.gait.foot import (
    SPIN_HEEL_LIFT,
    StanceFoot,
    direction,
    foot_points,
    stance_foot_pose,
    wrap_angle,
)
from crowdwalk.gait.posing_kernels import smoothstep
from crowdwalk.steps import StepBatch

__all__ = ["StepCommand", "PoseFrame", "Animator", "GroundHeight"]


_CLEARANCE = 0.002  # swing foot closer to the ground than this [m] → follow the Bezier
_CHECK_SPAN = np.linspace(0.0, 1.0, 10)  # swing samples, fractions of toe-off → 0.95
_PHASE_END = 0.5 - 1e-6
_BEZIER_IN, _BEZIER_OUT = 0.5, 0.3  # the Bezier blends in / out over these fractions of swing
_HIP_BLEND = 0.5  # fraction of the step over which the root joins the data again
_HIP_BLEND_CLAMPED = 1.0  # ... after a step served clamped (GaitStyle.clamped_join)
_C1_RISE = 0.05  # steps rising or falling this much [m] (stairs) join the root C¹ ...
_VEL_PHASE = 0.02  # ... with velocities measured over this stance-phase interval [1]
_TRAIL_CONTINUES = np.deg2rad(3.0)  # new data continue the trailing leg within [rad]
_TRAIL_TURN = np.deg2rad(45.0)  # ... on steps turning less (MetaGait's T, §6.1) [rad]
_SPIN_GRID = np.linspace(0.0, 1.0, 41)  # step phases searched for the heel rise
_MAX_TOE_START = np.radians(40.0)  # largest toe-out the swing leg starts from
_MIN_STEP = 0.05  # shortest step requested of ElevInterp [m]
_SOLE_SAMPLES = 8  # ground samples along the sole, heel to toe tip
_SOLE_HEEL_BALL = np.linspace(0.0, 1.0, 5)  # swing-sole samples, heel → ball (≤ 5 cm apart)
_SOLE_BALL_TOE = np.array([1.0])  # ... and the toe tip (edges between: sub-sampled)
_EDGE_JUMP = 0.005  # ground step between two sole samples that is looked into [m]
_EDGE_SUB = (np.arange(24) + 0.5) / 24  # where it is looked for between the two
_LIFT_GRID = np.linspace(0.0, 1.0, 9)  # step phases sampled for the anticipated lift
_LIFT_SUB = np.array([0.25, 0.5, 0.75])  # sole positions sampled between two of them
_LIFT_WIDTH = 0.2  # half-width of each sample's lift bump, fraction of the step
_LIFT_LAND = 0.1  # the lift is gone over this last fraction of the step (the landing)
_LIFT_ROUNDS = 3  # clearance passes on a swing foot below the ground
_LIFT_MARGIN = 1e-3  # a lifted swing sole clears the ground by this [m]
_LEVEL_RISE = 0.02  # steps rising or falling less than this are level [m]
_YAW_ROUNDS = 2  # corrections of the swing foot's yaw per frame
_REACH = 0.995  # largest hip–ankle distance at landing, fraction of thigh + shank
_TOE_OFF_BLEND = 0.7  # the toe-off velocity hand-over lasts this fraction of the swing
_TOE_OFF_ACCEL = 25.0  # ... adds at most this acceleration [m/s²] (chosen on the park)
_TOE_OFF_KEEP = 2.0  # ... and leaves a velocity jump up to this [m/s] (level walkers: 1.2-1.8)
_TOE_OFF_PEAK = 3.94  # max |h''(u)| of its shape (_toe_off_shape)
_TOE_OFF_DPHASE = 0.005  # stance-phase interval of its velocity differences [1]
_TOE_OFF_GRID = np.linspace(0.0, 1.0, 11)  # data_toe_off: fractions of the toe-off sampled
_TOE_OFF_RISE = 0.035  # data_toe_off: the data's swing sole risen this far is off [m] (park)
_TOE_OFF_SHORT = 0.75  # ... on steps shorter than this [leg lengths] (park's: <= 0.74)
_PIN_ROUNDS = 2  # corrections of the pinned push-off ankle's goal per frame ...
_PIN_TOLERANCE = 0.002  # ... while its ball is farther than this from the pin's [m]
_SETTLE_DECEL = 10.0  # a stopping walker's root comes to rest at this [m/s²] (stop_settle)
_SETTLE_SPEED = 1.25  # ... from at most this times its last step's speed [1]


def _toe_off_shape(u: np.ndarray) -> np.ndarray:
    """The toe-off hand-over's shape h(u) (k,), u ∈ [0, 1] (k,): h(0) = 0, h'(0) = 1, and
    h, h', h'' zero at u = 1 (quintic; h''(0) = 0: no acceleration added at either end)."""
    return u * (1.0 - u) ** 3 * (1.0 + 3.0 * u)


def _bezier(ctrl: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Cubic Bezier points (k, 3) of control points (k, 4, 3) at parameters tau (k,)
    (compiled: ``animator_kernels.bezier_points``)."""
    tau = _floats(tau)
    return ak.bezier_points(np.ascontiguousarray(ctrl, dtype=float), tau, (1.0 - tau)**3,
                            tau**3)


def _rows(a: np.ndarray) -> np.ndarray:
    """Agent indices (k,) as the kernels take them (intp)."""
    return np.asarray(a, dtype=np.intp)


def _floats(x) -> np.ndarray:
    """(k,) float64, C-contiguous, for the kernels."""
    return np.ascontiguousarray(x, dtype=np.float64)


def _spin_start(body: Body, angles: np.ndarray, yaw_off: np.ndarray,
                slope: np.ndarray) -> np.ndarray:
    """Step phase τ (m,) [1] at which the stance foot's heel has risen ``SPIN_HEEL_LIFT``
    off the ground, rolling on its ball (§4.1: the foot pitch of the data ``angles``
    (m, S, 4) below the ground ``slope`` (m,) [rad], seen ``yaw_off`` (m,) [rad] from the
    sagittal plane); 1 where it never does (a spin then turns nothing)."""
    m = slope.size
    phases = np.tile(0.5 * np.minimum(_SPIN_GRID, 1.0 - 1e-6), m)
    rows = np.repeat(np.arange(m), _SPIN_GRID.size)
    phi = sample(angles, phases, rows=rows)[:, 0].reshape(m, -1)
    pitch = np.arctan(np.tan(phi) * np.cos(yaw_off)[:, None])
    hb = (body.heel_offset + body.ball_offset)[:, None]
    up = hb * np.sin(np.maximum(slope[:, None] - pitch, 0.0)) >= SPIN_HEEL_LIFT
    up &= _SPIN_GRID[None, :] > 0.3  # the rise of late stance, not the heel strike
    return np.where(up.any(axis=1), _SPIN_GRID[np.argmax(up, axis=1)], 1.0)


def _column(values, m: int, owner: str, name: str, constraint: str, dtype=float) -> np.ndarray:
    arr = np.asarray(values, dtype=dtype)
    if arr.shape != (m,):
        raise invalid(owner, name, f"an ({m},) array {constraint}", arr.shape)
    return arr


@dataclass(frozen=True, eq=False)
class StepCommand:
    """Steps that m agents start now (at their heel strike).

    Attributes
    ----------
    agent : (m,) int, agent index into the Animator's bodies.
    time : (m,) step start [s].
    duration : (m,) heel strike to next heel strike [s], > 0.
    swing_foot : (m,) int, 0 = left foot swings, 1 = right foot swings.
    start : (m, 3) stance foothold (ground point below the stance ankle) [m].
    target : (m, 3) foothold where the swing foot lands [m].
    heading : (m,) walking direction ψ at the end of the step, from +x [rad].
    step_length, step_height : (m,) [m], requested of ElevInterp (foothold to foothold).
    swing_bezier : (m, 4, 3), optional
        Planner's collision-free Bezier control points of the swing ankle, world xyz [m];
        rows of NaN where an agent has none.
    toe_out : (m,), optional
        Toe-out of the swing foot [rad] (MetaGait §6.1); default the style's.
    spin : (m,), optional
        Spin turn on the stance foot [rad], positive counter-clockwise (§6.1).
    speed : (m,), optional
        Walking speed of the step [m/s] (length / duration), for ElevInterp's speed blend.
    """

    agent: np.ndarray
    time: np.ndarray
    duration: np.ndarray
    swing_foot: np.ndarray
    start: np.ndarray
    target: np.ndarray
    heading: np.ndarray
    step_length: np.ndarray
    step_height: np.ndarray
    swing_bezier: np.ndarray | None = None
    toe_out: np.ndarray | None = None
    spin: np.ndarray | None = None
    speed: np.ndarray | None = None

    def take(self, rows: np.ndarray) -> StepCommand:
        """The commands at ``rows`` (k,) (every field's rows; optional fields stay None)."""
        return StepCommand(**{f.name: None if (v := getattr(self, f.name)) is None else v[rows]
                              for f in fields(self)})

    @classmethod
    def from_batch(cls, steps: StepBatch) -> StepCommand:
        """The gait part of the crowd's steps (step lengths below 5 cm requested as 5 cm)."""
        return cls(agent=steps.agent, time=steps.start_time, duration=steps.duration,
                   swing_foot=steps.foot.astype(int), start=steps.start, target=steps.target,
                   heading=steps.heading, step_length=np.maximum(steps.length, _MIN_STEP),
                   step_height=steps.rise, swing_bezier=steps.swing_bezier,
                   speed=np.maximum(steps.length, _MIN_STEP) / steps.duration,
                   toe_out=steps.toe_out, spin=steps.spin)

    def __post_init__(self) -> None:
        owner = "StepCommand"
        agent = np.atleast_1d(np.asarray(self.agent))
        if agent.ndim != 1 or not np.issubdtype(agent.dtype, np.integer):
            raise invalid(owner, "agent", "an (m,) integer array", agent.dtype)
        m = agent.size
        object.__setattr__(self, "agent", agent.astype(np.intp))
        for name in ("time", "duration", "heading", "step_length", "step_height"):
            arr = _column(np.atleast_1d(getattr(self, name)), m, owner, name, "[finite]")
            if not np.all(np.isfinite(arr)):
                raise invalid(owner, name, "finite", arr[~np.isfinite(arr)][:3])
            object.__setattr__(self, name, arr)
        if np.any(self.duration <= 0):
            raise invalid(owner, "duration", "> 0 [s]", self.duration[self.duration <= 0][:3])
        if np.any(self.step_length <= 0):
            raise invalid(owner, "step_length", "> 0 [m]", self.step_length.min())
        foot = _column(np.atleast_1d(self.swing_foot), m, owner, "swing_foot", "of 0/1", int)
        if np.any((foot != 0) & (foot != 1)):
            raise invalid(owner, "swing_foot", "0 (left) or 1 (right)", foot[(foot > 1)][:3])
        object.__setattr__(self, "swing_foot", foot)
        for name in ("start", "target"):
            arr = np.asarray(getattr(self, name), dtype=float).reshape(-1, 3)
            if arr.shape != (m, 3) or not np.all(np.isfinite(arr)):
                raise invalid(owner, name, f"a finite ({m}, 3) array [m]", arr.shape)
            object.__setattr__(self, name, arr)
        if self.swing_bezier is not None:
            bez = np.asarray(self.swing_bezier, dtype=float)
            if bez.shape != (m, 4, 3):
                raise invalid(owner, "swing_bezier", f"an ({m}, 4, 3) array [m]", bez.shape)
            object.__setattr__(self, "swing_bezier", bez)
        for name in ("toe_out", "spin"):
            value = getattr(self, name)
            if value is not None:
                arr = _column(np.atleast_1d(value), m, owner, name, "[rad]")
                if not np.all(np.isfinite(arr) & (np.abs(arr) < np.pi)):
                    raise invalid(owner, name, "finite and in (-π, π) [rad]", arr)
                object.__setattr__(self, name, arr)
        if self.speed is not None:
            arr = _column(np.atleast_1d(self.speed), m, owner, "speed", "[m/s]")
            if not np.all(np.isfinite(arr) & (arr > 0)):
                raise invalid(owner, "speed", "finite and > 0 [m/s]", float(arr.min()))
            object.__setattr__(self, "speed", arr)


@dataclass(eq=False)
class _StepState:
    """The step each of n agents is in: its dataset and timing."""

    commanded: np.ndarray  # (n,) bool, has had a command
    angles: np.ndarray  # (n, S, 4) elevation-angle dataset of the step [rad]
    prev_angles: np.ndarray  # (n, S, 4) ... of the step before (the crossfade's start) [rad]
    stance_fraction: np.ndarray  # (n,) of the dataset's cycle
    t0: np.ndarray  # (n,) step start [s]
    duration: np.ndarray  # (n,) [s]
    stance_left: np.ndarray  # (n,) bool
    psi0: np.ndarray  # (n,) heading at the start of the step [rad]
    psi1: np.ndarray  # (n,) ... at its end [rad]
    spin_start: np.ndarray  # (n,) step phase τ at which a spin turn starts [1]
    first: np.ndarray  # (n,) bool, the agent's first step (a walk from standing)
    rise: np.ndarray  # (n,) commanded step height [m]

    @classmethod
    def zeros(cls, n: int, samples: int) -> _StepState:
        return cls(np.zeros(n, bool), np.zeros((n, samples, 4)), np.zeros((n, samples, 4)),
                   np.full(n, 0.6),
                   np.zeros(n), np.ones(n), np.ones(n, bool), np.zeros(n), np.zeros(n),
                   np.ones(n), np.ones(n, bool), np.zeros(n))


@dataclass(eq=False)
class _StanceState:
    """The stance foot of n agents and the step's footholds."""

    ball: np.ndarray  # (n, 3) contact under the ball [m]
    yaw: np.ndarray  # (n,) [rad]
    slope: np.ndarray  # (n,) [rad]
    spin: np.ndarray  # (n,) spin turn on the ball [rad]
    toe_out: np.ndarray  # (n,) toe-out the swing foot turns to [rad]
    toe_start: np.ndarray  # (n,) ... and starts from [rad]
    start: np.ndarray  # (n, 3) commanded stance foothold [m]
    target: np.ndarray  # (n, 3) commanded landing foothold [m]

    @classmethod
    def zeros(cls, n: int, toe_out: float) -> _StanceState:
        return cls(np.zeros((n, 3)), np.zeros(n), np.zeros(n), np.zeros(n),
                   np.full(n, toe_out), np.full(n, toe_out), np.zeros((n, 3)),
                   np.zeros((n, 3)))


@dataclass(eq=False)
class _SwingState:
    """The corrections of the data-driven swing and root of n agents over their step."""

    d0: np.ndarray  # (n, 3) swing-ankle offset at toe-off [m]
    d1: np.ndarray  # (n, 3) ... at the landing [m]
    trail_ball: np.ndarray  # (n, 3) trailing foot's ball in push-off [m]
    trail_yaw: np.ndarray  # (n,) [rad]
    trail_slope: np.ndarray  # (n,) [rad]
    has_trail: np.ndarray  # (n,) bool, pinned in push-off
    trail_root: np.ndarray  # (n,) bool, the root moves on with the trailing leg
    served: np.ndarray  # (n,) bool, the step's dataset was served as asked (not clamped)
    toe_off: np.ndarray  # (n,) toe-off, fraction of the step
    bezier: np.ndarray  # (n, 4, 3) planner's swing-ankle Bezier [m]
    use_bezier: np.ndarray  # (n,) bool
    lift_need: np.ndarray  # (n, G) anticipated lift at the _LIFT_GRID phases [m]
    hip_fix: np.ndarray  # (n, 3) root continuity offset [m]
    hip_vel: np.ndarray  # (n, 3) root velocity jump the offset starts with [m/s]
    hip_drop: np.ndarray  # (n, 3) pelvis drop toward an out-of-reach landing [m]
    join_long: np.ndarray  # (n,) bool, hip_fix blends out over the whole step (clamped_join)
    join_whole: np.ndarray  # (n,) bool, ... and hip_vel too (a restart: stop_settle)
    toe_vel: np.ndarray  # (n, 3) pinned ankle's velocity less the data's at toe-off [m/s]

    @classmethod
    def zeros(cls, n: int) -> _SwingState:
        return cls(np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3)), np.zeros(n),
                   np.zeros(n), np.zeros(n, bool), np.zeros(n, bool), np.zeros(n, bool),
                   np.zeros(n), np.zeros((n, 4, 3)),
                   np.zeros(n, bool), np.zeros((n, _LIFT_GRID.size)), np.zeros((n, 3)),
                   np.zeros((n, 3)), np.zeros((n, 3)), np.zeros(n, bool), np.zeros(n, bool),
                   np.zeros((n, 3)))


@dataclass(eq=False)
class _SolverWarmth:
    """Gauss–Newton warm starts of n agents (stance ankle, swing hip) and Jacobians."""

    ankle: np.ndarray  # (n, 2) [rad]
    hip: np.ndarray  # (n, 3) [rad]
    ankle_jacobian: np.ndarray  # (n, 2, 2), NaN: none
    hip_jacobian: np.ndarray  # (n, 3, 3), NaN: none

    @classmethod
    def zeros(cls, n: int) -> _SolverWarmth:
        return cls(np.zeros((n, 2)), np.zeros((n, 3)), np.full((n, 2, 2), np.nan),
                   np.full((n, 3, 3), np.nan))


@dataclass(eq=False)
class _LastPose:
    """The last pose of n agents (kept where a solve fails)."""

    has: np.ndarray  # (n,) bool
    root: np.ndarray  # (n, 3) [m]
    rotation: np.ndarray  # (n, 3, 3)
    local: np.ndarray  # (n, J, 3, 3)
    positions: np.ndarray  # (n, J, 3) [m]
    contact: np.ndarray  # (n, 2) bool

    @classmethod
    def zeros(cls, n: int, joints: int) -> _LastPose:
        return cls(np.zeros(n, bool), np.zeros((n, 3)),
                   np.broadcast_to(np.eye(3), (n, 3, 3)).copy(),
                   np.broadcast_to(np.eye(3), (n, joints, 3, 3)).copy(),
                   np.zeros((n, joints, 3)), np.ones((n, 2), bool))


@dataclass(frozen=True, eq=False)
class _FreeWalk:
    """Joint positions (k, J, 3) [m] and convergence (k,) of an uncorrected walk of k
    agents (what :meth:`Animator._trailing_solved` reads of its free walk)."""

    positions: np.ndarray
    converged: np.ndarray

    def take(self, rows: np.ndarray) -> _FreeWalk:
        return _FreeWalk(self.positions[rows], self.converged[rows])


@dataclass(frozen=True, eq=False)
class _Landed:
    """Where the previous step of m agents left the root (m, 3) [m] and the landed foot:
    heel (m, 3) [m], yaw (m,) [rad]; the old stance foot's yaw (m,) [rad]; the root's
    velocity at the end (m, 3) [m/s] (zero where not measured)."""

    root: np.ndarray
    heel: np.ndarray
    yaw: np.ndarray
    old_yaw: np.ndarray
    root_velocity: np.ndarray


@dataclass(eq=False)
class _Settle:
    """The stop settle of n agents (``GaitStyle.stop_settle``): per step, whether the
    root's velocity (n, 3) [m/s] and the landed (swing) ankle (n, 3) [m] at its end are
    measured (``has`` (n,) bool); per walk, the agents settling (``on`` (n,) bool) and
    their root offsets (n, 3) [m] from the step's end pose; the time (n,) [s] each agent
    was last posed at; per stop, the last offset (n, 3) [m] its pose was solved with
    (``good``) and whether the root is held there (``held`` (n,) bool: a solve failed
    beyond it)."""

    has: np.ndarray
    velocity: np.ndarray
    ankle: np.ndarray
    on: np.ndarray
    shift: np.ndarray
    seen: np.ndarray
    good: np.ndarray
    held: np.ndarray

    @classmethod
    def zeros(cls, n: int) -> _Settle:
        return cls(np.zeros(n, bool), np.zeros((n, 3)), np.zeros((n, 3)), np.zeros(n, bool),
                   np.zeros((n, 3)), np.full(n, -np.inf), np.zeros((n, 3)), np.zeros(n, bool))


def _settled(velocity: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Root offset (k, 3) [m] and velocity (k, 3) [m/s] u (k,) [s] after a stop that
    began with ``velocity`` (k, 3) [m/s]: brought to rest at the constant deceleration
    _SETTLE_DECEL."""
    rest = np.linalg.norm(velocity, axis=1) / _SETTLE_DECEL  # time to rest [s]
    w = np.minimum(u, rest)[:, None]
    frac = np.where(rest > 0.0, 1.0 / np.maximum(rest, 1e-12), 0.0)[:, None]
    return velocity * (w - 0.5 * w * w * frac), velocity * (1.0 - w * frac)


def _first_rows(walked: WalkerPose, k: int) -> WalkerPose:
    """The first k rows of a walk (views)."""
    w = walked.warm
    return WalkerPose(
        walked.root_position[:k], walked.root_rotation[:k], walked.local[:k],
        walked.positions[:k], walked.rotations[:k], walked.contact[:k], walked.converged[:k],
        WarmStart(*(None if x is None else x[:k] for x in (w.ankle, w.hip, w.ankle_jacobian,
                                                           w.hip_jacobian))),
        None if walked.solves is None else walked.solves[:k],
        None if walked.stance is None else walked.stance.take(slice(0, k)))


@dataclass(frozen=True, eq=False)
class _WalkInputs:
    """What :meth:`Animator._walk` hands ElevWalker for k agents before the re-walks' own
    fixes (swing ankle ``lift``, ``toe_fix``, ``pin_fix``): the bodies, stance sides,
    phases (k,), legs ``st``/``sw`` (k, 4), heading ``psi`` (k,), stance ``foot``, the
    swing's toe-out (k,), warm starts, stance fractions (k,), the step corrections
    (``offset``, ``target``, ``goal`` (k, 3) [m] without lift or pin fix, ``blend``,
    ``toes`` (k,), ``hip_fix`` (k, 3); None uncorrected), the push-off rows ``pinned``
    (k,) bool (whose goal takes the pin fix: not a settling row's), the anticipated
    lift ``envelope`` (k,) [m] or None, styles, list scales.

    Within one :meth:`Animator.pose` none of them changes between the frame's walk and
    its re-walks (the warm starts are stored after the last walk; each agent's terms are
    its own), so the re-walks take their rows (:meth:`take`) instead of computing them
    again: the same values (``Animator._rewalk``)."""

    body: Body
    stance_left: np.ndarray
    phase: np.ndarray
    st: np.ndarray
    sw: np.ndarray
    psi: np.ndarray
    foot: StanceFoot
    toe_out: np.ndarray
    warm: WarmStart
    stance_fraction: np.ndarray
    offset: np.ndarray | None
    target: np.ndarray | None
    blend: np.ndarray | None
    goal: np.ndarray | None
    toes: np.ndarray | None
    hip_fix: np.ndarray | None
    pinned: np.ndarray | None
    envelope: np.ndarray | None
    attributes: object
    list_scale: np.ndarray

    def take(self, rows: np.ndarray) -> _WalkInputs:
        """The agents at ``rows`` (m,) (fresh arrays)."""
        def cut(v):
            if v is None or isinstance(v, np.ndarray):
                return None if v is None else v[rows]
            if isinstance(v, StanceFoot):
                return StanceFoot(v.ball[rows], v.yaw[rows], v.slope[rows])
            if isinstance(v, WarmStart):
                return WarmStart(*(None if x is None else x[rows] for x in
                                   (v.ankle, v.hip, v.ankle_jacobian, v.hip_jacobian)))
            return v.take(rows)  # Body, Style

        return _WalkInputs(**{f.name: cut(getattr(self, f.name)) for f in fields(self)})


class Animator:
    """Full-body poses for n agents from step commands (Sun & Metaxas 2001).

    Parameters
    ----------
    body : Body
        The n agents' bodies; agent i is row i.
    ground : callable, optional
        ``ground(xy (p, 2)) -> z (p,)`` [m], e.g. ``world.terrain.height``; used for the
        stance-foot slope and swing-foot clearance. Without it the ground is taken as the
        straight line between the step's two footholds.
    style : GaitStyle, optional
    interp : ElevInterp, optional
        Shared dataset interpolator (default: a new one over the shipped datasets).
    """

    def __init__(
        self,
        body: Body,
        ground: GroundHeight | None = None,
        style: GaitStyle | None = None,
        interp: ElevInterp | None = None,
        attributes=None,
    ) -> None:
        if not isinstance(body, Body):
            raise invalid("Animator", "body", "a crowdwalk.body.Body", type(body).__name__)
        self.body = body
        self.ground = ground
        self.style = style or GaitStyle()
        self.attributes = attributes  # crowdwalk.style.Style (n) or None
        self.interp = interp or ElevInterp()
        n = len(body)
        n_samples = self.interp.datasets[0].samples
        nj = len(JOINT_NAMES)
        self._step = _StepState.zeros(n, n_samples)
        self._stance = _StanceState.zeros(n, self.style.toe_out)
        self._swing = _SwingState.zeros(n)
        self._warm = _SolverWarmth.zeros(n)
        self._last = _LastPose.zeros(n, nj)
        self._settle = _Settle.zeros(n)
        self.stats = {"commands": 0, "poses": 0, "fallbacks": 0, "bezier_steps": 0,
                      "lifted": 0, "lift_steps": 0, "yaw_fixes": 0, "pin_fixes": 0,
                      "data_toe_offs": 0}  # fmt: skip

    # -- public -----------------------------------------------------------------------
    @property
    def skeleton(self) -> tuple[tuple[str, ...], np.ndarray]:
        """Joint names (J,) and parent indices (J,) for ``record.RunWriter``."""
        return JOINT_NAMES, PARENTS.copy()

    def command(self, cmd: StepBatch | StepCommand) -> None:
        """Start steps for the agents in ``cmd`` (batched; call at their heel strikes):
        the crowd's :class:`~crowdwalk.steps.StepBatch` (the :class:`GaitEngine`
        protocol) or a :class:`StepCommand`.

        Phases, in order: where the previous step left root and landed foot
        (:meth:`_landed`); the new stance foot (:meth:`_new_stance`); the step's dataset
        and per-step state (:meth:`_start_step`); root continuity (:meth:`_join_root`);
        the swing's ends, push-off and reach (:meth:`_swing_ends`); the planner's swing
        curve where the data's foot would touch the ground (:meth:`_swing_curve`); the
        anticipated lift over uneven ground (:meth:`_anticipate_lift`).
        """
        if isinstance(cmd, StepBatch):
            cmd = StepCommand.from_batch(cmd)
        n = len(self.body)
        a = cmd.agent
        if a.size == 0:
            return
        if np.any((a < 0) | (a >= n)):
            raise invalid("StepCommand", "agent", f"indices in [0, {n})", a[(a < 0) | (a >= n)])
        if np.unique(a).size != a.size:
            raise invalid("StepCommand", "agent", "without repeated agents", a)
        body = self.body.take(a)
        had = self._step.commanded[a].copy()
        # stair steps (this one or the last rises or falls _C1_RISE): C¹ root join
        c1 = had & ((np.abs(self._step.rise[a]) >= _C1_RISE)
                    | (np.abs(cmd.step_height) >= _C1_RISE))
        # walkers that stood since their last step's end (stop_settle): the root settled
        stopped = had & (cmd.time > self._step.t0[a] + self._step.duration[a])
        # ... or, without the settle, whose pose stood frozen (restart_c1): C¹ from rest
        # (their landed root velocity stays zero: not measured)
        rested = stopped & (self.style.restart_c1 and not self.style.stop_settle)
        stopped &= self.style.stop_settle
        landed = self._landed(a, had, c1 | stopped, cmd.time, stopped)
        c1 |= stopped | rested
        self._settle.has[a] = self._settle.held[a] = False
        self._settle.good[a] = 0.0
        st = self._stance
        trail = (st.ball[a].copy(), st.yaw[a] + st.spin[a], st.slope[a].copy())
        half = self._step.angles.shape[1] // 2
        trailing_before = self._step.angles[a, half, :3].copy()  # the stance leg at t = 0.5
        spun_before = self._stance.spin[a] != 0.0
        flat_before = np.abs(self._step.rise[a]) < _LEVEL_RISE
        served_before = self._swing.served[a].copy()
        stance, toe_out, psi0 = self._new_stance(cmd, body, had, landed)
        data = self._start_step(cmd, body, had, stance, toe_out, psi0)
        joined = self._join_root(a, had, landed, c1)
        restart = stopped | rested
        if restart.any():  # the restart's C¹ term at most _SETTLE_SPEED times the step's
            ast = a[restart]
            cap = _SETTLE_SPEED * np.linalg.norm(
                (cmd.target - cmd.start)[restart, :2], axis=1) / cmd.duration[restart]
            jump = np.linalg.norm(self._swing.hip_vel[ast], axis=1)
            self._swing.hip_vel[ast] *= np.minimum(1.0, cap / np.maximum(jump, 1e-12))[:, None]
        swing_from = np.where(had[:, None], trail[0], cmd.start)
        bumpy = self._uneven(cmd, body, swing_from)
        # the root follows the trailing leg where the new data continue it (a short step
        # after a long one, a stop, a start do not) on a straight or gently curved path
        # over level ground
        continues = np.abs(self._step.angles[a, half, :3] - trailing_before).max(axis=1)
        turn = np.abs(wrap_angle(cmd.heading - self._step.psi0[a]))
        self._swing.join_long[a] = had & ~served_before & self.style.clamped_join
        self._swing.join_whole[a] = stopped  # (rested: over half the step, as stairs)
        self._swing.served[a] = ~data.clamped
        self._swing.trail_root[a] = (had & self.style.trailing_root & flat_before & ~bumpy
                                     & served_before & ~data.clamped
                                     & (np.abs(cmd.step_height) < _LEVEL_RISE)
                                     & (continues < _TRAIL_CONTINUES) & (turn < _TRAIL_TURN)
                                     & ~spun_before & (self._stance.spin[a] == 0.0)
                                     & ~restart)
        sw = self._swing
        sw.trail_ball[a], sw.trail_yaw[a], sw.trail_slope[a] = trail
        sw.has_trail[a] = had
        joins = np.flatnonzero(sw.trail_root[a])
        if joins.size:  # the join starts from the trailing leg's root, not the stance leg's
            aj = a[joins]
            # the free walk at phase 0 is the root join's walk of those agents (its rows:
            # the same arguments, no spin), unless a stance yaw is −0.0 (the join's walk
            # adds the spin's +0.0 to it)
            yaw = self._stance.yaw[aj]
            free = None if np.any(np.signbit(yaw) & (yaw == 0.0)) else joined.take(
                np.cumsum(had)[joins] - 1)
            sw.hip_fix[aj] -= self._trailing_solved(aj, np.zeros(aj.size), free)
        capped = self._swing_ends(cmd, body, had, data.angles)
        if self.style.data_toe_off and self.ground is not None:
            # where the toe-off hand-over's cap leaves a jump on a short step off stairs:
            # let the foot go where the data have lifted it, and find the swing's ends again
            short = cmd.step_length < _TOE_OFF_SHORT * (body.thigh + body.shank)
            j = np.flatnonzero(capped & short & ~c1)
            j = j[self._data_toe_off(a[j])]
            if j.size:
                aj = a[j]
                sw.d0[aj] = sw.d1[aj] = sw.toe_vel[aj] = sw.hip_drop[aj] = 0.0
                self._swing_ends(cmd.take(j), body.take(j), had[j], data.angles[j])
        self._swing_curve(cmd, bumpy)
        if bumpy.any():
            self._anticipate_lift(a[bumpy])
        self.stats["commands"] += a.size

    def _landed(self, a: np.ndarray, had: np.ndarray, c1: np.ndarray, t=None,
                stopped: np.ndarray | None = None) -> _Landed:
        """Where the previous step (of the agents ``had`` a step) left the root and the
        foot that landed, at its end; the root's velocity there for the agents ``c1``.
        The agents ``stopped`` (a subset of c1) are where their settle has taken the root
        by time ``t`` (k,) [s] (:meth:`_settling`), at its velocity then."""
        m = a.size
        out = _Landed(np.zeros((m, 3)), np.zeros((m, 3)), np.zeros(m), np.zeros(m),
                      np.zeros((m, 3)))
        settling = stopped is not None and stopped.any()
        if settling:
            as_ = a[stopped]
            velocity = self._settling(as_, t[stopped] - self._step.t0[as_]
                                      - self._step.duration[as_])
        try:
            self._landed_walk(a, had, c1, out)
        finally:
            self._settle.on[:] = False
        if settling:
            out.root_velocity[stopped] = velocity
        return out

    def _landed_walk(self, a: np.ndarray, had: np.ndarray, c1: np.ndarray,
                     out: _Landed) -> None:
        """:meth:`_landed`'s walk, into ``out``."""
        if had.any():
            # one walk: the agents' ends, and the c1 agents (a subset) a little earlier
            # (each agent's walk is its own: the values of separate walks)
            ah, ac = a[had], a[c1]
            k = ah.size
            walked = self._walk(np.concatenate([ah, ac]), np.concatenate(
                [np.full(k, _PHASE_END), np.full(ac.size, _PHASE_END - _VEL_PHASE)]),
                corrected=True)
            root = walked.root_position
            if ac.size:
                out.root_velocity[c1] = (root[:k][c1[had]] - root[k:]) / (
                    2.0 * _VEL_PHASE * self._step.duration[ac])[:, None]
            old_st = np.where(self._step.stance_left[ah], 0, 1)
            out.root[had] = root[:k]
            feet = foot_points(self.body.take(ah), walked.positions[:k], walked.rotations[:k])
            new_st = feet[np.arange(k), 1 - old_st]  # the foot that just landed
            out.heel[had] = new_st[:, 0]
            toward = new_st[:, 1] - new_st[:, 0]
            out.yaw[had] = np.arctan2(toward[:, 1], toward[:, 0])
            out.old_yaw[had] = self._stance.yaw[ah] + self._stance.spin[ah]

    def _settling(self, a: np.ndarray, u: np.ndarray) -> np.ndarray:
        """Turn the stop settle on for agents a (k,), u (k,) [s] after their step's end
        (the next walks carry their roots on, the landed ankles kept where they were;
        ``_settle.on`` is cleared by the caller); the root velocity (k, 3) [m/s] then.
        The step end's root velocity and landed ankle are measured once per step."""
        s = self._settle
        new = a[~s.has[a]]
        if new.size:  # not measured in the frame before (pose's step ends ahead)
            k = new.size
            walked = self._walk(np.concatenate([new, new]), np.concatenate(
                [np.full(k, _PHASE_END), np.full(k, _PHASE_END - _VEL_PHASE)]),
                corrected=True)
            self._settle_ends(new, walked.root_position[:k], walked.root_position[k:],
                              np.full(k, _VEL_PHASE), walked.positions[:k])
        shift, velocity = _settled(s.velocity[a], u)
        held = s.held[a]
        s.shift[a] = np.where(held[:, None], s.good[a], shift)
        s.on[a] = True
        return np.where(held[:, None], 0.0, velocity)

    def _hold_settle(self, a: np.ndarray, phase: np.ndarray, stood: np.ndarray,
                     walked) -> None:
        """The settling rows ``stood`` of the frame's walk ``walked`` of agents a (k,) at
        ``phase`` (k,): where a solve failed, the root is held at the last offset solved
        (those rows posed again, in place); where it converged, that offset and the
        landed ankle as posed are kept."""
        s = self._settle
        fail = stood[~walked.converged[stood] & ~s.held[a[stood]]]
        if fail.size:
            af = a[fail]
            s.held[af] = True
            s.shift[af] = s.good[af]
            self._merge(walked, fail, self._posed(af, phase[fail]))
        ok = stood[walked.converged[stood]]
        s.good[a[ok]] = s.shift[a[ok]]
        # the landed ankle kept where it was posed (a lift raised it once, not every frame)
        landing = LEG_JOINTS[np.where(self._step.stance_left[a[ok]], 1, 0)][:, 2]
        s.ankle[a[ok]] = walked.positions[ok, landing]

    def _settle_ends(self, a: np.ndarray, root: np.ndarray, before: np.ndarray,
                     dphase: np.ndarray, positions: np.ndarray) -> None:
        """Keep, for a stop of agents a (k,), their step end's root velocity and landed
        ankle: the root (k, 3) [m] and joint positions (k, J, 3) [m] at _PHASE_END, the
        root ``before`` (k, 3) [m] ``dphase`` (k,) [1] of stance phase earlier."""
        s, k = self._settle, a.size
        v = (root - before) / (2.0 * dphase * self._step.duration[a])[:, None]
        v[:, 2] = 0.0  # the root's height stays the step end's
        # at most _SETTLE_SPEED times the step's own speed (squeezed crowds' poses
        # jump: root velocities up to 12 m/s at a step's end in the bottleneck)
        cap = _SETTLE_SPEED * np.linalg.norm(
            (self._stance.target[a] - self._stance.start[a])[:, :2], axis=1
        ) / self._step.duration[a]
        speed = np.linalg.norm(v, axis=1)
        s.velocity[a] = v * np.minimum(1.0, cap / np.maximum(speed, 1e-12))[:, None]
        landing = LEG_JOINTS[np.where(self._step.stance_left[a], 1, 0)][:, 2]
        s.ankle[a] = positions[np.arange(k), landing]
        s.has[a] = True

    def _own_toe(self, a: np.ndarray) -> np.ndarray:
        """The walkers' own toe-out (k,) [rad]: the style's foot angle, else GaitStyle's."""
        if self.attributes is None:
            return np.full(a.size, self.style.toe_out)
        return self.attributes.foot_angle[a]

    def _new_stance(self, cmd: StepCommand, body: Body, had: np.ndarray, landed: _Landed):
        """The new stance foot: exactly where and how the previous swing foot landed (its
        heel is the contact point, so nothing slides at the swap), or the commanded
        foothold with default toe-out for an agent's first step; and the swing foot's
        toe-out at its start (the yaw it had as stance foot, turning to toe-out)."""
        a, first = cmd.agent, ~had
        side_sw = np.where(cmd.swing_foot == 0, 1.0, -1.0)
        own_toe = self._own_toe(a)
        toe_out = cmd.toe_out if cmd.toe_out is not None else own_toe
        yaw = np.where(first, cmd.heading - side_sw * own_toe, landed.yaw)
        along = np.stack([np.cos(yaw), np.sin(yaw)], axis=1)
        heel_xy = np.where(had[:, None], landed.heel[:, :2],
                           cmd.start[:, :2] - body.heel_offset[:, None] * along)  # fmt: skip
        stance = self._contact(body, heel_xy, cmd.start[:, 2], yaw)
        psi0 = np.where(first, cmd.heading, self._step.psi1[a])
        start_toe = np.clip(side_sw * wrap_angle(landed.old_yaw - psi0), -_MAX_TOE_START,
                            _MAX_TOE_START)
        self._stance.toe_start[a] = np.where(had, start_toe, toe_out)
        return stance, toe_out, psi0

    def _start_step(self, cmd: StepCommand, body: Body, had: np.ndarray, stance: StanceFoot,
                    toe_out: np.ndarray, psi0: np.ndarray):
        """The step's elevation-angle dataset and the per-step state: the step ElevInterp
        must produce is the one between the footholds the feet really use (the stance
        foot where it landed, the commanded target); corrections start from zero."""
        a = cmd.agent
        d = direction(stance.yaw, stance.slope)
        stance_foothold = stance.ball - body.ball_offset[:, None] * d
        rel = cmd.target - stance_foothold
        length = rel[:, 0] * np.cos(cmd.heading) + rel[:, 1] * np.sin(cmd.heading)
        # Eq. 10's pelvis term: a rotated pelvis puts the swing hip ahead at heel strike
        length = np.maximum(length - self._swing_hip_lead(a, body), _MIN_STEP)
        height = rel[:, 2]
        data = self.interp.request(body, length, height, speed=cmd.speed)
        step, st, sw = self._step, self._stance, self._swing
        cleared = self._cleared(a, body, data, height)
        # the crossfade starts from the dataset the feet were just placed by (none: this one)
        step.prev_angles[a] = np.where(had[:, None, None], step.angles[a], cleared)
        step.angles[a] = cleared
        step.stance_fraction[a] = data.stance_fraction
        step.psi0[a] = psi0
        step.psi1[a] = cmd.heading
        step.t0[a] = cmd.time
        step.rise[a] = cmd.step_height
        step.duration[a] = cmd.duration
        step.stance_left[a] = cmd.swing_foot != 0
        step.first[a] = ~had
        st.ball[a], st.yaw[a], st.slope[a] = stance.ball, stance.yaw, stance.slope
        # Spin turn (§6.1, MetaGait's): on the ball of the stance foot, once its heel is up
        st.spin[a] = 0.0 if cmd.spin is None else cmd.spin
        # (ψ before the spin is at most the hips' twist from the foot)
        step.spin_start[a] = _spin_start(body, self._stance_curves(a),
                                         cmd.heading - st.spin[a] - stance.yaw, stance.slope)
        st.toe_out[a] = toe_out
        st.start[a], st.target[a] = cmd.start, cmd.target
        sw.d0[a] = 0.0
        sw.d1[a] = 0.0
        sw.has_trail[a] = False
        sw.toe_off[a] = np.where(
            had, np.clip(2.0 * (data.stance_fraction - 0.5), 0.0, 0.45), 0.0
        )
        sw.hip_fix[a] = 0.0
        sw.hip_vel[a] = 0.0
        sw.hip_drop[a] = 0.0
        sw.toe_vel[a] = 0.0
        sw.use_bezier[a] = False
        sw.lift_need[a] = 0.0
        self._warm_start_swap(a, had)
        step.commanded[a] = True
        return data

    def _swing_hip_lead(self, a: np.ndarray, body: Body) -> np.ndarray:
        """How far (k,) [m] the swing hip is ahead of the stance hip at heel strike: the
        pelvic rotation ρ (the style's; none without) turns the hip axis, 2 (w/2) sin ρ,
        ρ the rotation at the landing (its shape's value there, ``pelvis_shapes``)."""
        if self.attributes is None:
            return np.zeros(a.size)
        at_landing = -pelvis_shapes(self.style, np.array([0.5]))[1][0]
        return body.hip_separation * np.sin(self.attributes.pelvic_rotation[a] * at_landing)

    def _swing_hip_rise(self, a: np.ndarray, body: Body) -> np.ndarray:
        """How far (k,) [m] the swing hip is above the stance hip at heel strike: the
        pelvic list there (``pelvis_shapes``; 0 for the sine list), w sin L(0.5)."""
        at = self.attributes
        amplitude = np.full(a.size, self.style.pelvic_list) if at is None else at.pelvic_list[a]
        stance_up = pelvis_shapes(self.style, np.array([0.5]))[0][0]
        return -body.hip_separation * np.sin(amplitude * stance_up)

    def _cleared(self, a: np.ndarray, body: Body, data, height: np.ndarray) -> np.ndarray:
        """The step's datasets (k, N, 4) with the swing sole lifted to
        ``GaitStyle.toe_clearance`` over level ground (``elevinterp.lift_swing_toe``; the
        swing hip drops by the pelvic list); steps up or down keep ElevInterp's dataset."""
        if not self.style.level_clearance:
            return data.angles
        level = np.abs(height) < _LEVEL_RISE
        out = data.angles.copy()
        if not level.any():
            return out
        at = self.attributes
        pelvic_list = self.style.pelvic_list if at is None else at.pelvic_list[a[level]]
        lb = body.take(np.flatnonzero(level))
        out[level] = lift_swing_toe(data.angles[level], lb, data.stance_fraction[level],
                                    hip_drop=lb.hip_separation * np.sin(pelvic_list),
                                    clearance=self.style.toe_clearance)
        return out

    def _join_root(self, a: np.ndarray, had: np.ndarray, landed: _Landed,
                   c1: np.ndarray) -> _FreeWalk | None:
        """Root continuity: the stance hip starts where the previous step left the root
        and blends to the data over the first half of the step. On stair steps (``c1``)
        the join is C¹: the offset also starts with the root velocity the data lack at the
        heel strike and loses it over the same blend (docs/architecture.md, "C¹ root join
        on stair steps"). Returns the uncorrected walk of the agents ``a[had]`` at the
        step's start (:class:`_FreeWalk`), None if none had a step."""
        if not had.any():
            return None
        # one walk: the agents' starts, and the c1 agents (a subset) a little later
        ah, ac = a[had], a[c1]
        k = ah.size
        walked = self._walk(np.concatenate([ah, ac]), np.concatenate(
            [np.zeros(k), np.full(ac.size, _VEL_PHASE)]), corrected=False)
        root = walked.root_position
        self._swing.hip_fix[ah] = landed.root[had] - root[:k]
        if ac.size:
            v_data = (root[k:] - root[:k][c1[had]]) / (
                2.0 * _VEL_PHASE * self._step.duration[ac])[:, None]
            self._swing.hip_vel[ac] = landed.root_velocity[c1] - v_data
        return _FreeWalk(walked.positions[:k], walked.converged[:k])

    def _swing_ends(self, cmd: StepCommand, body: Body, had: np.ndarray,
                    angles: np.ndarray) -> np.ndarray:
        """The data-driven swing ankle at toe-off and at the landing (no swing corrections
        yet), the offsets that pin the trailing foot in push-off and land the swing foot
        on the target, and the pelvis drop where the landing is out of reach (``angles``
        the steps' datasets). Returns (m,) bool: the toe-off hand-over's cap leaves a
        jump (:meth:`_toe_off_velocity`; none without ``toe_off_c1``)."""
        a = cmd.agent
        sw = self._swing
        ends = np.concatenate([a, a])
        toe_off_phase = 0.5 * sw.toe_off[a]
        phases = np.concatenate([toe_off_phase, np.full(a.size, _PHASE_END)])
        pose = self._walk(ends, phases, corrected=True)
        m = a.size
        sw_idx = LEG_JOINTS[np.where(cmd.swing_foot == 0, 0, 1)]
        tc = sw_idx[:, 2]
        rows = np.arange(m)
        ankle0 = pose.positions[rows, tc]
        ankle1 = pose.positions[m + rows, tc]
        sub = sw_idx[:, 3]
        heel_to_ball = pose.rotations[m + rows, sub][:, :, 0]
        land_yaw = np.arctan2(heel_to_ball[:, 1], heel_to_ball[:, 0])
        land_along = np.stack([np.cos(land_yaw), np.sin(land_yaw)], axis=1)
        land_heel = cmd.target[:, :2] - body.heel_offset[:, None] * land_along
        land = self._contact(body, land_heel, cmd.target[:, 2], land_yaw)
        land_phi = sample(angles, np.zeros(m))[:, 0]
        land_pitch = np.arctan(np.tan(land_phi) * np.cos(land_yaw - cmd.heading))
        ankle_land = stance_foot_pose(body, land, land_pitch)[1]
        # Push-off: until toe-off the trailing foot (the previous stance foot) stays on
        # its ball, pitched by the data; then the ankle joins the data smoothly.
        pin = self._pinned_ankle(a, toe_off_phase, self._legs(a, toe_off_phase)[1])[0]
        sw.d0[a] = np.where(had[:, None], pin - ankle0, 0.0)
        capped = np.zeros(m, dtype=bool)
        if self.style.toe_off_c1:
            capped = self._toe_off_velocity(a, had, toe_off_phase, pin, tc)
        # Out of reach (a step down deeper than the data's): the stance leg bends and
        # lowers the pelvis toward the landing over the second half of the step.
        hip1 = pose.positions[m + rows, sw_idx[:, 0]]
        to_land = ankle_land - hip1
        reach = np.linalg.norm(to_land, axis=1)
        # the data's own landing leg, and the swing hip's rise under the pelvic list at the
        # landing (Eq. 10's pelvis term, vertical part: the planar data do not carry it)
        data_reach = (np.linalg.norm(ankle1 - hip1, axis=1)
                      + np.maximum(self._swing_hip_rise(a, body), 0.0))
        short = np.maximum(reach - np.maximum(_REACH * (body.thigh + body.shank), data_reach),
                           0.0)
        sw.hip_drop[a] = short[:, None] * to_land / np.maximum(reach, 1e-9)[:, None]
        sw.d1[a] = ankle_land - ankle1 - sw.hip_drop[a]
        return capped

    def _data_toe_off(self, aj: np.ndarray) -> np.ndarray:
        """``GaitStyle.data_toe_off``: the trailing foot of agents ``aj`` (k,) is let go
        no later than where the step's own data lift its swing sole ``_TOE_OFF_RISE``
        above where it starts the step (uncorrected walks at ``_TOE_OFF_GRID`` of the
        stance-fraction toe-off, linear between samples). Returns (k,) bool: moved."""
        if aj.size == 0:
            return np.zeros(0, dtype=bool)
        t_off = self._swing.toe_off[aj]
        g = _TOE_OFF_GRID
        idx = np.tile(aj, g.size)
        walked = self._walk(idx, 0.5 * np.repeat(g, aj.size) * np.tile(t_off, g.size),
                            corrected=False)
        height = -self._points_depth(idx, self._swing_sole(idx, walked)).reshape(g.size, -1)
        rise = height - height[0]
        over = rise > _TOE_OFF_RISE
        first = np.argmax(over, axis=0)
        k = np.arange(aj.size)
        lo = np.maximum(first - 1, 0)
        r0, r1 = rise[lo, k], rise[first, k]
        frac = np.clip((_TOE_OFF_RISE - r0) / np.maximum(r1 - r0, 1e-9), 0.0, 1.0)
        x = (lo + np.where(first > 0, frac, 0.0)) / (g.size - 1)
        moved = over.any(axis=0)
        self._swing.toe_off[aj] = np.where(moved, x * t_off, t_off)
        self.stats["data_toe_offs"] += int(moved.sum())
        return moved

    def _toe_off_velocity(self, a: np.ndarray, had: np.ndarray, toe_off_phase: np.ndarray,
                          pin: np.ndarray, ankle_joint: np.ndarray) -> None:
        """``GaitStyle.toe_off_c1``: the horizontal velocity (k, 3) [m/s] the swing ankle's
        offset starts with at toe-off: the pinned push-off ankle's less the data's swing
        ankle's there (one-sided differences over ``_TOE_OFF_DPHASE`` of stance phase;
        ``pin`` (k, 3) the pinned ankle at toe-off), less ``_TOE_OFF_KEEP`` of it and at
        most what the hand-over carries within ``_TOE_OFF_ACCEL``. Returns (m,) bool: that
        cap leaves more than ``_TOE_OFF_KEEP`` of the jump."""
        capped = np.zeros(a.size, dtype=bool)
        j = np.flatnonzero(had & (self._swing.toe_off[a] > 0.0))
        if j.size == 0:
            return capped
        aj, p = a[j], toe_off_phase[j]
        dt = 2.0 * _TOE_OFF_DPHASE * self._step.duration[aj]
        after = self._walk(aj, p + _TOE_OFF_DPHASE, corrected=True)
        # (the corrected pose starts from the pinned ankle: ankle0 + d0)
        v_data = (after.positions[np.arange(j.size), ankle_joint[j]] - pin[j]) / dt[:, None]
        before = p - _TOE_OFF_DPHASE
        pin_before = self._pinned_ankle(aj, before, self._legs(aj, before)[1])[0]
        v_pin = (pin[j] - pin_before) / dt[:, None]
        dv = v_pin - v_data
        dv[:, 2] = 0.0  # horizontal: the data's faster rise is the swing's clearance
        size = np.maximum(np.linalg.norm(dv, axis=1), 1e-9)
        # the part of the jump above _TOE_OFF_KEEP, and only what the hand-over can carry
        # within the acceleration it may add (on short swings the whole difference would
        # add more than the jump it removes)
        beta = _TOE_OFF_BLEND * (1.0 - self._swing.toe_off[aj]) * self._step.duration[aj]
        cap = _TOE_OFF_ACCEL * beta / _TOE_OFF_PEAK
        carry = np.minimum(np.maximum(size - _TOE_OFF_KEEP, 0.0), cap)
        self._swing.toe_vel[aj] = dv * (carry / size)[:, None]
        capped[j] = size - _TOE_OFF_KEEP > cap
        return capped

    def _uneven(self, cmd: StepCommand, body: Body, swing_from: np.ndarray) -> np.ndarray:
        """(m,) bool: steps over uneven ground — something above the line from the
        trailing foot ``swing_from`` (m, 3) to the stance foothold, or from there to the
        target (the swing starts two placements back), along the ankles or the toes."""
        m = cmd.agent.size
        toes = (body.toe_offset[:, None]
                * np.stack([np.cos(cmd.heading), np.sin(cmd.heading)], axis=1))
        both = self._bumpy(np.concatenate([swing_from, cmd.start]),
                           np.concatenate([cmd.start, cmd.target]), np.tile(toes, (2, 1)))
        return both[:m] | both[m:]

    def _swing_curve(self, cmd: StepCommand, bumpy: np.ndarray) -> None:
        """Swing clearance: would the corrected data-driven foot touch the ground? Steps
        over uneven ground with a planner's Bezier are sampled from toe-off to just before
        the landing; where the sole comes within ``_CLEARANCE`` the ankle follows the
        Bezier."""
        if cmd.swing_bezier is None:
            return
        a, sw = cmd.agent, self._swing
        has = np.all(np.isfinite(cmd.swing_bezier), axis=(1, 2))
        sw.bezier[a[has]] = cmd.swing_bezier[has]
        has &= bumpy
        if not has.any() or self.style.lift_swing:
            return  # lift_swing: the data's swing, raised by _anticipate_lift
        ab = a[has]
        k = ab.size
        idx = np.tile(ab, _CHECK_SPAN.size)
        t_off = np.tile(sw.toe_off[ab], _CHECK_SPAN.size)
        ph = 0.5 * (t_off + np.repeat(_CHECK_SPAN, k) * (0.95 - t_off))
        check = self._walk(idx, ph, corrected=True)
        pts = foot_points(self.body.take(idx), check.positions, check.rotations)
        side = np.where(self._step.stance_left[idx], 1, 0)
        feet = pts[np.arange(idx.size), side]  # (p, 3, 3) heel, ball, toe tip
        sole = np.concatenate([feet, 0.5 * (feet[:, :2] + feet[:, 1:])], axis=1)
        gap = sole[:, :, 2] - self._ground_at(idx, sole)
        clearance = gap.min(axis=1).reshape(_CHECK_SPAN.size, k).min(axis=0)
        sw.use_bezier[ab] = clearance < _CLEARANCE
        self.stats["bezier_steps"] += int(sw.use_bezier[ab].sum())

    def _anticipate_lift(self, ab: np.ndarray) -> None:
        """Anticipated clearance of the agents ``ab`` stepping over uneven ground: where
        the final swing (data, blends, Bezier) would still put the sole below the ground,
        the ankle is raised by a smooth envelope over the step's phase
        (``_lift_envelope``) that starts before the contact and ends after it — a toe
        reaching a riser face is otherwise lifted only once inside it, a jump of the
        whole depth between two frames."""
        k = ab.size
        idx = np.tile(ab, _LIFT_GRID.size)
        ph = np.minimum(0.5 * np.repeat(_LIFT_GRID, k), _PHASE_END)
        check = self._walk(idx, ph, corrected=True)
        sole = self._swing_sole(idx, check).reshape(_LIFT_GRID.size, k, -1, 3)
        # between two samples the sole moves about linearly: its depth there too
        # (a toe crossing a riser face between two samples), sub-sampled
        w = _LIFT_SUB[:, None, None, None, None]
        between = (1.0 - w) * sole[None, :-1] + w * sole[None, 1:]  # (u, g-1, k, q, 3)
        u, gm = between.shape[:2]
        pts = np.concatenate([sole.reshape(-1, *sole.shape[2:]),
                              between.reshape(-1, *sole.shape[2:])])
        depth = self._points_depth(np.tile(ab, _LIFT_GRID.size + u * gm), pts)
        at = depth[:_LIFT_GRID.size * k].reshape(_LIFT_GRID.size, k)
        mid = depth[_LIFT_GRID.size * k:].reshape(u, gm, k).max(axis=0)  # (g-1, k)
        # a sample lifts for itself and for the intervals on either side of it
        at[:-1] = np.maximum(at[:-1], mid)
        at[1:] = np.maximum(at[1:], mid)
        # lift_swing: the sole clears the ground by toe_clearance where it would touch
        margin = self.style.toe_clearance if self.style.lift_swing else _LIFT_MARGIN
        need = np.where(at > -margin + _LIFT_MARGIN, at + margin, 0.0).T
        self._swing.lift_need[ab] = need
        self.stats["lift_steps"] += int((need > 0).any(axis=1).sum())

    def pose(self, t: float, agents: np.ndarray | None = None) -> PoseFrame:
        """Poses of ``agents`` (default: all) at time ``t`` [s], one vectorised call."""
        n = len(self.body)
        a = np.arange(n) if agents is None else np.atleast_1d(np.asarray(agents))
        if a.ndim != 1 or not np.issubdtype(a.dtype, np.integer):
            raise invalid("Animator", "agents", "an (k,) integer array", a.dtype)
        if np.any((a < 0) | (a >= n)):
            raise invalid("Animator", "agents", f"indices in [0, {n})", a[(a < 0) | (a >= n)])
        if not np.all(self._step.commanded[a]):
            missing = a[~self._step.commanded[a]][:5]
            raise invalid("Animator", "agents", "agents that received a StepCommand", missing)
        if not np.isfinite(t):
            raise invalid("Animator", "t", "finite [s]", t)
        phase = np.clip(0.5 * (t - self._step.t0[a]) / self._step.duration[a], 0.0, _PHASE_END)
        over = t - self._step.t0[a] - self._step.duration[a]
        stood = ends = np.zeros(0, int)
        if self.style.stop_settle:
            stood = np.flatnonzero(over > 0.0)
            # steps that end before the walker's next frame (one frame interval on): their
            # ends measured in this frame's walk, for a stop (no walk of their own then)
            s = self._settle
            gap = t - s.seen[a]
            ends = np.flatnonzero((over <= 0.0) & np.isfinite(gap) & (over + gap > 0.0)
                                  & ~s.has[a])
            s.seen[a] = t
        try:
            if stood.size:  # stopped walkers settle (GaitStyle.stop_settle)
                self._settling(a[stood], over[stood])
            walked = self._posed(a, phase, ends)
            if stood.size:  # a settle whose solve fails holds the root where it last solved
                self._hold_settle(a, phase, stood, walked)
        finally:
            self._settle.on[:] = False
        ok = walked.converged
        warm = self._warm
        warm.ankle[a] = np.where(ok[:, None], walked.warm.ankle, warm.ankle[a])
        warm.hip[a] = np.where(ok[:, None], walked.warm.hip, warm.hip[a])
        warm.ankle_jacobian[a] = np.where(ok[:, None, None], walked.warm.ankle_jacobian, np.nan)
        warm.hip_jacobian[a] = np.where(ok[:, None, None], walked.warm.hip_jacobian, np.nan)
        keep = ~ok & self._last.has[a]
        if keep.any():
            root = np.where(keep[:, None], self._last.root[a], walked.root_position)
            rot = np.where(keep[:, None, None], self._last.rotation[a], walked.root_rotation)
            local = np.where(keep[:, None, None, None], self._last.local[a], walked.local)
            positions = np.where(keep[:, None, None], self._last.positions[a],
                                 walked.positions)  # fmt: skip
            contact = np.where(keep[:, None], self._last.contact[a], walked.contact)
        else:  # the walker's own arrays (fresh per call, not kept elsewhere)
            root, rot, local = walked.root_position, walked.root_rotation, walked.local
            positions, contact = walked.positions, walked.contact
        # converged rows are finite (the walker checks), kept rows were guarded before:
        # only rows that did not converge can be non-finite
        bad = np.zeros(a.size, bool)
        if not ok.all():
            bad = ~(np.isfinite(positions).all(axis=(1, 2))
                    & np.isfinite(local).all(axis=(1, 2, 3)))  # fmt: skip
        if bad.any():  # never reached in tests; a last guard so no NaN leaves the Animator
            root[bad], rot[bad], local[bad], positions[bad] = self._standing(a[bad])
            contact[bad] = True
        self._last.root[a], self._last.rotation[a], self._last.local[a] = root, rot, local
        self._last.positions[a], self._last.contact[a] = positions, contact
        self._last.has[a] = True
        fallback = ~ok
        self.stats["poses"] += a.size
        self.stats["fallbacks"] += int(fallback.sum())
        local = local.copy()
        local[:, 0] = rot
        quats = matrix_to_quaternion(local)
        return PoseFrame(
            agents=a,
            time=float(t),
            root_position=root,
            root_quaternion=quats[:, 0].copy(),
            joints=quats,
            positions=positions,
            contact=contact,
            fallback=fallback,
            stance_left=self._step.stance_left[a].copy(),
        )

    def _posed(self, a: np.ndarray, phase: np.ndarray, ends: np.ndarray | None = None):
        """The corrected walk of agents a (k,) at stance phases (k,), the trailing
        foot's yaw fixed and a swing sole below the ground lifted (:meth:`pose`). The
        step ends of the rows ``ends`` (m,) of a are measured in the same first walk
        (:meth:`_settle_ends`)."""
        if ends is None or ends.size == 0:
            inputs = self._walk_inputs(a, phase, corrected=True)
            walked = self._walk_from(inputs)
        else:
            # the root's velocity from this frame's to the end's, or over _VEL_PHASE
            # where this frame is nearer the end than a quarter of that
            k, m = a.size, ends.size
            dphase = _PHASE_END - phase[ends]
            j = np.flatnonzero(dphase < 0.25 * _VEL_PHASE)
            near = ends[j]
            # the re-walks take rows < k of these arguments (the frame's own)
            inputs = self._walk_inputs(np.concatenate([a, a[ends], a[near]]), np.concatenate(
                [phase, np.full(m, _PHASE_END), np.full(near.size, _PHASE_END - _VEL_PHASE)]),
                corrected=True)
            both = self._walk_from(inputs)
            before = both.root_position[ends]
            before[j] = both.root_position[k + m:]
            dphase[j] = _VEL_PHASE
            self._settle_ends(a[ends], both.root_position[k:k + m], before, dphase,
                              both.positions[k:k + m])
            walked = _first_rows(both, k)
        toe_fix = np.zeros(a.size)
        for _ in range(_YAW_ROUNDS):
            more = self._swing_yaw_fix(a, phase, walked)
            fix = np.flatnonzero(np.abs(more) > np.radians(0.5))
            if fix.size == 0:
                break
            toe_fix[fix] += more[fix]
            self._merge(walked, fix, self._rewalk(a[fix], phase[fix], inputs, fix,
                                                  toe_fix=toe_fix[fix],
                                                  stance=walked.stance.take(fix)))
            self.stats["yaw_fixes"] += fix.size
        pin_fix = None
        if self.style.pin_ball:
            pin_fix = self._pin_ball(a, phase, walked, toe_fix, inputs)
        walked, lifted = self._lift_swing_foot(a, phase, walked, toe_fix, pin_fix, inputs)
        self.stats["lifted"] += int(lifted)
        return walked

    def followed_angles(self, t: float, agents: np.ndarray):
        """The elevation angles the walker follows at time ``t`` [s] for ``agents`` (k,):
        stance leg (k, 4) and swing leg (k, 4) [rad], stance side (k,) bool (True = left)
        and the stance phase (k,) [1] — for diagnostics and validation."""
        a = np.atleast_1d(np.asarray(agents))
        step = self._step
        phase = np.clip(0.5 * (t - step.t0[a]) / step.duration[a], 0.0, _PHASE_END)
        return (*self._legs(a, phase), step.stance_left[a].copy(), phase)

    # -- internals --------------------------------------------------------------------
    def _legs(self, a: np.ndarray, phase: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The elevation angles agents a (k,) follow at stance phases (k,): stance leg at
        t and swing leg at t + 0.5, (k, 4) each [rad]. With ``GaitStyle.step_crossfade``
        the step's dataset is faded in over the step (smoothstep in τ) from the previous
        step's: at the heel strike that opens the step the legs are where the previous
        dataset left them (its Eq. 10 step is the one the feet span), at the one that
        ends it they follow the step's own dataset (whose Eq. 10 step is this one)."""
        return ak.crossfade_legs(self._step.angles, self._step.prev_angles, _rows(a),
                                 _floats(phase), bool(self.style.step_crossfade))

    def _stance_curves(self, a: np.ndarray) -> np.ndarray:
        """(k, S, 4) [rad]: the step's dataset as the stance leg of agents a follows it
        over t ∈ [0, 0.5] (the crossfade of :meth:`_legs` at τ = 2t; rows past 0.5 are
        the step's own dataset) — for the stance-only measures (:func:`_spin_start`)."""
        new = self._step.angles[a]
        if not self.style.step_crossfade:
            return new
        before = self._step.prev_angles[a]
        grid = np.arange(new.shape[1]) / new.shape[1]
        w = smoothstep(2.0 * grid)[None, :, None]
        return before + w * (new - before)

    def _spin_progress(self, a: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """How much of its spin turn (k,) [0, 1] the stance foot of agents a has made at
        step phases tau (k,): none until the heel is up, all by the step's end."""
        t0 = self._step.spin_start[a]
        return smoothstep((tau - t0) / np.maximum(1.0 - t0, 1e-9))

    def _heading(self, a: np.ndarray, phase: np.ndarray) -> np.ndarray:
        """ψ (k,) [rad] at stance phases (k,): from the previous heading to the commanded
        one over the step (§4.4); the part a spin turn makes turns with the spin."""
        step = self._step
        return ak.headings(step.psi0, step.psi1, self._stance.spin, step.spin_start, _rows(a),
                           _floats(phase))

    def _contact(self, body: Body, heel_xy: np.ndarray, z: np.ndarray, yaw: np.ndarray):
        """How a foot with its heel at ``heel_xy`` (m, 2) [m] and ``yaw`` (m,) [rad] rests
        on the ground (:class:`StanceFoot`).

        The sole line from the heel is pitched just enough that no point along the foot
        (heel to toe tip, sampled) is below the ground: on a plane it takes the plane's
        slope, against a curb it tilts up onto the edge, with the toes over a drop it stays
        level on the edge. A heel over a drop (a nosing behind it) stays in the air with
        the front of the foot on the tread. Without ``ground`` the foot is flat at ``z``.
        """
        m = len(body)
        along = np.stack([np.cos(yaw), np.sin(yaw)], axis=1)
        hb = body.heel_offset + body.ball_offset
        ht = body.heel_offset + body.toe_offset
        ball_xy = heel_xy + hb[:, None] * along
        if self.ground is None:
            return StanceFoot(np.column_stack([ball_xy, z]), yaw, np.zeros(m))
        frac = np.linspace(0.0, 1.0, _SOLE_SAMPLES)  # heel → toe tip
        dist = ht[:, None] * frac[None, :]  # (m, q)
        pts = heel_xy[:, None, :] + dist[..., None] * along[:, None, :]
        zs = np.asarray(self.ground(pts.reshape(-1, 2)), dtype=float).reshape(m, -1)
        zh = zs[:, 0]
        slope = np.max(np.arctan2(zs[:, 1:] - zh[:, None], dist[:, 1:]), axis=1)
        # heel over a drop: the front of the foot (ball onward) is higher than the heel
        beyond = dist >= hb[:, None] - 1e-9
        z_front = np.where(beyond, zs, np.inf).min(axis=1)
        zb = np.asarray(self.ground(ball_xy), dtype=float)
        rel = np.where(beyond & (dist > hb[:, None] + 1e-9),
                       np.arctan2(zs - zb[:, None], np.maximum(dist - hb[:, None], 1e-9)),
                       -np.inf)  # fmt: skip
        front = np.maximum(rel.max(axis=1), 0.0)
        heel_drop = (zh < z_front - 0.01) & (front < slope)
        slope = np.where(heel_drop, front, slope)
        d = direction(yaw, slope)
        ball = np.where(heel_drop[:, None], np.column_stack([ball_xy, zb]),
                        np.column_stack([heel_xy, zh]) + hb[:, None] * d)  # fmt: skip
        return StanceFoot(ball, yaw, slope)

    def _bumpy(self, start: np.ndarray, target: np.ndarray,
               reach: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
        """(m,) bool: the ground between two footholds (m, 3) rises more than 1 cm above
        the straight line joining them (a step, a block, a nosing in between); with
        ``reach`` (m, 2) [m] also along that line shifted by each row's xy offsets (where
        the toes and heel pass: a sideways step beside a riser)."""
        if self.ground is None:
            return np.abs(target[:, 2] - start[:, 2]) > 0.01
        s = np.linspace(0.0, 1.0, 16)
        line = start[:, None, :] + s[None, :, None] * (target - start)[:, None, :]
        if reach is not None:
            line = np.concatenate([line, line + np.pad(reach, ((0, 0), (0, 1)))[:, None],
                                   line - np.pad(reach, ((0, 0), (0, 1)))[:, None]], axis=1)
        z = np.asarray(self.ground(line[..., :2].reshape(-1, 2)), dtype=float)
        return (z.reshape(line.shape[:2]) - line[..., 2]).max(axis=1) > 0.01

    def _ground_at(self, a: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Ground height [m] below points (p, q, 3) of agents a (p,)."""
        p, q = points.shape[:2]
        xy = points[:, :, :2].reshape(-1, 2)
        if self.ground is not None:
            return np.asarray(self.ground(xy), dtype=float).reshape(p, q)
        start, target = self._stance.start[a], self._stance.target[a]
        d = target[:, :2] - start[:, :2]
        dd = np.maximum(np.einsum("ka,ka->k", d, d), 1e-12)
        s = np.einsum("kqa,ka->kq", points[:, :, :2] - start[:, None, :2], d) / dd[:, None]
        s = np.clip(s, 0.0, 1.0)
        return start[:, None, 2] + s * (target[:, 2] - start[:, 2])[:, None]

    def _warm_start_swap(self, a: np.ndarray, had: np.ndarray) -> None:
        """Warm starts after the legs swap roles: the new swing hip starts from the old
        stance hip's angles (YXZ Euler); the new stance ankle from zero subtalar."""
        from scipy.spatial.transform import Rotation

        self._warm.ankle[a] = 0.0
        self._warm.hip[a] = 0.0
        self._warm.ankle_jacobian[a] = np.nan
        self._warm.hip_jacobian[a] = np.nan
        ok = had & self._last.has[a]
        if not ok.any():
            return
        ah = a[ok]
        new_swing_left = ~self._step.stance_left[ah]
        hip = np.where(new_swing_left, LEG_JOINTS[0, 0], LEG_JOINTS[1, 0])
        local_hip = self._last.local[ah, hip]
        self._warm.hip[ah] = Rotation.from_matrix(local_hip).as_euler("YXZ")

    def _swing_toe(self, a: np.ndarray, tau: np.ndarray, psi: np.ndarray) -> np.ndarray:
        """The swing foot's toe-out (k,) [rad] of agents a at step phases tau, heading psi:
        the trailing foot keeps its world yaw while pinned in push-off (its toe-out
        follows ψ), then turns to the commanded toe-out over the swing."""
        sw = self._swing
        return ak.swing_toes(self._stance.toe_out, sw.toe_off, self._step.stance_left,
                             sw.trail_yaw, sw.has_trail, self._stance.toe_start, _rows(a),
                             _floats(tau), _floats(psi), _MAX_TOE_START)

    def _swing_yaw_fix(self, a: np.ndarray, phase: np.ndarray, walked) -> np.ndarray:
        """Toe-out corrections (k,) [rad] that turn the trailing foot of agents a, pinned
        in push-off, to the yaw :meth:`_swing_toe` asks for (the swing leg's IK toward the
        pinned ankle and the skew talocrural axis turn it: by 20° in push-off after a 15°
        turn)."""
        rows = np.arange(a.size)
        sw = LEG_JOINTS[np.where(self._step.stance_left[a], 1, 0)]
        along = walked.rotations[rows, sw[:, 3]][:, :, 0]
        psi = self._heading(a, phase)
        side_sw = np.where(self._step.stance_left[a], -1.0, 1.0)
        want = psi + side_sw * self._swing_toe(a, 2.0 * phase, psi)
        err = wrap_angle(np.arctan2(along[:, 1], along[:, 0]) - want)
        # a steep foot's yaw is ill-conditioned: the correction fades out beyond 45° pitch;
        # it is for the trailing foot on the ground, and fades out over the early swing
        err *= np.clip((np.hypot(along[:, 0], along[:, 1]) - 0.5) / 0.2, 0.0, 1.0)
        t_off = self._swing.toe_off[a]
        err *= self._swing.has_trail[a] * (1.0 - smoothstep((2.0 * phase - t_off) / 0.4))
        return -side_sw * err

    @staticmethod
    def _merge(walked, rows: np.ndarray, again) -> None:
        """Put the re-solved poses ``again`` of ``rows`` into ``walked`` (in place; the
        walker's arrays are fresh per call)."""
        for name in ("root_position", "root_rotation", "local", "positions", "rotations",
                     "contact", "converged", "solves"):  # fmt: skip
            getattr(walked, name)[rows] = getattr(again, name)
        for name in ("ankle", "hip", "ankle_jacobian", "hip_jacobian"):
            getattr(walked.warm, name)[rows] = getattr(again.warm, name)

    def _walk(self, a: np.ndarray, phase: np.ndarray, corrected: bool,
              lift: np.ndarray | None = None, toe_fix: np.ndarray | None = None,
              pin_fix: np.ndarray | None = None, stance: StanceHalf | None = None):  # fmt: skip
        """ElevWalker for agents a (k,) at stance phases (k,), with the step corrections
        (and an extra vertical ``lift`` (k,) [m] of the swing ankle goal, a correction
        ``toe_fix`` (k,) [rad] of the swing foot's toe-out, a correction ``pin_fix`` (k, 3)
        [m] of the pinned push-off ankle's goal). ``stance``: the stance half of a walk of
        the same agents at the same phases within this frame (the warm starts are stored
        after the frame's last walk, and the lift, toe and pin fixes change only the
        swing's inputs), taken instead of solved again: the same values."""
        return self._walk_from(self._walk_inputs(a, phase, corrected), lift, toe_fix,
                               pin_fix, stance)

    def _walk_inputs(self, a: np.ndarray, phase: np.ndarray, corrected: bool) -> _WalkInputs:
        """:meth:`_walk`'s ElevWalker arguments for agents a (k,) at stance phases (k,),
        before the lift, toe and pin fixes (:class:`_WalkInputs`)."""
        body = self.body.take(a)
        st, sw = self._legs(a, phase)  # stance leg at t, swing leg at t + 0.5
        psi = self._heading(a, phase)
        tau = 2.0 * phase
        spin = self._stance.spin[a] * self._spin_progress(a, tau)
        foot = StanceFoot(self._stance.ball[a], self._stance.yaw[a] + spin, self._stance.slope[a])
        spinning = np.flatnonzero(spin != 0.0)
        if spinning.size and self.ground is not None:
            # The heel swings round the ball; where it would enter higher ground (a curb)
            # the foot spins on its raised forefoot instead.
            sub = StanceFoot(foot.ball[spinning], foot.yaw[spinning], foot.slope[spinning])
            b = body.take(spinning)
            heel = sub.heel(b)
            g = np.asarray(self.ground(heel[:, :2]), dtype=float)
            hb = b.heel_offset + b.ball_offset
            p_max = np.arcsin(np.clip((sub.ball[:, 2] - g) / hb, -1.0, 1.0))
            slope = foot.slope.copy()
            slope[spinning] = np.minimum(sub.slope, p_max)
            foot = StanceFoot(foot.ball, foot.yaw, slope)
        offset = target = blend = goal = toes = hip_fix = pinned = envelope = None
        if corrected:
            # ak.corrections: the swing offset blended from toe-off to the landing, with
            # toe_off_c1 its C¹ hand-over T β h(u), u = (τ − toe-off) / β (starts with the
            # velocity the data lack, gone at rest after β of the step); the Bezier's
            # blend; the push-off pin (toes rigid after toe-off); the stance hip's offset,
            # blended out over half the step, or the whole step after a clamped one (its
            # landing pulled onto the target by IK), with the C¹ term T b x (1 - x)²
            # (x = τ / b: the velocity jump as d/dt at t0) and the drop toward the landing
            sw_, rows, tau_ = self._swing, _rows(a), _floats(tau)
            u = ak.toe_off_progress(rows, tau_, sw_.toe_off, _TOE_OFF_BLEND)
            offset, blend, pinned, toes, hip_fix = ak.corrections(
                rows, tau_, sw_.toe_off, sw_.d0, sw_.d1, sw_.toe_vel, self._step.duration,
                sw_.use_bezier, sw_.has_trail, sw_.join_long, sw_.join_whole, sw_.hip_fix,
                sw_.hip_vel, sw_.hip_drop, bool(self.style.toe_off_c1), _toe_off_shape(u),
                _TOE_OFF_BLEND, _BEZIER_IN, _BEZIER_OUT, _HIP_BLEND, _HIP_BLEND_CLAMPED)
            target = _bezier(self._swing.bezier[a], tau)
            goal = np.full((a.size, 3), np.nan)
            if pinned.any():
                goal[pinned], toes[pinned] = self._pinned_ankle(a[pinned], phase[pinned],
                                                                sw[pinned])  # fmt: skip
            settling = np.flatnonzero(self._settle.on[a])
            if settling.size:  # a stopped walker's root carried on, the landed foot kept
                hip_fix[settling] += self._settle.shift[a[settling]]
                goal[settling] = self._settle.ankle[a[settling]]
                pinned[settling] = False  # (its goal takes no pin fix in _walk_from)
            envelope = self._lift_envelope(a, tau)
        if corrected:
            trailing = np.flatnonzero(self._swing.trail_root[a] & (tau < self._swing.toe_off[a]))
            if trailing.size:
                hip_fix[trailing] += self._trailing_solved(a[trailing], phase[trailing])
        warm = WarmStart(self._warm.ankle[a], self._warm.hip[a], self._warm.ankle_jacobian[a],
                         self._warm.hip_jacobian[a])  # fmt: skip
        # a walk starts from standing: the pelvis is level and lists in over the first step
        list_scale = np.where(self._step.first[a], smoothstep(tau), 1.0)
        return _WalkInputs(
            body, self._step.stance_left[a], phase, st, sw, psi, foot,
            self._swing_toe(a, tau, psi), warm, self._step.stance_fraction[a], offset, target,
            blend, goal, toes, hip_fix, pinned, envelope,
            None if self.attributes is None else self.attributes.take(a), list_scale)

    def _walk_from(self, w: _WalkInputs, lift: np.ndarray | None = None,
                   toe_fix: np.ndarray | None = None, pin_fix: np.ndarray | None = None,
                   stance: StanceHalf | None = None):  # fmt: skip
        """ElevWalker on the arguments ``w`` (:meth:`_walk_inputs`) with the fixes of
        :meth:`_walk` applied (to copies: ``w`` stays as it was)."""
        offset, target, goal = w.offset, w.target, w.goal
        if offset is not None:  # corrected
            offset, target, goal = offset.copy(), target.copy(), goal.copy()
            if pin_fix is not None and w.pinned.any():
                goal[w.pinned] += pin_fix[w.pinned]
            if w.envelope is not None:
                lift = w.envelope if lift is None else lift + w.envelope
            if lift is not None:
                offset[:, 2] += lift
                target[:, 2] += lift
                goal[:, 2] += lift
        toe_out = w.toe_out if toe_fix is None else w.toe_out + toe_fix
        return elevwalker_pose(
            w.body, w.stance_left, w.phase, w.st, w.sw, w.psi, w.foot, toe_out, w.warm,
            self.style, w.stance_fraction, swing_offset=offset, swing_target=target,
            swing_blend=w.blend, stance_hip_offset=w.hip_fix, swing_goal=goal,
            swing_toe_angle=w.toes, attributes=w.attributes, list_scale=w.list_scale,
            stance=stance,
        )  # fmt: skip

    def _rewalk(self, a: np.ndarray, phase: np.ndarray, inputs: _WalkInputs | None,
                rows: np.ndarray, lift: np.ndarray | None = None,
                toe_fix: np.ndarray | None = None, pin_fix: np.ndarray | None = None,
                stance: StanceHalf | None = None):  # fmt: skip
        """A corrected re-walk of agents a (k,) at stance phases (k,) in the frame being
        posed with the fixes of :meth:`_walk`: the rows ``rows`` (k,) of the frame's walk
        arguments ``inputs`` taken (the same values), or all found again without them."""
        if inputs is None:
            return self._walk(a, phase, corrected=True, lift=lift, toe_fix=toe_fix,
                              pin_fix=pin_fix, stance=stance)
        return self._walk_from(inputs.take(rows), lift, toe_fix, pin_fix, stance)

    def _trailing_solved(self, a: np.ndarray, phase: np.ndarray,
                         free: _FreeWalk | None = None) -> np.ndarray:
        """Root offset (k, 3) [m] along ψ of agents a at stance phases (k,) in the double
        support that opens a step (``GaitStyle.trailing_root``): (1 − w) times how far
        ahead of the new stance leg's root the trailing leg, pinned on its ball
        (:meth:`_pinned_ankle`) and following its data (the swing leg at t + 0.5), puts
        it; w a smoothstep from 0 at the heel strike to 1 at toe-off. At the heel strike
        the root moves on as the previous step's stance leg moved it. ``free``: that free
        walk of the agents at these phases in this state, taken instead of solved again."""
        k = a.size
        st, sw = self._legs(a, phase)
        psi = self._heading(a, phase)
        tau = 2.0 * phase
        if free is None:
            body = self.body.take(a)
            foot = StanceFoot(self._stance.ball[a], self._stance.yaw[a], self._stance.slope[a])
            warm = WarmStart(self._warm.ankle[a], self._warm.hip[a],
                             self._warm.ankle_jacobian[a], self._warm.hip_jacobian[a])
            free = elevwalker_pose(
                body, self._step.stance_left[a], phase, st, sw, psi, foot,
                self._swing_toe(a, tau, psi), warm, self.style, self._step.stance_fraction[a],
                attributes=None if self.attributes is None else self.attributes.take(a),
                list_scale=np.where(self._step.first[a], smoothstep(tau), 1.0),
            )  # fmt: skip
        swing_ankle = free.positions[np.arange(k), LEG_JOINTS[np.where(
            self._step.stance_left[a], 1, 0)][:, 2]]
        gap = self._pinned_ankle(a, phase, sw)[0] - swing_ankle
        fwd = np.stack([np.cos(psi), np.sin(psi), np.zeros(k)], axis=1)
        w = smoothstep(tau / np.maximum(self._swing.toe_off[a], 1e-9))
        ahead = (1.0 - w) * np.sum(gap * fwd, axis=1)
        # along the circle about the stance ankle: the stance leg pivots, its knee stays
        st_leg = LEG_JOINTS[np.where(self._step.stance_left[a], 0, 1)]
        rows = np.arange(k)
        leg = free.positions[rows, st_leg[:, 0]] - free.positions[rows, st_leg[:, 2]]
        rise = -np.sum(leg * fwd, axis=1) / np.maximum(leg[:, 2], 1e-3)
        shift = ahead[:, None] * (fwd + rise[:, None] * np.array([0.0, 0.0, 1.0]))
        return np.where(free.converged[:, None], shift, 0.0)

    def _lift_envelope(self, a: np.ndarray, tau: np.ndarray) -> np.ndarray | None:
        """Anticipated swing-ankle lift (k,) [m] of agents a at step phases tau (k,): the
        upper envelope of the lifts needed at the ``_LIFT_GRID`` samples, each spread over
        ±``_LIFT_WIDTH`` of the step by a smooth bump (1 at its sample, C¹ zero at the
        ends); None when no agent needs one."""
        need = self._swing.lift_need[a]
        rows = np.flatnonzero(need.any(axis=1))
        if rows.size == 0:
            return None
        x = np.abs(tau[rows, None] - _LIFT_GRID[None, :]) / _LIFT_WIDTH
        bump = 1.0 - smoothstep(x)
        # zero at the step's ends: the trailing foot leaves, and the landing foot
        # arrives, where the stance feet are (the per-frame pass covers what remains)
        t = tau[rows]
        ends = smoothstep(t / _LIFT_WIDTH) * smoothstep((1.0 - t) / _LIFT_LAND)
        out = np.zeros(a.size)
        out[rows] = (need[rows] * bump).max(axis=1) * ends
        return out

    def _pinned_ankle(self, a: np.ndarray, phase: np.ndarray, swing_angles: np.ndarray):
        """Ankle (k, 3) [m] and toe angle (k,) [rad] of the trailing foot in push-off
        (:meth:`_pinned_foot`)."""
        return self._pinned_foot(a, phase, swing_angles)[:2]

    def _pin_ball(self, a: np.ndarray, phase: np.ndarray, walked, toe_fix: np.ndarray,
                  inputs: _WalkInputs | None = None) -> np.ndarray | None:
        """``GaitStyle.pin_ball``: corrections (k, 3) [m] of the pinned push-off ankle's goal
        that put the trailing foot's ball horizontally where the pin put it (None: none
        needed), the walk ``walked`` re-solved with them (in place). The swing talocrural
        turns the foot about a skew axis and the subtalar stays neutral, so a foot pitched
        while yawed away from ψ (a turn) rolls and its ball moves sideways off the pinned
        ankle (up to 19 mm at the corner); each round moves the goal by the ball's error.
        ``inputs``: ``walked``'s :class:`_WalkInputs`, whose rows the re-walks take."""
        tau = 2.0 * phase
        pinned = np.flatnonzero(self._swing.has_trail[a] & (tau < self._swing.toe_off[a]))
        if pinned.size == 0:
            return None
        ap = a[pinned]
        want = self._pinned_foot(ap, phase[pinned], self._legs(ap, phase[pinned])[1])[2]
        ball_joint = LEG_JOINTS[np.where(self._step.stance_left[ap], 1, 0), 4]
        # horizontal: over a riser the lift raises the pin on purpose
        first = walked.positions[pinned, ball_joint] - want
        first[:, 2] = 0.0
        # all of it until half-way to toe-off, none at toe-off (the swing's offset starts
        # from the uncorrected pin): the ball is up on the straightening toes by then
        x = tau[pinned] / np.maximum(self._swing.toe_off[ap], 1e-9)
        want = want + smoothstep(2.0 * x - 1.0)[:, None] * first
        fix = np.zeros((a.size, 3))
        for _ in range(_PIN_ROUNDS):
            err = walked.positions[pinned, ball_joint] - want
            err[:, 2] = 0.0
            off = np.linalg.norm(err, axis=1) > _PIN_TOLERANCE
            if not off.any():
                break
            rows = pinned[off]
            fix[rows] -= err[off]
            self._merge(walked, rows, self._rewalk(
                a[rows], phase[rows], inputs, rows, toe_fix=toe_fix[rows], pin_fix=fix[rows],
                stance=walked.stance.take(rows)))
            self.stats["pin_fixes"] += rows.size
        return fix

    def _pinned_foot(self, a: np.ndarray, phase: np.ndarray, swing_angles: np.ndarray):
        """Ankle (k, 3) [m], toe angle (k,) [rad] and ball (k, 3) [m] of the trailing foot
        in push-off.

        The foot keeps the swing data's elevation and its toe tip stays where it stood;
        the toes straighten from lying flat (at the step's start: the §4.1 stance model
        rolling on the ball, so the swap is seamless) to rigid (at toe-off: the foot model
        of ElevInterp's step measure, so the data's leg reaches it).
        """
        psi = self._heading(a, phase)
        b, sw = self.body, self._swing
        # numpy's tan and arctan (not glibc's here), the rest compiled
        pitch = np.arctan(np.tan(swing_angles[:, 0]) * np.cos(sw.trail_yaw[a] - psi))
        return ak.pinned_feet(_rows(a), _floats(phase), _floats(pitch), sw.trail_yaw,
                              sw.trail_slope, sw.trail_ball, sw.toe_off, b.toe_offset,
                              b.ball_offset, b.ankle_height)

    def _swing_sole(self, a: np.ndarray, walked) -> np.ndarray:
        """Points (k, q, 3) [m] along the swing foot's sole of agents a (k,): heel → ball
        → toe tip (the foot is a segment: at a riser edge its middle can be inside the
        step while heel, ball and toe are not)."""
        b = self.body
        joints = np.ascontiguousarray(LEG_JOINTS[np.where(self._step.stance_left[a], 1, 0)],
                                      dtype=np.intp)
        return ak.sole_points(walked.positions, walked.rotations, joints, _rows(a),
                              b.heel_offset, b.ankle_height, b.toe_offset, b.ball_offset,
                              _SOLE_HEEL_BALL, _SOLE_BALL_TOE)

    def _points_depth(self, a: np.ndarray, sole: np.ndarray) -> np.ndarray:
        """Deepest point (k,) [m] of sole points ``sole`` (k, q, 3) [m] of agents a (k,) below
        the ground (negative: clear).

        The sole is sampled (``_swing_sole``); between two neighbouring samples whose
        ground differs by more than ``_EDGE_JUMP`` (a riser or curb edge between them) the
        sole is sampled again, ``_EDGE_SUB`` (one batched ground call, for those pairs
        only): the corner a sole crossing an edge cuts, which samples alone miss by up to
        their spacing times the foot's pitch, is found to 1/24 of the spacing (2 mm).
        """
        g = self._ground_at(a, sole)
        depth = (g - sole[:, :, 2]).max(axis=1)
        jump = np.abs(np.diff(g, axis=1)) > _EDGE_JUMP
        if not jump.any():
            return depth
        r, i = np.nonzero(jump)
        p0, p1 = sole[r, i], sole[r, i + 1]
        pts = p0[:, None] + _EDGE_SUB[None, :, None] * (p1 - p0)[:, None]  # (e, u, 3)
        gap = self._ground_at(a[r], pts) - pts[:, :, 2]
        np.maximum.at(depth, r, gap.max(axis=1))
        return depth

    def _lift_swing_foot(self, a: np.ndarray, phase: np.ndarray, walked,
                         toe_fix: np.ndarray | None = None,
                         pin_fix: np.ndarray | None = None,
                         inputs: _WalkInputs | None = None):
        """Re-solve agents whose swing sole (heel to toe tip, sampled) dips below the
        ground, the ankle goal raised by the depth (IK on the swing leg); the lifted pose
        is checked again and raised further (the swing leg's IK does not translate the
        foot exactly: reach, knee plane), up to ``_LIFT_ROUNDS`` times. ``inputs``:
        ``walked``'s :class:`_WalkInputs`, whose rows the re-walks take."""
        depth = self._points_depth(a, self._swing_sole(a, walked))
        sink = np.flatnonzero(depth > 1e-4)
        if sink.size == 0:
            return walked, 0
        lifted = sink.size
        lift = np.zeros(a.size)
        for _ in range(_LIFT_ROUNDS):
            lift[sink] += depth[sink] + _LIFT_MARGIN
            again = self._rewalk(a[sink], phase[sink], inputs, sink, lift=lift[sink],
                                 toe_fix=None if toe_fix is None else toe_fix[sink],
                                 pin_fix=None if pin_fix is None else pin_fix[sink],
                                 stance=walked.stance.take(sink))
            self._merge(walked, sink, again)
            depth[sink] = self._points_depth(a[sink], self._swing_sole(a[sink], again))
            sink = sink[depth[sink] > 1e-4]
            if sink.size == 0:
                break
        return walked, lifted

    def _standing(self, a: np.ndarray):
        """A neutral standing pose above each agent's stance foothold."""
        body = self.body.take(a)
        k = a.size
        nj = len(JOINT_NAMES)
        root = self._stance.start[a] + np.stack(
            [np.zeros(k), np.zeros(k), body.hip_height], axis=1
        )
        rot = np.broadcast_to(np.eye(3), (k, 3, 3)).copy()
        local = np.broadcast_to(np.eye(3), (k, nj, 3, 3)).copy()
        from crowdwalk.body import forward_kinematics

        positions, _ = forward_kinematics(body, root, rot, local)
        return root, rot, local, positions
