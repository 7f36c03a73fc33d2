"""KLAW: step-oriented kinematic walking (Bruderlin & Calvert 1993, §2).

Per step (from the heel strike of the stance foot at t1 to the heel strike of the swing
foot at t4) the engine computes the **step constraints** of §2.2 from the walker's style
(:class:`crowdwalk.style.Style`, read at each command, so a change of parameters takes
effect at the next step) and the step the crowd decided (footholds, heading, duration):

1. **Leg-phase durations**: the step time t_step comes from the crowd; the double support
   t_ds = ``double_support_fraction(f)`` · t_step from the step frequency f = 1 / t_step
   (measured: the shipped level-walking datasets), t_swing = t_step − t_ds.
2. **Leg angles at the end of the step**: the landing leg's virtual leg (hip to ankle, knee
   flexed by ``knee_impact``) reaches the landing ankle from ``HIP_BEHIND`` step lengths
   behind it; that fixes the stance hip at t4 and y_impact.
3. **Stance-hip control points** at t1 (mid double support t2 = t_ds/2, mid swing t3 =
   t_ds + t_swing/2, t4), §2.2 as written::

       x_mid_ds    = 0.5 t_ds s_l x_factor / t_step
       x_mid_swing = (t_ds + 0.5 t_swing) s_l / (t_step x_factor)
       y_mid_swing = f(knee_bend)   (virtual leg with the knee flexed knee_bend, over the
                                     stance ankle at t3)
       y_mid_ds    = y_impact − bounce_factor (y_mid_swing − y_impact) / 5

   with x_factor = 1.1, knee_bend = ``knee_stance_min`` (8°), bounce_factor =
   ``bounciness`` (1); s_l is the stance hip's travel over the step (the step length in
   steady walking). Interpolating splines (Kochanek & Bartels 1984 with tension,
   continuity and bias 0) through the four points give x(t) and y(t); the start tangent
   is the end tangent of the previous step (C¹ across steps).
4. **Stance leg by the virtual-leg principle**: the stance foot rolls over its heel to
   flat, then (where the hip moves beyond the reach of the virtual leg with the knee at
   ``knee_stance_min``) over its ball; the knee follows from the hip–ankle distance.
5. **Pelvis** (§2.2, Figs. 5–6) from the extreme values by linear interpolation:
   rotation ±``pelvic_rotation`` at heel strikes, 0 at mid stance; list 0 at heel strikes,
   ``pelvic_list`` (swing side down) at the end of double support; lateral displacement
   toward the stance leg, 0 at heel strikes and greatest at mid stance, growing with stride
   width and falling with speed. The swing hip follows from the pelvis.
6. **Swing leg in three sub-phases** ([3]; thigh elevation, knee flexion and foot pitch
   interpolated linearly between toe-off, end of initial swing (greatest knee flexion),
   end of mid swing (greatest hip flexion) and heel strike); the knee flexion of the
   inner key frames is set so that the least toe clearance in mid swing is
   ``toe_clearance``. Before toe-off the trailing foot rolls on its ball.
7. **Upper body**: each arm swings with the opposite leg (``arm_swing`` at its extremes,
   elbow from ``elbow_min`` back to ``elbow_max`` forward, ``arm_out`` abduction), the
   shoulders rotate against the pelvis (``shoulder_rotation``), the trunk tilts
   (``torso_tilt``) and sways over the stance leg (``torso_sway``).

Deviations (docs/architecture.md): durations and leg angles of [3] are not in our sources
and are replaced as said in 1–2; feet lie horizontal (stair treads; ramps tilt nothing).
Batched over agents: numpy on (k,) arrays, no Python loop over agents.
"""

from __future__ import annotations

import numpy as np

from crowdwalk.body import (
    JOINT,
    JOINT_NAMES,
    PARENTS,
    Body,
    forward_kinematics,
    matrix_to_quaternion,
    rotation_x,
    rotation_y,
    rotation_z,
)
from crowdwalk.errors import invalid
from crowdwalk.gait.foot import SPIN_HEEL_LIFT, column_or, two_link_knee
from crowdwalk.gait.foot import wrap_angle as _wrap

__all__ = ["KlawEngine", "X_FACTOR", "double_support_fraction", "kochanek_bartels",
           "virtual_leg_length"]

X_FACTOR = 1.1  # §2.2: change in horizontal velocity
HIP_BEHIND = 0.4  # stance hip behind the landing ankle at heel strike [step lengths]
KNEE_TOE_OFF = np.deg2rad(35.0)  # knee flexion at toe-off (Winter 1991: 35-40°)
KNEE_SWING = np.deg2rad(60.0)  # greatest swing knee flexion before clearance (Winter: 60-65°)
THIGH_OVERSHOOT = np.deg2rad(4.0)  # greatest hip flexion beyond the heel-strike angle
HEEL_STRIKE_PITCH = np.deg2rad(15.0)  # foot toe-up at heel strike
SUBPHASES = (0.3, 0.7)  # ends of swing sub-phases 1 and 2 [fraction of swing]
MTC_WINDOW = (0.3, 0.85)  # where the least toe clearance is taken [fraction of swing]
_MTC_SAMPLES = np.linspace(*MTC_WINDOW, 16)
_EXTRA_KNEE = np.deg2rad([-40.0, 80.0])  # range of the clearance's knee flexion change
# Double support per step [fraction of step] at step frequency [steps/s]: the shipped level
# datasets (crowdwalk/data, Bovi 2011 / Winter), sorted by frequency.
_DS_FREQ = np.array([1.439, 1.817, 1.822, 2.045, 2.340])
_DS_FRAC = np.array([0.3089, 0.2526, 0.2558, 0.2385, 0.1882])


