"""The ``ko_badler`` gait engine: per step, the prototype walk generalised to the walker's
body and the planner's step (Ko & Badler 1992), posed as a full body.

Per walker, once: ψ_{S*}^{S} of the prototype (the walker's own walk, §4; kept instead
of the prototype, which transitivity allows). Per step (at its heel strike): φ_ρ of it to
the planner's step length, from the walker's previous step and current hip height (§2).
Per frame, at the step phase s ∈ [0, 1]:

- **stance foot** from F1/F2/M on its foothold (heel pivot until FGM, ball pivot until
  MOM, toe-tip pivot after), **hip** from H, the **stance leg** by two-link IK from the
  hip to the stance ankle (Ko & Badler's Cartesian hip and foot);
- **swing foot**: until TOM it pushes off on its own foothold (the F2/M of the step in which
  it stood, one step on); after, its ankle follows A and its angle F3 (offset at TOM to
  where the push-off left them, fading over the swing); the swing leg by two-link IK;
- **upper body** as ElevWalker (§8 of Sun & Metaxas): trunk upright along the heading,
  arms swinging with the opposite thigh.

Beyond the paper (straight level walking; docs/architecture.md, "Ko & Badler"):
footholds and times are the crowd's; the pelvis moves between the midpoints of
consecutive foothold pairs, timed by H's x; heading turns linearly over the step (as
ElevWalker §4.4); the floor under each point is the line between the footholds it moves
between (hip height follows the ground); over uneven ground (rising > 1 cm above the
foothold line) the swing ankle is lifted to the planner's Bezier swing curve where that is
higher; the pelvis is lowered where a leg would not
reach (``stats["lowered"]`` frames, by at most ``stats["lowered_max"]`` [m]).
"""

from __future__ import annotations

import numpy as np

from crowdwalk.body import (
    JOINT,
    JOINT_NAMES,
    LEG_JOINTS,
    PARENTS,
    Body,
    forward_kinematics,
    matrix_to_quaternion,
    rotation_x,
    rotation_y,
    rotation_z,
)
from crowdwalk.errors import invalid
from crowdwalk.gait.elevwalker import GaitStyle
from crowdwalk.gait.engine import PoseFrame
from crowdwalk.gait.foot import SPIN_HEEL_LIFT, column_or, two_link_knee
from crowdwalk.gait.foot import wrap_angle as _wrap
from crowdwalk.gait.ko_badler.generalize import (
    body_generalization,
    hip_height_at_heel_strike,
    step_length_generalization,
)
from crowdwalk.gait.ko_badler.walkdata import (
    SEQUENCES,
    BodyCondition,
    StepStart,
    WalkData,
    interpolation,
    load_prototype,
)

__all__ = ["KoBadlerEngine", "foot_configuration"]

_REACH = 0.999  # longest hip–ankle distance, fraction of thigh + shank
_TOE_RELAX = 0.3  # step fraction after toe-off over which the swing toes straighten
_EPS = 1e-9
_PATH = np.linspace(0.0, 1.0, 17)  # ground samples along the swing path
# Least toe clearance in mid swing [m]: Winter DA (1992), Foot trajectory in human gait,
# Phys Ther 72:45-53 (1.29 ± 0.45 cm). The prototype's rigid marker foot with straight toes
# would pass 1.2-1.5 cm below the floor in mid swing (its toe marker is 1.1 cm above the sole line).
_TOE_CLEARANCE = 0.0129
_BEZIER_RAMP = 0.25  # fraction of the swing over which the Bezier lift is eased in
_UNEVEN = 0.01  # ground this far above the foothold line: the step is over uneven ground [m]
_SPIN_GRID = np.linspace(0.3, 1.0, 15)  # step phases searched for the heel rise



def foot_configuration(body: BodyCondition, foot_angle, meta_angle):
    """Sagittal ankle (x, y) [m] and toe pitch [rad] of a foot on its footprint.

    The footprint's N is the origin. Toe-up foot angles pivot on the heel (−hN, 0);
    heel-up ones on the ball (bN, 0) while the meta angle is 0, else on the tip of the
    toes (bN + bt, 0) with the toes at the meta angle (Ko & Badler Fig. 7, Lemma 1).

    Parameters
    ----------
    body : BodyCondition
    foot_angle, meta_angle : numpy.ndarray
        (k,) [rad]: the foot (toe up +) and meta angle (ball above toe tip +).

    Returns
    -------
    ankle : (k, 2) [m]; toe_pitch : (k,) [rad], toe up + (the toes' angle from the floor).
    """
    f = np.asarray(foot_angle, dtype=float)
    m = np.asarray(meta_angle, dtype=float)
    ah, th = body.ankle_heel, body.heel_angle
    ab, tb = body.ankle_ball, body.ball_angle
    heel = np.stack([-body.heel + ah * np.cos(th + f), ah * np.sin(th + f)], axis=-1)
    ball = np.stack([body.ball + body.toes - body.toes * np.cos(m), body.toes * np.sin(m)], -1)
    ball = ball + np.stack([-ab * np.cos(tb - f), ab * np.sin(tb - f)], axis=-1)
    ankle = np.where((f > 0)[..., None], heel, ball)
    return ankle, np.where(f > 0, 0.0, -m)


def _segment_frame(direction, lateral):
    """World rotation (k, 3, 3) of a segment whose rest pose points down −z (x forward).

    ``direction`` (k, 3) proximal → distal; ``lateral`` (k, 3) the hinge axis (+y left),
    made orthogonal to it.
    """
    z = -direction / np.linalg.norm(direction, axis=-1, keepdims=True)
    y = lateral - np.sum(lateral * z, axis=-1, keepdims=True) * z
    y = y / np.linalg.norm(y, axis=-1, keepdims=True)
    return np.stack([np.cross(y, z), y, z], axis=-1)


def _t(a):
    return np.swapaxes(a, -1, -2)