_SPIN_GRID = np.linspace(0.0, 1.0, 26)  # step fractions searched for the heel rise



def double_support_fraction(step_frequency: np.ndarray) -> np.ndarray:
    """Double support over step time [1] at ``step_frequency`` (k,) [steps/s] (measured,
    clamped to the data's range)."""
    return np.interp(step_frequency, _DS_FREQ, _DS_FRAC)


def virtual_leg_length(thigh, shank, knee) -> np.ndarray:
    """Hip-to-ankle distance [m] of legs (k,) with the knee flexed ``knee`` [rad]."""
    return np.sqrt(thigh**2 + shank**2 + 2.0 * thigh * shank * np.cos(knee))


def kochanek_bartels(knots: np.ndarray, values: np.ndarray, start_tangent: np.ndarray,
                     end_tangent: np.ndarray) -> np.ndarray:
    """Tangents (k, 4) of Kochanek–Bartels splines with t = c = b = 0 through four
    points per row (``knots`` (k, 4) [s], ``values`` (k, 4)); inner tangents are the mean
    of the neighbouring chord slopes, the end tangents (k,) are given."""
    slope = np.diff(values, axis=1) / np.maximum(np.diff(knots, axis=1), 1e-9)
    return np.column_stack([start_tangent, 0.5 * (slope[:, :-1] + slope[:, 1:]), end_tangent])


def _hermite(knots, values, tangents, t):
    """Cubic Hermite evaluation (k,) of the splines at times ``t`` (k,) (clamped)."""
    t = np.clip(t, knots[:, 0], knots[:, -1])
    i = np.clip((t[:, None] >= knots[:, 1:-1]).sum(axis=1), 0, 2)
    r = np.arange(t.size)
    t0, t1 = knots[r, i], knots[r, i + 1]
    h = np.maximum(t1 - t0, 1e-9)
    s = (t - t0) / h
    h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, \
        s**3 - s**2
    return (h00 * values[r, i] + h10 * h * tangents[r, i] + h01 * values[r, i + 1]
            + h11 * h * tangents[r, i + 1])


def _lerp_keys(knots, values, t):
    """Piecewise-linear interpolation (k,) through key values (k, q) at knots (k, q)."""
    t = np.clip(t, knots[:, 0], knots[:, -1])
    i = np.clip((t[:, None] >= knots[:, 1:-1]).sum(axis=1), 0, knots.shape[1] - 2)
    r = np.arange(t.size)
    t0, t1 = knots[r, i], knots[r, i + 1]
    w = np.clip((t - t0) / np.maximum(t1 - t0, 1e-9), 0.0, 1.0)
    return values[r, i] + w * (values[r, i + 1] - values[r, i])


def _fwd(psi):
    return np.stack([np.cos(psi), np.sin(psi), np.zeros_like(psi)], axis=-1)


def _left(psi):
    return np.stack([-np.sin(psi), np.cos(psi), np.zeros_like(psi)], axis=-1)


def _dot(a, b):
    return np.einsum("...i,...i->...", a, b)


def _unit(v):
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def _foot_offsets(body: Body, pitch, yaw):
    """Heel, ball and toe-tip offsets from the ankle, (k, 3, 3) [m], of a rigid foot
    pitched toe-up by ``pitch`` [rad] along ``yaw`` (toes in line with the foot)."""
    f, z = _fwd(yaw), np.array([0.0, 0.0, 1.0])
    c, s = np.cos(pitch)[:, None], np.sin(pitch)[:, None]
    along, up = c * f + s * z, -s * f + c * z  # the foot's forward and up axes
    ah = body.ankle_height[:, None]
    return np.stack([-body.heel_offset[:, None] * along - ah * up,
                     body.ball_offset[:, None] * along - ah * up,
                     body.toe_offset[:, None] * along - ah * up], axis=1)


def _roll_about(pivot, pivot_offset, hip, reach, yaw, pitch_range):
    """Foot pitch [rad] (k,) rolling about a ground point so that the ankle lies ``reach``
    (k,) [m] from the hip, with ``pivot_offset`` = (forward, down) of the pivot from the
    ankle in the foot frame; the root nearest the flat foot, clamped to ``pitch_range``."""
    f = _fwd(yaw)
    rel = hip - pivot
    fx, fz = _dot(rel, f), rel[:, 2]
    lat2 = np.maximum(_dot(rel, rel) - fx**2 - fz**2, 0.0)
    r2 = np.maximum(reach**2 - lat2, 1e-9)  # in-plane radius about the hip
    a, b = pivot_offset  # ankle = pivot + R(p)(-a, b): distance rho from the pivot
    rho = np.hypot(a, b)
    base = np.arctan2(b, -a)  # direction of the ankle from the pivot at pitch 0
    d = np.hypot(fx, fz)
    cos_g = np.clip((rho**2 + d**2 - r2) / (2.0 * rho * np.maximum(d, 1e-9)), -1.0, 1.0)
    toward = np.arctan2(fz, fx)
    cand = np.stack([toward + np.arccos(cos_g), toward - np.arccos(cos_g)]) - base
    cand = _wrap(cand)
    best = np.where(np.abs(cand[0]) <= np.abs(cand[1]), cand[0], cand[1])
    return np.clip(best, *pitch_range)


def _segment_frame(down, forward):
    """World frames (k, 3, 3) whose −z is ``down`` and x lies toward ``forward``."""
    z = -_unit(down)
    x = _unit(forward - _dot(forward, z)[:, None] * z)
    return np.stack([x, np.cross(z, x), z], axis=2)


def _sagittal_ik(fwd_dist, down_dist, thigh, shank):
    """Thigh elevation and knee flexion [rad] (k,) putting the ankle ``fwd_dist`` ahead
    of and ``down_dist`` below the hip in the leg's plane (knee forward)."""
    dist = np.clip(np.hypot(fwd_dist, down_dist), np.abs(thigh - shank) + 1e-6,
                   0.99999 * (thigh + shank))
    line = np.arctan2(fwd_dist, down_dist)
    at_hip = np.arccos(np.clip((thigh**2 + dist**2 - shank**2) / (2 * thigh * dist), -1, 1))
    knee = np.pi - np.arccos(np.clip((thigh**2 + shank**2 - dist**2) / (2 * thigh * shank),
                                     -1, 1))
    return line + at_hip, knee


class KlawEngine:
    """KLAW poses for n walkers from the crowd's steps (``gait: klaw``).

    Parameters
    ----------
    body : Body
        n bodies; agent i is row i.
    ground : callable, optional
        ``ground(xy (p, 2)) -> z (p,)`` [m] for the swing foot's toe clearance; without it
        the ground is the line between the step's footholds.
    attributes : Style, optional
        n styles (:mod:`crowdwalk.style`, default: the normal walk); kept as
        ``engine.style`` — replace it to change them, each walker takes the new values at
        its next step.
    """

    name = "klaw"

    def __init__(self, body: Body, ground=None, attributes=None) -> None:
        from crowdwalk.style import Style

        style = Style.default(body.height, 1.34) if attributes is None else attributes
        if len(style) != len(body):
            raise invalid("KlawEngine", "attributes", f"of {len(body)} walkers", len(style))
        self.body, self.style, self.ground = body, style, ground
        n = len(body)
        self._commanded = np.zeros(n, bool)
        z1, z3 = np.zeros(n), np.zeros((n, 3))
        self._s = {name: z1.copy() for name in (
            "t0", "T", "tds", "side", "psi0", "psi1", "dmax", "rot", "list", "tflat",
            "p_hs", "yaw_st", "yaw_tr", "yaw_land", "p_tr0", "k_tr0", "front", "lat_to",
            "lat_hs", "rear", "z_land", "v_end_x", "v_end_z", "next_p", "p_hs_now", "kmin",
            "arm", "arm_out", "elbow_min", "elbow_max", "shoulder", "tilt", "sway", "spin",
            "spin_t0", "spin_pitch", "yaw_end")}
        self._s.update({name: z3.copy() for name in (
            "origin", "u", "heel_st", "ball_st", "ball_tr", "hip_b_end", "ankle_hs")})
        self._s.update({name: np.zeros((n, 4)) for name in (
            "knots", "hx", "hz", "mx", "mz", "kt", "th", "kn", "fp")})
        self.stats = {"commands": 0, "poses": 0}

    @property
    def skeleton(self) -> tuple[tuple[str, ...], np.ndarray]:
        """Joint names (J,) and parent indices (J,) for ``record.RunWriter``."""
        return JOINT_NAMES, PARENTS.copy()

    # -- steps ----------------------------------------------------------------------
    def command(self, cmd) -> None:
        """Start the steps in ``cmd`` (a :class:`crowdwalk.steps.StepBatch`: ``agent``,
        ``start_time``, ``duration``, ``foot`` (the swinging one, 0 left), ``start``,
        ``target``, ``heading``)."""
        a = np.asarray(cmd.agent)
        if a.size == 0:
            return
        n = len(self.body)
        if np.any((a < 0) | (a >= n)) or np.unique(a).size != a.size:
            raise invalid("KlawEngine", "agent", f"distinct indices in [0, {n})", a)
        s, b, st = self._s, self.body.take(a), self.style.take(a)
        m = a.size
        first = ~self._commanded[a]
        side = np.where(np.asarray(cmd.foot) == 0, -1.0, 1.0)  # +1: left stance
        T = np.asarray(cmd.duration, float)
        f = 1.0 / T
        tds = double_support_fraction(f) * T
        tsw = T - tds
        psi1 = np.asarray(cmd.heading, float)
        psi0 = np.where(first, psi1, s["psi1"][a])
        start, target = np.asarray(cmd.start, float), np.asarray(cmd.target, float)
        hh = 0.5 * b.hip_separation
        l1, l2 = b.thigh, b.shank
        kmin, kimp = st.knee_stance_min, st.knee_impact

        # the feet: the stance foot landed at start (heel rocker from the swing's landing
        # pitch); the trailing foot is the previous stance foot (feet side by side first)
        yaw_st = np.where(first, psi1 + side * st.foot_angle, s["yaw_land"][a])
        heel_st = np.where(first[:, None], start - b.heel_offset[:, None] * _fwd(yaw_st),
                           s["ankle_hs"][a] + _foot_offsets(b, s["p_hs"][a], yaw_st)[:, 0])
        heel_st[:, 2] = start[:, 2]
        p_hs_st = np.where(first, 0.0, s["p_hs"][a])
        ankle_flat = heel_st + b.heel_offset[:, None] * _fwd(yaw_st)
        ankle_flat[:, 2] += b.ankle_height
        ball_st = ankle_flat + _foot_offsets(b, np.zeros(m), yaw_st)[:, 1]
        lateral0 = _left(psi1) * (side * st.stride_width)[:, None]
        yaw_tr = np.where(first, psi1 - side * st.foot_angle, s["yaw_end"][a])
        ball_tr = np.where(first[:, None], ball_st - lateral0, s["ball_st"][a])
        p_tr0 = np.where(first, 0.0, s["next_p"][a])

        # landing: the heel-strike ankle, the landing leg's hip HIP_BEHIND steps behind it;
        # the landing foot points the step's toe-out from the heading (MetaGait §6.1)
        toe_out = column_or(cmd, "toe_out", st.foot_angle)
        yaw_land = psi1 - side * toe_out
        land_heel = target - b.heel_offset[:, None] * _fwd(yaw_land)
        ankle_hs = land_heel - _foot_offsets(b, np.full(m, HEEL_STRIKE_PITCH), yaw_land)[:, 0]
        fwd1, left1 = _fwd(psi1), _left(psi1)
        step = np.maximum(_dot(target - start, fwd1), 0.05)
        centre = target + 0.5 * _dot(start - target, left1)[:, None] * left1
        rot_end = side * st.pelvic_rotation  # the landing (swing) hip forward
        y_p = rotation_z(psi1 + rot_end)[:, :, 1]
        xf = HIP_BEHIND * step
        hip_b_xy = ankle_hs - xf[:, None] * fwd1
        root_xy = centre + (_dot(hip_b_xy - centre, fwd1) + side * hh * _dot(y_p, fwd1)
                            )[:, None] * fwd1
        hip_b = root_xy - (side * hh)[:, None] * y_p
        gap = hip_b - ankle_hs
        reach = virtual_leg_length(l1, l2, kimp)
        hip_b[:, 2] = ankle_hs[:, 2] + np.sqrt(np.maximum(
            reach**2 - gap[:, 0]**2 - gap[:, 1]**2, 0.01 * reach**2))
        hip_a_end = hip_b + (2 * side * hh)[:, None] * y_p
        hip_a_end[:, 2] = hip_b[:, 2]

        # the stance hip's spline (§2.2)
        origin = np.where(first[:, None], 0.0, s["hip_b_end"][a])
        stand = ankle_flat + (side * hh)[:, None] * _left(psi1) - lateral0 * 0.5
        stand[:, 2] = ankle_flat[:, 2] + virtual_leg_length(l1, l2, kmin)
        origin = np.where(first[:, None], stand, origin)
        travel = hip_a_end - origin
        D = np.maximum(np.hypot(travel[:, 0], travel[:, 1]), 1e-3)
        u = np.where((D > 2e-3)[:, None], travel / D[:, None], fwd1)
        u[:, 2] = 0.0
        u = _unit(u)
        t2, t3 = 0.5 * tds, tds + 0.5 * tsw
        x2 = 0.5 * tds * D * X_FACTOR / T
        x3 = (tds + 0.5 * tsw) * D / (T * X_FACTOR)
        speed_v = D / T
        dmax = 0.25 * st.stride_width * np.clip(1.34 / np.maximum(speed_v, 0.1), 0.5, 2.0)
        hip3 = origin + x3[:, None] * u + (side * dmax)[:, None] * _left(psi1)
        rel3 = hip3 - ankle_flat
        y_ms = ankle_flat[:, 2] + np.sqrt(np.maximum(
            virtual_leg_length(l1, l2, kmin)**2 - rel3[:, 0]**2 - rel3[:, 1]**2, 0.01))
        y_imp = origin[:, 2]
        y_ds = y_imp - st.bounciness * (y_ms - y_imp) / 5.0
        knots = np.column_stack([np.zeros(m), t2, t3, T])
        hx = np.column_stack([np.zeros(m), x2, x3, D])
        hz = np.column_stack([y_imp, y_ds, y_ms, hip_a_end[:, 2]])
        vx0 = np.where(first, D / T, s["v_end_x"][a])
        vz0 = np.where(first, 0.0, s["v_end_z"][a])
        # the end tangent toward the next step's t2 point, assumed like this one
        nx = D + x2
        nz = hip_a_end[:, 2] + (y_ds - y_imp)
        vx1 = 0.5 * ((D - x3) / (T - t3) + (nx - D) / t2)
        vz1 = 0.5 * ((hip_a_end[:, 2] - y_ms) / (T - t3) + (nz - hip_a_end[:, 2]) / t2)
        mx = kochanek_bartels(knots, hx, vx0, vx1)
        mz = kochanek_bartels(knots, hz, vz0, vz1)

        cols = dict(t0=np.asarray(cmd.start_time, float), T=T, tds=tds, side=side, psi0=psi0,
                    psi1=psi1, dmax=dmax, rot=st.pelvic_rotation, list=st.pelvic_list,
                    tflat=t2, p_hs=np.full(m, HEEL_STRIKE_PITCH), yaw_st=yaw_st, yaw_tr=yaw_tr,
                    yaw_land=yaw_land, p_tr0=p_tr0, kmin=kmin, arm=st.arm_swing,
                    arm_out=st.arm_out, elbow_min=st.elbow_min, elbow_max=st.elbow_max,
                    shoulder=st.shoulder_rotation, tilt=st.torso_tilt, sway=st.torso_sway,
                    v_end_x=vx1, v_end_z=vz1, origin=origin, u=u, heel_st=heel_st,
                    ball_st=ball_st, ball_tr=ball_tr, hip_b_end=hip_b, ankle_hs=ankle_hs,
                    knots=knots, hx=hx, hz=hz, mx=mx, mz=mz,
                    front=np.arcsin(np.clip(xf / reach, -1, 1)), z_land=target[:, 2])
        for k, v in cols.items():
            s[k][a] = v
        s["p_hs_now"][a] = p_hs_st
        s["spin"][a], s["spin_t0"][a] = 0.0, T
        self._commanded[a] = True
        # trailing knee at t1: where the previous step left it (the foot on its ball)
        t_abs = np.asarray(cmd.start_time, float)
        hip_b0 = self._legs(a, t_abs)["hip_b"]
        rel_tr = ball_tr - _foot_offsets(b, p_tr0, yaw_tr)[:, 1] - hip_b0
        s["k_tr0"][a] = np.pi - np.arccos(np.clip(
            (l1**2 + l2**2 - _dot(rel_tr, rel_tr)) / (2 * l1 * l2), -1, 1))

        # swing key frames: toe-off (the trailing roll at t_ds), sub-phase ends, landing
        to = self._legs(a, t_abs + tds)
        rel = to["ankle_b"] - to["hip_b"]
        s["rear"][a] = np.arctan2(_dot(rel, _fwd(to["psi"])), -rel[:, 2])
        lat_to, th_to, kn_to = self._swing_coords(b, to["hip_b"], to["ankle_b"], to["psi"])
        s["lat_to"][a] = lat_to
        lat_hs, th_hs, kn_hs = self._swing_coords(b, hip_b, ankle_hs, psi1)
        s["lat_hs"][a] = lat_hs
        s["kt"][a] = np.column_stack([tds, tds + SUBPHASES[0] * tsw, tds + SUBPHASES[1] * tsw,
                                      T])
        s["fp"][a] = np.column_stack([to["pitch_b"], 0.5 * to["pitch_b"],
                                      np.full(m, HEEL_STRIKE_PITCH), np.full(m, HEEL_STRIKE_PITCH)])
        th1 = th_to + 0.55 * (th_hs - th_to)
        th2 = th_hs + THIGH_OVERSHOOT
        s["th"][a] = np.column_stack([th_to, th1, th2, th_hs])

        def clearance(extra):
            s["kn"][a] = np.column_stack([kn_to, KNEE_SWING + extra, th2 + extra, kn_hs])
            return self._toe_clearance(a, b, start, target, t_abs, tds, tsw)

        # bisection on the extra knee flexion (the clearance grows with it), then the
        # secant between the bracket ends
        lo, hi = np.full(m, _EXTRA_KNEE[0]), np.full(m, _EXTRA_KNEE[1])
        c_lo, c_hi = clearance(lo), clearance(hi)
        for _ in range(7):
            mid = 0.5 * (lo + hi)
            below = clearance(mid) < st.toe_clearance
            lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
        c_lo, c_hi = clearance(lo), clearance(hi)
        w = np.clip((st.toe_clearance - c_lo) / np.where(c_hi > c_lo, c_hi - c_lo, 1.0), 0, 1)
        clearance(lo + w * (hi - lo))
        # the spin turn (MetaGait §6.1) of the stance foot: about its ball, from when its
        # heel is up SPIN_HEEL_LIFT to the step's end (none if it never stood flat and
        # rose, nor was carried onto its ball by 30 % of the step: then the trailing foot
        # keeps its yaw)
        s["spin_t0"][a], s["spin_pitch"][a] = self._heel_off(a, b, t_abs, T)
        s["spin"][a] = np.where(s["spin_t0"][a] < T, column_or(cmd, "spin", np.zeros(m)),
                                0.0)
        # the stance foot's state at t4 is the next step's trailing foot
        end = self._legs(a, t_abs + T)
        s["next_p"][a] = end["pitch_a"]
        s["yaw_end"][a] = end["yaw_a"]
        self.stats["commands"] += m

    def _heel_off(self, a, b, t_abs, T):
        """Time into the step [s] (m,) at which the stance foot's heel has risen
        ``SPIN_HEEL_LIFT`` rolling on its ball (after 30 % of the step: not the heel
        strike's rocker); ``T`` where it never does, and where the foot neither stood
        flat (its heel down) nor was off its heel rocker by then (a short queueing step
        still on its rocker). A foot the hip carries from its heel straight onto its
        ball (the pivot foot of a step across its own axis) spins, its heel held at
        least as high as at the spin's start (its heel never stood lower). Also the
        highest pitch (m,) [rad] the foot takes while spinning."""
        m = a.size
        times = t_abs[:, None] + _SPIN_GRID[None, :] * T[:, None]
        legs = self._legs(np.repeat(a, _SPIN_GRID.size), times.ravel())
        hb = np.repeat(b.heel_offset + b.ball_offset, _SPIN_GRID.size)
        pitch = legs["pitch_a"].reshape(m, -1)
        up = hb.reshape(m, -1) * np.sin(np.maximum(-pitch, 0.0)) >= SPIN_HEEL_LIFT
        # only a foot that has stood flat (its heel down), or is on its ball early, rises
        # to spin on its ball
        flat = np.maximum.accumulate(pitch == 0.0, axis=1)
        early = _SPIN_GRID[None, :] <= 0.3
        never_flat = ~flat[:, -1]
        on_ball = never_flat & ((pitch < 0.0) & early).any(axis=1)
        up &= (flat | on_ball[:, None]) & ~early
        first = np.argmax(up, axis=1)
        hold = -np.arcsin(np.minimum(SPIN_HEEL_LIFT / (b.heel_offset + b.ball_offset), 1.0))
        limit = np.where(never_flat, np.minimum(hold, pitch[np.arange(m), first]), hold)
        return np.where(up.any(axis=1), _SPIN_GRID[first] * T, T), limit

    @staticmethod
    def _swing_coords(b, hip, ankle, psi):
        """Lateral offset [m] of the ankle from the hip and the sagittal thigh elevation
        and knee flexion [rad] reaching it, (m,) each."""
        rel = ankle - hip
        f, left = _fwd(psi), _left(psi)
        lat = _dot(rel, left)
        down = np.sqrt(rel[:, 2]**2 + lat**2)
        th, kn = _sagittal_ik(_dot(rel, f), down, b.thigh, b.shank)
        return lat, th, kn

    def _toe_clearance(self, a, b, start, target, t_abs, tds, tsw):
        """Least toe-tip height [m] (m,) above the ground over ``MTC_WINDOW`` of swing."""
        m = a.size
        times = t_abs[:, None] + tds[:, None] + _MTC_SAMPLES[None, :] * tsw[:, None]
        rep = np.repeat(a, _MTC_SAMPLES.size)
        legs = self._legs(rep, times.ravel())
        toe = legs["foot_b"][:, 2]
        if self.ground is not None:
            z = self.ground(toe[:, :2])
        else:
            start_r = np.repeat(start, _MTC_SAMPLES.size, 0)
            target_r = np.repeat(target, _MTC_SAMPLES.size, 0)
            span = target_r - start_r
            w = np.clip(_dot(toe - start_r, span) / np.maximum(_dot(span, span), 1e-9), 0, 1)
            z = start_r[:, 2] + w * span[:, 2]
        return (toe[:, 2] - z).reshape(m, -1).min(axis=1)

    # -- poses ----------------------------------------------------------------------
    def _legs(self, a, t):
        """Stance (a) and trailing/swing (b) legs, pelvis and root of agents ``a`` at
        absolute times ``t`` (k,): a dict of (k, ...) arrays."""
        s, b = self._s, self.body.take(a)
        tau = np.clip(t - s["t0"][a], 0.0, s["T"][a])
        T, tds, side = s["T"][a], s["tds"][a], s["side"][a]
        knots = s["knots"][a]
        t3 = knots[:, 2]
        x = _hermite(knots, s["hx"][a], s["mx"][a], tau)
        z = _hermite(knots, s["hz"][a], s["mz"][a], tau)
        w = np.clip(tau / T, 0, 1)
        psi = s["psi0"][a] + _wrap(s["psi1"][a] - s["psi0"][a]) * (3 * w**2 - 2 * w**3)
        # pelvis determinants, linear between their extremes (Figs. 5, 6)
        rho = np.where(tau < t3, 1.0 - tau / np.maximum(t3, 1e-9),
                       -(tau - t3) / np.maximum(T - t3, 1e-9))
        lam = np.where(tau < tds, tau / np.maximum(tds, 1e-9),
                       1.0 - (tau - tds) / np.maximum(T - tds, 1e-9))
        disp = np.where(tau < t3, tau / np.maximum(t3, 1e-9),
                        1.0 - (tau - t3) / np.maximum(T - t3, 1e-9))
        r_p = rotation_z(psi - side * s["rot"][a] * rho) @ rotation_x(side * s["list"][a] * lam)
        hh = 0.5 * b.hip_separation
        hip_a = s["origin"][a] + x[:, None] * s["u"][a] + (side * s["dmax"][a] * disp)[:, None] \
            * _left(psi)
        hip_a[:, 2] = z
        y_p = r_p[:, :, 1]
        root = hip_a - (side * hh)[:, None] * y_p
        hip_b = root - (side * hh)[:, None] * y_p
        l1, l2 = b.thigh, b.shank
        kmin_reach = virtual_leg_length(l1, l2, s["kmin"][a])
        # stance foot: heel rocker to flat by t2, then flat, heel rising if out of reach;
        # once the heel is up it spins its spin turn about the ball (MetaGait §6.1)
        t0 = s["spin_t0"][a]
        turned = np.clip((tau - t0) / np.maximum(T - t0, 1e-9), 0.0, 1.0)
        yaw_st = s["yaw_st"][a] + s["spin"][a] * turned * turned * (3.0 - 2.0 * turned)
        heel = s["heel_st"][a]
        p_rock = s["p_hs_now"][a] * np.clip(1.0 - tau / np.maximum(s["tflat"][a], 1e-9), 0, 1)
        p_ball = _roll_about(s["ball_st"][a], (b.ball_offset, b.ankle_height), hip_a,
                             kmin_reach, yaw_st, (-np.deg2rad(60.0), 0.0))
        flat_ankle = heel + b.heel_offset[:, None] * _fwd(yaw_st)
        flat_ankle[:, 2] += b.ankle_height
        far = np.linalg.norm(hip_a - flat_ankle, axis=1) > kmin_reach
        pitch_a = np.where(p_rock > 0, p_rock, np.where(far, p_ball, 0.0))
        # while it spins the heel stays up: the foot turns on its ball only
        pitch_a = np.where((turned > 0) & (s["spin"][a] != 0),
                           np.minimum(pitch_a, s["spin_pitch"][a]), pitch_a)
        offs_a = _foot_offsets(b, pitch_a, yaw_st)
        ankle_a = np.where((pitch_a >= 0)[:, None], heel - offs_a[:, 0],
                           s["ball_st"][a] - offs_a[:, 1])
        # trailing foot on its ball until toe-off, knee flexing to KNEE_TOE_OFF
        kn_tr = s["k_tr0"][a] + (KNEE_TOE_OFF - s["k_tr0"][a]) * np.clip(
            tau / np.maximum(tds, 1e-9), 0, 1)
        yaw_tr = s["yaw_tr"][a]
        p_tr = _roll_about(s["ball_tr"][a], (b.ball_offset, b.ankle_height), hip_b,
                           virtual_leg_length(l1, l2, kn_tr), yaw_tr, (-np.deg2rad(70.0), 0.0))
        p_tr = np.minimum(p_tr, s["p_tr0"][a])
        ankle_tr = s["ball_tr"][a] - _foot_offsets(b, p_tr, yaw_tr)[:, 1]
        # swing: three sub-phases of linear thigh, knee and foot-pitch interpolation
        kt = s["kt"][a]
        th = _lerp_keys(kt, s["th"][a], tau)
        kn = _lerp_keys(kt, s["kn"][a], tau)
        fp = _lerp_keys(kt, s["fp"][a], tau)
        wsw = np.clip((tau - tds) / np.maximum(T - tds, 1e-9), 0, 1)
        lat = s["lat_to"][a] + wsw * (s["lat_hs"][a] - s["lat_to"][a])
        f, left = _fwd(psi), _left(psi)
        fwd_d = l1 * np.sin(th) + l2 * np.sin(th - kn)
        down = l1 * np.cos(th) + l2 * np.cos(th - kn)
        drop = np.sqrt(np.maximum(down**2 - lat**2, 0.0))
        ankle_sw = hip_b + fwd_d[:, None] * f + lat[:, None] * left
        ankle_sw[:, 2] -= drop
        swinging = tau > tds
        yaw_sw = yaw_tr + wsw * _wrap(s["yaw_land"][a] - yaw_tr)
        # in the second half of the swing the heel never goes below the landing height
        heel_sw = ankle_sw[:, 2] + _foot_offsets(b, fp, yaw_sw)[:, 0, 2]
        ankle_sw[:, 2] += np.where(wsw > 0.5, np.maximum(s["z_land"][a] - heel_sw, 0.0), 0.0)
        ankle_b = np.where(swinging[:, None], ankle_sw, ankle_tr)
        pitch_b = np.where(swinging, fp, p_tr)
        yaw_b = np.where(swinging, yaw_sw, yaw_tr)
        foot_b = _foot_offsets(b, pitch_b, yaw_b) + ankle_b[:, None, :]
        return dict(tau=tau, psi=psi, r_p=r_p, root=root, hip_a=hip_a, hip_b=hip_b,
                    ankle_a=ankle_a, ankle_b=ankle_b, pitch_a=pitch_a, pitch_b=pitch_b,
                    yaw_a=yaw_st, yaw_b=yaw_b, foot_b=foot_b, rho=rho, disp=disp,
                    swinging=swinging, contact_b=~swinging)

    def pose(self, t: float, agents: np.ndarray | None = None):
        """Poses (:class:`crowdwalk.gait.animator.PoseFrame`) of ``agents`` at ``t`` [s]."""
        from crowdwalk.gait.animator import PoseFrame

        n = len(self.body)
        a = np.arange(n) if agents is None else np.atleast_1d(np.asarray(agents))
        if not np.all(self._commanded[a]):
            raise invalid("KlawEngine", "agents", "agents that received a step",
                          a[~self._commanded[a]][:5])
        s, b = self._s, self.body.take(a)
        k = a.size
        g = self._legs(a, np.full(k, float(t)))
        side = s["side"][a]
        left_stance = side > 0
        l1, l2 = b.thigh, b.shank
        W = np.broadcast_to(np.eye(3), (k, len(JOINT_NAMES), 3, 3)).copy()
        W[:, 0] = W[:, 1] = g["r_p"]
        on_ball = {"a": g["pitch_a"] < 0, "b": (g["pitch_b"] < 0) & g["contact_b"]}
        for leg in ("a", "b"):
            hip, ankle, pitch, yaw = (g[f"{q}_{leg}"] for q in ("hip", "ankle", "pitch", "yaw"))
            fwd = _fwd(yaw)
            knee = two_link_knee(hip, ankle, l1, l2, fwd)
            foot = rotation_z(yaw) @ rotation_y(-pitch)
            # toes flat on the ground while the foot stands on its ball, else in line
            toe = np.where(on_ball[leg][:, None, None], rotation_z(yaw), foot)
            is_left = left_stance if leg == "a" else ~left_stance
            for side_name, mask in (("l", is_left), ("r", ~is_left)):
                rows = np.flatnonzero(mask)
                j = {name: JOINT[f"{side_name}_{name}"] for name in (
                    "hip", "knee", "talocrural", "subtalar", "metatarsal")}
                W[rows, j["hip"]] = _segment_frame(knee[rows] - hip[rows], fwd[rows])
                W[rows, j["knee"]] = _segment_frame(ankle[rows] - knee[rows], fwd[rows])
                W[rows, j["talocrural"]] = W[rows, j["subtalar"]] = foot[rows]
                W[rows, j["metatarsal"]] = toe[rows]
        # upper body: trunk tilt and sway, shoulders against the pelvis, arms
        psi = g["psi"]
        sway = -side * s["sway"][a] * g["disp"]
        shoulder = side * s["shoulder"][a] * g["rho"]
        trunk = rotation_z(psi + shoulder) @ rotation_x(sway) @ rotation_y(s["tilt"][a])
        W[:, JOINT["vl5"]] = trunk
        W[:, JOINT["skullbase"]] = rotation_z(psi)
        swing_of = self._arm_signal(a, g)
        for side_name, sign in (("l", 1.0), ("r", -1.0)):
            sig = swing_of[side_name]
            alpha = s["arm"][a] * sig
            elbow = s["elbow_min"][a] + (s["elbow_max"][a] - s["elbow_min"][a]) * 0.5 * (sig + 1)
            upper = rotation_z(psi + shoulder) @ rotation_x(sign * s["arm_out"][a]) \
                @ rotation_y(-alpha)
            W[:, JOINT[f"{side_name}_shoulder"]] = upper
            W[:, JOINT[f"{side_name}_elbow"]] = W[:, JOINT[f"{side_name}_wrist"]] = \
                upper @ rotation_y(-elbow)
        local = np.einsum("kjba,kjbc->kjac", W[:, np.maximum(PARENTS, 0)], W)
        local[:, 0] = g["r_p"]
        positions, _ = forward_kinematics(b, g["root"], g["r_p"], local)
        contact = np.zeros((k, 2), bool)
        rows = np.arange(k)
        contact[rows, np.where(left_stance, 0, 1)] = True
        contact[rows, np.where(left_stance, 1, 0)] = g["contact_b"]
        ok = np.isfinite(positions).all(axis=(1, 2)) & np.isfinite(local).all(axis=(1, 2, 3))
        self.stats["poses"] += k
        quats = matrix_to_quaternion(local)
        return PoseFrame(agents=a, time=float(t), root_position=g["root"],
                         root_quaternion=quats[:, 0].copy(), joints=quats, positions=positions,
                         contact=contact, fallback=~ok, stance_left=left_stance)

    def _arm_signal(self, a, g):
        """Arm swing signal in [-1, 1] per side (+1 forward): the opposite leg's virtual-leg
        angle between its angles at toe-off (−1) and heel strike (+1) (§2.2: the arm
        swings forward with the opposite leg)."""
        s = self._s
        f = _fwd(g["psi"])
        front, rear = s["front"][a], np.minimum(s["rear"][a], s["front"][a] - 1e-3)
        ang = {}
        for leg in ("a", "b"):
            rel = g[f"ankle_{leg}"] - g[f"hip_{leg}"]
            angle = np.arctan2(_dot(rel, f), -rel[:, 2])
            ang[leg] = np.clip(2.0 * (angle - rear) / (front - rear) - 1.0, -1.0, 1.0)
        left_stance = s["side"][a] > 0
        left_leg = np.where(left_stance, ang["a"], ang["b"])
        right_leg = np.where(left_stance, ang["b"], ang["a"])
        return {"l": right_leg, "r": left_leg}