class KoBadlerEngine:
    """Full-body poses of n walkers by Ko & Badler's generalised walk data.

    Parameters
    ----------
    body : Body
        The n walkers' bodies.
    ground : callable, optional
        ``ground(xy (p, 2)) -> z (p,)`` [m]: where it rises more than 1 cm above the line
        between a step's footholds the swing ankle may be lifted to the planner's Bezier.
    style : GaitStyle, optional
        Arm swing and elbow flexion of the upper body (ElevWalker's §8 parameters).
    prototype : WalkData, optional
        W̄(S*, sl*); default the shipped one (:func:`load_prototype`).
    """

    def __init__(self, body: Body, ground=None, style: GaitStyle | None = None,
                 prototype: WalkData | None = None) -> None:  # fmt: skip
        if not isinstance(body, Body):
            raise invalid("KoBadlerEngine", "body", "a crowdwalk.body.Body", type(body).__name__)
        self.body = body
        self.ground = ground
        self.style = style or GaitStyle()
        proto = prototype or load_prototype()
        self.condition = BodyCondition.from_body(body)
        self.own = body_generalization(proto, self.condition)  # ψ, once per walker
        n = len(body)
        self._values = {k: getattr(self.own, k).v.copy() for k in SEQUENCES}
        # the swing foot's push-off: F2 and M of the step in which it was the stance foot
        self._push = {k: self._values[k].copy() for k in ("foot2", "meta")}
        self._t0 = np.zeros(n)
        self._duration = np.ones(n)
        self._length = self.own.step_length.copy()
        self._before = self.own.step_length.copy()
        self._hip_end = np.asarray(hip_height_at_heel_strike(proto.law, self.condition,
                                                             self.own.step_length))  # fmt: skip
        self._stance_left = np.ones(n, bool)
        self._start = np.zeros((n, 3))
        self._target = np.zeros((n, 3))
        self._trail = np.zeros((n, 3))
        self._yaw_stance = np.zeros(n)
        self._yaw_trail = np.zeros(n)
        self._yaw_land = np.zeros(n)  # where the swing foot lands pointing [rad]
        self._yaw_end = np.zeros(n)  # where the stance foot points after its spin [rad]
        self._spin = np.zeros(n)  # the stance foot's spin turn on its ball [rad]
        self._spin_start = np.ones(n)  # step phase s at which it starts [1]
        self._psi0 = np.zeros(n)
        self._psi1 = np.zeros(n)
        self._bezier = np.full((n, 4, 3), np.nan)
        self._use_bezier = np.zeros(n, bool)
        self._commanded = np.zeros(n, bool)
        self.stats = {"commands": 0, "poses": 0, "lowered": 0, "lowered_max": 0.0,
                      "bezier_lifted": 0, "toe_lifted": 0}  # fmt: skip

    @property
    def skeleton(self) -> tuple[tuple[str, ...], np.ndarray]:
        """Joint names (J,) and parent indices (J,)."""
        return JOINT_NAMES, PARENTS.copy()

    # -- steps ------------------------------------------------------------------------
    def command(self, steps) -> None:
        """Start the steps of a :class:`crowdwalk.steps.StepBatch` (at their heel strikes)."""
        a = np.asarray(steps.agent, dtype=np.intp)
        if a.size == 0:
            return
        n = len(self.body)
        if np.any((a < 0) | (a >= n)) or np.unique(a).size != a.size:
            raise invalid("KoBadlerEngine", "agent", f"distinct indices in [0, {n})", a)
        start = np.asarray(steps.start, dtype=float)
        target = np.asarray(steps.target, dtype=float)
        heading = np.asarray(steps.heading, dtype=float)
        length = np.maximum(np.asarray(steps.length, dtype=float), 0.02)
        first = ~self._commanded[a]
        # The swing foot's footprint and the walker's previous step: the last step's, or
        # for a first step one step behind, mirrored across the walking line.
        fwd = np.stack([np.cos(heading), np.sin(heading), np.zeros(a.size)], axis=1)
        centre = np.concatenate([np.asarray(steps.stance_centre, dtype=float),
                                 start[:, 2:]], axis=1)  # fmt: skip
        guess = 2 * centre - start - length[:, None] * fwd
        guess[:, 2] = start[:, 2]
        # MetaGait's orientation (§6.1): the landing foot points the step's toe-out from
        # the heading; the trailing foot is where the last stance foot's spin left it
        side_sw = np.where(np.asarray(steps.foot) == 0, 1.0, -1.0)
        toe_out = column_or(steps, "toe_out", np.full(a.size, self.style.toe_out))
        spun = self._spun_origin(a, self._start[a], self._yaw_stance[a], self._yaw_end[a])
        trail = np.where(first[:, None], guess, spun)
        before = np.where(first, length, self._length[a])
        hip_now = np.where(first, hip_height_at_heel_strike(
            self.own.law, self.condition.take(a), before), self._hip_end[a])  # fmt: skip
        yaw_stance = np.where(first, heading - side_sw * toe_out, self._yaw_land[a])
        self._yaw_trail[a] = np.where(first, heading + side_sw * toe_out, self._yaw_end[a])
        self._yaw_stance[a] = yaw_stance
        self._yaw_land[a] = heading + side_sw * toe_out
        self._psi0[a] = np.where(first, heading, self._psi1[a])
        self._psi1[a] = heading
        # φ_ρ of the walker's own walk to this step (Ko & Badler §2).
        own = self.own.take(a)
        w = step_length_generalization(own, length / own.step_length,
                                       start=StepStart(before, hip_now))  # fmt: skip
        for k in ("foot2", "meta"):
            self._push[k][a] = np.where(first[:, None], getattr(w, k).v, self._values[k][a])
        for k in SEQUENCES:
            self._values[k][a] = getattr(w, k).v
        self._hip_end[a] = w.hip.y[:, -1]
        self._t0[a] = np.asarray(steps.start_time, dtype=float)
        self._duration[a] = np.asarray(steps.duration, dtype=float)
        self._before[a] = before
        self._length[a] = length
        self._start[a], self._target[a], self._trail[a] = start, target, trail
        self._stance_left[a] = np.asarray(steps.foot) == 1  # the right foot swings
        bezier = np.asarray(steps.swing_bezier, dtype=float)
        self._bezier[a] = bezier
        self._use_bezier[a] = np.isfinite(bezier).all(axis=(1, 2)) & self._uneven(trail, target)
        self._commanded[a] = True
        # the stance foot's spin turn: about its ball once its heel is up (none if never)
        self._spin_start[a] = self._heel_off(a)
        spin = column_or(steps, "spin", np.zeros(a.size))
        self._spin[a] = np.where(self._spin_start[a] < 1.0, spin, 0.0)
        self._yaw_end[a] = yaw_stance + self._spin[a]
        self.stats["commands"] += a.size

    def _heel_off(self, a: np.ndarray) -> np.ndarray:
        """Step phase s (m,) [1] at which the stance foot's heel has risen
        ``SPIN_HEEL_LIFT`` on its ball (after 30 % of the step); 1 where it never does."""
        g = _SPIN_GRID.size
        rows, s = np.repeat(a, g), np.tile(_SPIN_GRID, a.size)
        f = np.where(s < self.own.fgm, self._seq("foot1", rows, s), self._seq("foot2", rows, s))
        cond = self.condition.take(rows)
        up = ((cond.heel + cond.ball) * np.sin(np.maximum(-f, 0.0)) >= SPIN_HEEL_LIFT)
        up = up.reshape(a.size, g)
        return np.where(up.any(axis=1), _SPIN_GRID[np.argmax(up, axis=1)], 1.0)

    def _spun_origin(self, a, origin, yaw0, yaw):
        """Footprint origins (m, 3) [m] of stance feet at ``origin`` pointing ``yaw0``
        turned to ``yaw`` (m,) [rad] about their balls (N + bN along the foot)."""
        bn = np.asarray(self.condition.take(a).ball, dtype=float) * np.ones(a.size)
        d = np.stack([np.cos(yaw0) - np.cos(yaw), np.sin(yaw0) - np.sin(yaw),
                      np.zeros(a.size)], axis=1)
        return origin + bn[:, None] * d

    def _uneven(self, trail: np.ndarray, target: np.ndarray) -> np.ndarray:
        """(m,) bool: the ground under the swing path rises above the line between the
        footholds by more than ``_UNEVEN`` (without ``ground``: the footholds differ)."""
        line = trail[:, None] + _PATH[None, :, None] * (target - trail)[:, None]
        if self.ground is None:
            return np.abs(target[:, 2] - trail[:, 2]) > _UNEVEN
        z = np.asarray(self.ground(line[..., :2].reshape(-1, 2))).reshape(line.shape[:2])
        return np.max(z - line[..., 2], axis=1) > _UNEVEN

    def _toe_clearance_lift(self, cond, ankle_y, foot, toe_pitch, swing) -> np.ndarray:
        """Lift [m] (k,) of the swing ankle so that its sole (heel, ball, toe tip) clears
        the floor line by ``_TOE_CLEARANCE`` in mid swing; ``swing`` (k,) is the phase in
        [TOM, HSM⁺] as 0…1 (smooth window: 0 at toe-off and from 0.85 on, the landing)."""
        c, s_ = np.cos(foot), np.sin(foot)
        heel = ankle_y - cond.heel * s_ - cond.ankle_height * c
        ball = ankle_y + cond.ball * s_ - cond.ankle_height * c
        toe = ball + cond.toes * np.sin(toe_pitch)
        low = np.minimum(np.minimum(heel, ball), toe)
        x = np.clip(swing, 0.0, 1.0)
        rise, fall = np.clip(x / 0.15, 0, 1), np.clip((0.85 - x) / 0.15, 0, 1)
        window = rise * rise * (3 - 2 * rise) * fall * fall * (3 - 2 * fall)
        lift = window * np.maximum(_TOE_CLEARANCE - low, 0.0)
        self.stats["toe_lifted"] += int(np.count_nonzero(lift > 0))
        return lift

    # -- poses ------------------------------------------------------------------------
    def _seq(self, name: str, a: np.ndarray, s: np.ndarray, values=None) -> np.ndarray:
        q = getattr(self.own, name)
        v = (self._values if values is None else values)[name][a]
        return interpolation(q.with_values(v), s)

    def _push_off(self, cond, a, s1, mom):
        """Foot angle, sagittal ankle and toe pitch of the swing foot pushing off (k,)."""
        f = self._seq("foot2", a, s1, self._push)
        m = np.where(s1 >= mom, self._seq("meta", a, s1, self._push), 0.0)
        ankle, toe = foot_configuration(cond, f, m)
        return f, ankle, toe

    def pose(self, t: float, agents: np.ndarray) -> PoseFrame:
        """Poses of ``agents`` (k,) at time ``t`` [s]."""
        a = np.atleast_1d(np.asarray(agents, dtype=np.intp))
        if not np.all(self._commanded[a]):
            raise invalid("KoBadlerEngine", "agents", "agents that received a step", a)
        if not np.isfinite(t):
            raise invalid("KoBadlerEngine", "t", "finite [s]", t)
        k = a.size
        body = self.body.take(a)
        cond = self.condition.take(a)
        own = self.own
        s = np.clip((t - self._t0[a]) / self._duration[a], 0.0, 1.0)
        fgm, mom, tom = own.fgm, own.mom, own.tom
        start, target, trail = self._start[a], self._target[a], self._trail[a]
        length, before = self._length[a], self._before[a]

        # Stance foot on its foothold (F1, F2, M); a spin turn turns it about its ball
        # from when its heel is up, holding the heel up while it turns (MetaGait §6.1).
        f_st = np.where(s < fgm, self._seq("foot1", a, s), self._seq("foot2", a, s))
        s0 = self._spin_start[a]
        turned = np.clip((s - s0) / np.maximum(1.0 - s0, _EPS), 0.0, 1.0)
        spinning = (turned > 0) & (self._spin[a] != 0)
        hold = -np.arcsin(np.minimum(SPIN_HEEL_LIFT / (cond.heel + cond.ball), 1.0))
        f_st = np.where(spinning, np.minimum(f_st, hold), f_st)
        yaw_st = self._yaw_stance[a] + self._spin[a] * turned * turned * (3.0 - 2.0 * turned)
        origin_st = self._spun_origin(a, start, self._yaw_stance[a], yaw_st)
        m_st = np.where(s >= mom, self._seq("meta", a, s), 0.0)
        ankle_st, toe_st = foot_configuration(cond, f_st, m_st)
        # Swing foot: until TOM it pushes off its footprint as the stance foot of the last
        # step did (that step's F2, M one step on); then the ankle follows A and the foot
        # F3, offset at TOM to where the push-off left them, the offset fading linearly
        # over the swing (as Eq. 30's d1; consecutive steps' μ3, μ4 differ).
        push = s < tom
        f_push, ankle_push, toe_push = self._push_off(cond, a, s + 1.0, mom)
        f_end, ankle_end, toe_end = self._push_off(cond, a, np.full(k, 1.0 + tom), mom)

        def on_print(origin, yaw, xy):  # footprint frame → world
            c, si = np.cos(yaw), np.sin(yaw)
            return origin + np.stack([c * xy[:, 0], si * xy[:, 0], xy[:, 1]], axis=1)

        def flight(ankle_xy):  # A's (x, y) → world point and the floor below it
            u = np.clip((ankle_xy[:, 0] + before) / (before + length), 0.0, 1.0)
            floor = trail + u[:, None] * (target - trail)
            return floor + np.stack([0 * u, 0 * u, ankle_xy[:, 1]], axis=1), floor, u

        fade = 1.0 - np.clip((s - tom) / (1 - tom), 0.0, 1.0)
        fly0, _, _ = flight(self._seq("ankle", a, np.full(k, tom)))
        fly, floor, u = flight(self._seq("ankle", a, s))
        fly += fade[:, None] * (on_print(trail, self._yaw_trail[a], ankle_end) - fly0)
        # ... and lands pointing its toe-out: A ends its offset from the target along ψ;
        # the foot turned to its landing yaw carries that offset round (faded in over the
        # swing), so the landing is where the next step's stance foot starts
        reach = np.stack([self._seq("ankle", a, np.ones(k))[:, 0] - length, 0 * s], axis=1)
        turn_in = on_print(target, self._yaw_land[a], reach) - on_print(
            target, self._psi1[a], reach)
        fly += (1.0 - fade)[:, None] * turn_in
        f_fly = self._seq("foot3", a, s) + fade * (f_end - self._values["foot3"][a, 0])
        relax = np.clip((s - tom) / _TOE_RELAX, 0.0, 1.0)
        toe_fly = f_fly + (1 - relax) * (toe_end - f_end)
        f_sw = np.where(push, f_push, f_fly)
        toe_sw = np.where(push, toe_push, toe_fly)
        p_ankle_st = on_print(origin_st, yaw_st, ankle_st)
        fly[:, 2] += self._toe_clearance_lift(cond, fly[:, 2] - floor[:, 2], f_fly, toe_fly,
                                              (s - tom) / (1 - tom))  # fmt: skip
        bez = self._bezier[a]
        has_bez = self._use_bezier[a] & ~push
        if has_bez.any():
            w = np.stack([(1 - u) ** 3, 3 * (1 - u) ** 2 * u, 3 * (1 - u) * u**2, u**3], 1)
            z_bez = np.einsum("kc,kc->k", w[has_bez], bez[has_bez, :, 2])
            up = np.maximum(z_bez - fly[has_bez, 2], 0.0)
            ramp = np.clip((s[has_bez] - tom) / (_BEZIER_RAMP * (1 - tom)), 0.0, 1.0)
            fly[has_bez, 2] += ramp * ramp * (3 - 2 * ramp) * up  # eased in after TOM
            self.stats["bezier_lifted"] += int(np.count_nonzero(up > 0))
        p_ankle_sw = np.where(push[:, None], on_print(trail, self._yaw_trail[a], ankle_push), fly)
        yaw_fly = self._yaw_trail[a] + _wrap(self._yaw_land[a] - self._yaw_trail[a]) * np.clip(
            (s - tom) / (1 - tom), 0.0, 1.0)  # fmt: skip
        yaw_sw = np.where(push, self._yaw_trail[a], yaw_fly)

        # Pelvis: H's x times its path between foothold-pair midpoints, H's y above them.
        hip = self._seq("hip", a, s)
        hx = self._values["hip"][a][:, :, 0]
        wpath = (hip[:, 0] - hx[:, 0]) / np.maximum(hx[:, -1] - hx[:, 0], _EPS)
        c0, c1 = 0.5 * (trail + start), 0.5 * (start + target)
        pelvis = c0 + wpath[:, None] * (c1 - c0)
        pelvis[:, 2] += hip[:, 1]
        yaw_p = self._psi0[a] + _wrap(self._psi1[a] - self._psi0[a]) * s
        r_pelvis = rotation_z(yaw_p)
        left_dir = r_pelvis[:, :, 1]
        side = np.where(self._stance_left[a], 1.0, -1.0)[:, None]
        half = 0.5 * body.hip_separation[:, None]
        reach = _REACH * (body.thigh + body.shank)
        for ankle_p, sgn in ((p_ankle_st, side), (p_ankle_sw, -side)):
            h = pelvis + sgn * half * left_dir
            flat = np.linalg.norm((ankle_p - h)[:, :2], axis=1)
            top = ankle_p[:, 2] + np.sqrt(np.maximum(reach**2 - flat**2, 0.0))
            low = pelvis[:, 2] - top
            self.stats["lowered"] += int((low > 0).sum())
            self.stats["lowered_max"] = max(self.stats["lowered_max"], float(low.max()))
            pelvis[:, 2] = np.minimum(pelvis[:, 2], top)
        hip_st = pelvis + side * half * left_dir
        hip_sw = pelvis - side * half * left_dir
        forward = r_pelvis[:, :, 0]
        knee_st = two_link_knee(hip_st, p_ankle_st, body.thigh, body.shank, forward)
        knee_sw = two_link_knee(hip_sw, p_ankle_sw, body.thigh, body.shank, forward)

        # Joint rotations (BVH semantics: R_world[j] = R_world[parent] @ local[j]).
        nj = len(JOINT_NAMES)
        local = np.broadcast_to(np.eye(3), (k, nj, 3, 3)).copy()
        legs = np.where(self._stance_left[a][:, None], LEG_JOINTS[0], LEG_JOINTS[1])
        legs_sw = np.where(self._stance_left[a][:, None], LEG_JOINTS[1], LEG_JOINTS[0])
        rows = np.arange(k)
        for joints, hp, kn, an, f, yaw, toe in (
            (legs, hip_st, knee_st, p_ankle_st, f_st, yaw_st, toe_st),
            (legs_sw, hip_sw, knee_sw, p_ankle_sw, f_sw, yaw_sw, toe_sw),
        ):
            hinge = np.cross(hp - an, forward)  # normal of the leg's plane (+y at rest)
            r_thigh = _segment_frame(kn - hp, hinge)
            r_shank = _segment_frame(an - kn, hinge)
            r_foot = rotation_z(yaw) @ rotation_y(-f)
            local[rows, joints[:, 0]] = _t(r_pelvis) @ r_thigh
            local[rows, joints[:, 1]] = _t(r_thigh) @ r_shank
            local[rows, joints[:, 2]] = _t(r_shank) @ r_foot
            local[rows, joints[:, 4]] = rotation_y(-(toe - f))
        # Upper body (ElevWalker §8): trunk upright along ψ, arms with the opposite thigh.
        local[:, JOINT["vl5"]] = _t(r_pelvis) @ rotation_z(yaw_p)
        st_left = self._stance_left[a]
        elev_st, elev_sw = _elev(hip_st, knee_st, forward), _elev(hip_sw, knee_sw, forward)
        thigh_left = np.where(st_left, elev_st, elev_sw)
        thigh_right = np.where(st_left, elev_sw, elev_st)
        for name, thigh_opp, tilt in (("l", thigh_right, 0.08), ("r", thigh_left, -0.08)):
            arm = self.style.arm_swing * thigh_opp
            local[:, JOINT[f"{name}_shoulder"]] = rotation_y(-arm) @ rotation_x(np.full(k, tilt))
            local[:, JOINT[f"{name}_elbow"]] = rotation_y(
                -(self.style.elbow_flexion + 0.5 * np.maximum(arm, 0.0)))  # fmt: skip
        positions, _ = forward_kinematics(body, pelvis, r_pelvis, local)
        local[:, 0] = r_pelvis
        quats = matrix_to_quaternion(local)
        contact = np.ones((k, 2), bool)
        swing_col = np.where(self._stance_left[a], 1, 0)
        contact[rows, swing_col] = push
        self.stats["poses"] += k
        return PoseFrame(agents=a, time=float(t), root_position=pelvis,
                         root_quaternion=quats[:, 0].copy(), joints=quats, positions=positions,
                         contact=contact, fallback=np.zeros(k, bool),
                         stance_left=self._stance_left[a].copy())  # fmt: skip


def _elev(hip, knee, forward):
    """Thigh elevation: hip→knee from the downward vertical, knee anterior + [rad]."""
    d = knee - hip
    return np.arctan2(np.sum(d * forward, axis=1), -d[:, 2])
