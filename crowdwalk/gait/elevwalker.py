"""ElevWalker: full-body poses from sagittal elevation angles (Sun & Metaxas 2001, §4, §8).

Per frame and agent, given the stance leg's elevation angles at ``t`` and the swing leg's
at ``t + 0.5`` (columns foot, shank, thigh, pelvis, :mod:`crowdwalk.gait.datasets`):

1. **Root from the foot–floor interaction model (§4.1).** The stance foot rotates about
   its instantaneous contact point until its elevation equals the data: about the heel
   while the foot is pitched up relative to the ground, about the first metatarsal head
   (ball) once the heel rises; then the toe joint takes the foot elevation and the toes
   stay flat. Heel and ball points are fixed in the world for the whole step, so the foot
   never slides, and both lie on the ground plane, so it never penetrates.
2. **Stance ankle complex (§4.3, Eq. 8).** Talocrural and subtalar angles (skew Inman
   axes, :mod:`crowdwalk.body`) from two constraints — the shank elevation and the
   stance width — by Gauss–Newton warm-started from the previous frame. The
   stance knee inside it is the analytic single-DOF solve (§4.2, Eqs. 2–7).
3. **Hip complex (§4.3).** The pelvis takes the (exact) data pelvis elevation, the pelvic
   list ``L(t)`` and the heading; the stance hip's 3 DOFs follow in closed form. The
   swing hip's 3 DOFs solve thigh elevation, swing width and toe-out by Gauss–Newton.
   Swing knee and swing talocrural joint: analytic single-DOF solves.
4. **Curved locomotion (§4.4)** through the sagittal-plane heading ψ, per agent.
5. **Upper body (§8).** Arms swing with the opposite thigh; the spine cancels pelvic
   tilt, list and rotation so trunk and head stay upright and face the heading.

Optionally the swing ankle is pulled toward a target with IK on the swing leg (the
Animator's landing correction and swing-clearance blend, issue item 6).

Everything is batched over agents: the two Gauss–Newton solves run per agent in the
compiled kernels of :mod:`crowdwalk.gait.complexes`, the swing IK, swing foot and joint
rotations in :mod:`crowdwalk.gait.joints`.
Conventions: world x east, y north, z up; ψ from +x; angles [rad]; lengths [m].
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from crowdwalk.body import (
    JOINT,
    JOINT_NAMES,
    LEG_JOINTS,
    PARENTS,
    SUBTALAR_AXIS,
    TALOCRURAL_AXIS,
    Body,
    _forward_kinematics,
    mirrored_axis,
)
from crowdwalk.errors import invalid
from crowdwalk.gait import elevwalker_kernels as ek
from crowdwalk.gait.complexes import MIN_POSE_ROWS, solve_stance_ankle, solve_swing_hip
from crowdwalk.gait.foot import StanceFoot, foot_points, mat_vec, stance_foot_pose
from crowdwalk.gait.foot import wrap_angle as _wrap
from crowdwalk.gait.joints import _assemble, assemble_arguments
from crowdwalk.gait.posing_kernels import (
    as_rows,
    rows_finite,
)
from crowdwalk.workers import row_threads

__all__ = [
    "GaitStyle",
    "StanceFoot",
    "StanceHalf",
    "WarmStart",
    "WalkerPose",
    "elevwalker_pose",
    "sagittal_elevation",
    "solve_single_dof",
    "leg_elevations",
    "foot_points",
    "joint_flexion",
    "walk_cycle",
    "pelvis_shapes",
]

# Skew ankle axes per side (row 0 left, row 1 right), unit vectors in the parent frame.
_TC_AXES = np.stack([TALOCRURAL_AXIS, mirrored_axis(TALOCRURAL_AXIS)])
_SUB_AXES = np.stack([SUBTALAR_AXIS, mirrored_axis(SUBTALAR_AXIS)])
_SHOULDERS = np.array([JOINT["l_shoulder"], JOINT["r_shoulder"]])
_ELBOWS = np.array([JOINT["l_elbow"], JOINT["r_elbow"]])


def _vector(values, k: int) -> np.ndarray:
    """``values`` (scalar or (k,)) as a contiguous float (k,) array for the kernels."""
    return as_rows(values, (k,))


def _rows(values, k: int, dtype) -> np.ndarray:
    """``values`` (scalar or (k,)) as a contiguous (k,) array of ``dtype``."""
    return np.ascontiguousarray(np.broadcast_to(np.asarray(values, dtype=dtype), (k,)))


@dataclass(frozen=True)
class GaitStyle:
    """Procedural gait parameters that the sagittal data leave open (§4.3, §8).

    Attributes
    ----------
    step_width : float
        Lateral distance between the left and right ankle lines, fraction of body height
        [1] (0.05 H ≈ 9 cm for 1.75 m; adult stride width 8–10 cm, Gouelle normals).
    sway : float
        Amplitude of the pelvis's lateral sway toward the stance foot, fraction of body
        height [1] (COM sway ≈ ±2 cm at natural speed).
    pelvic_list : float
        Amplitude of pelvic list L(t), swing side down [rad] (Bovi 2011: ≈ ±4°).
    toe_out : float
        Default toe-out O(t) of the feet [rad] (foot progression angle 5–10°).
    arm_swing : float
        Upper-arm elevation per unit of the opposite thigh's elevation [1] (§8).
    elbow_flexion : float
        Elbow flexion at arm's neutral [rad]; half the forward arm swing is added.
    tolerance : float
        Gauss–Newton convergence threshold on the residuals [rad or m].
    max_iterations : int
        Gauss–Newton iterations before a solve counts as not converged.
    toe_clearance : float
        Least height of the swing sole over level ground in the middle of the swing [m]
        (Winter 1992: minimum toe clearance 1.29 ± 0.45 cm).
    level_clearance : bool
        The Animator lifts the data's swing sole to ``toe_clearance`` over level ground
        (an extension, docs/architecture.md "Level steps"); False: the data's swing.
    pelvis_from_data : bool
        Pelvic list L(t) and the pelvis's transverse rotation follow the measured curves
        of Bovi 2011 (adult natural walking, :func:`~crowdwalk.gait.datasets.pelvis_motion`;
        list greatest in loading response, level again by mid-stance), scaled by the
        amplitudes ``pelvic_list`` / the style's ``pelvic_rotation``; False: L(t) =
        amplitude · sin 2πt and rotation = amplitude · cos 2πt.
    trunk_from_data : bool
        With KLAW attributes, the trunk's counter-rotation follows Schwartz 2008's
        measured thorax rotation (scaled by ``shoulder_rotation``) and its forward tilt
        carries the measured wave about ``torso_tilt``
        (:func:`~crowdwalk.gait.datasets.trunk_motion`); False: ``shoulder_rotation`` ·
        cos 2πt and a constant tilt.
    trailing_root : bool
        In the double support that opens a level step the root's progress along ψ follows
        the trailing leg (pinned on its ball) and hands over to the new stance leg by
        toe-off, so the forward velocity is continuous at the heel strike (an extension of
        §4.1, docs/architecture.md "Root velocity at the heel strike"); False: the root
        follows the new stance foot from the heel strike on (§4.1), joined C⁰.
    lift_swing : bool
        Over uneven ground (stairs, curbs) the Animator's swing follows the data, raised
        where the sole would come below ``toe_clearance`` over the ground by the
        anticipated lift (an extension: docs/architecture.md "Stair swing from the
        data"); False: where the data's sole comes within 2 mm of the ground the ankle
        follows the planner's swing Bezier (Chen & Li §5.2: its control points 15 cm
        above the chord), which flexed the ascending swing knee to 110–115°.
    step_crossfade : bool
        The Animator plays each step as a crossfade from the previous step's dataset (at
        the heel strike that opens it) to the step's own (at the heel strike that ends
        it), so both legs follow data whose Eq. 10 step is the one the feet span at each
        end, and the angles are C¹ across the swap (an extension: the paper does not say
        how datasets join; docs/architecture.md "Step crossfade"); False: the step's
        dataset from its heel strike on, the root joined by an offset blended out over
        half the step.
    clamped_join : bool
        After a step ElevInterp served clamped (outside its legal region: the landing was
        pulled onto the target by the swing IK, 10–30 cm on the park's short steps) the
        root's join offset is blended out over the whole step instead of its first half
        (an extension: docs/architecture.md "Step crossfade"); False: half the step.
    toe_off_c1 : bool
        At toe-off the swing ankle's offset starts with the horizontal velocity the
        pinned push-off ankle has and the data's swing ankle lacks, less 2 m/s and at
        most what 25 m/s² carries over 0.7 of the swing, and is gone at rest by then
        (an extension: docs/architecture.md "Toe-off hand-over"); False: C⁰ only, the
        ankle jumps to the data's velocity (1.2–1.8 m/s faster at level walkers, up to
        3.4 m/s on the uneven park's short steps).
    pin_ball : bool
        The pinned push-off ankle's goal is corrected until the trailing foot's ball is
        where the pin put it (a turned foot rolls about the skew talocrural axis and its
        ball slid up to 19 mm at the corner; an extension: docs/architecture.md "Toe-off
        hand-over"); False: the goal as the pin computes it.
    data_toe_off : bool
        Where ``toe_off_c1``'s hand-over cannot carry the toe-off jump, on steps shorter
        than 0.75 leg lengths off stairs, the trailing foot is let go no later than where
        the step's own (blended) data have lifted its swing sole 3.5 cm above where it
        starts the step (an extension: docs/architecture.md "Toe-off where the data lift
        the foot"); False (default): at 2 (stance fraction − 0.5) of the step.
    stop_settle : bool
        A walker whose step ends without a next one (it stops: a queue, a wait) carries
        its root on from the heel strike and brings it to rest at a constant deceleration
        over 0.2 s, both feet planted; its next step joins the root C¹ from there (an
        extension: docs/architecture.md "Stop settle"); False (default): the pose freezes
        at the heel strike (the root stops dead in one frame) and the next step joins C⁰.
        Off by default: the corner's stops go 7.1 → 2.2 cm of pelvis second difference,
        but the crowds' worsts rise (bottleneck heel-down turn 37.5 → 73.8°, foot
        elsewhere 52 → 84 cm, fallbacks 139 → 166; quickstart foot elsewhere 18.3 →
        29.8 cm).
    restart_c1 : bool
        Without ``stop_settle``: a walker's step that starts after it stood (a restart in
        a queue) joins the root C¹ from rest, as stair steps join (the frozen pose's root
        stood still; the data's root velocity at the heel strike is blended in over half
        the step rather than taken at once) (an extension: docs/architecture.md "Restart
        from rest"); False (default): the C⁰ join.
    exact_hip_offset : bool
        The stance hip's offset (``stance_hip_offset``) is reached in 3-D: its sagittal
        two-link IK is exact only for a leg in the plane of ψ, and with the stance foot
        turned ~50° from ψ (a turn after a stand) the hip moved 4.4 times the requested
        drop (docs/architecture.md, gait22's section). The offset passed to the IK is
        corrected by secants per component (along ψ, vertical), four stance solves more,
        faded in (smoothstep) as the first solve misses by 0.5 → 2 cm; False (default):
        one IK.
    """

    step_width: float = 0.05
    sway: float = 0.012
    pelvic_list: float = float(np.deg2rad(4.0))
    toe_out: float = float(np.deg2rad(7.0))
    arm_swing: float = 0.75
    elbow_flexion: float = float(np.deg2rad(20.0))
    tolerance: float = 1e-6
    max_iterations: int = 12
    toe_clearance: float = 0.013
    level_clearance: bool = True
    pelvis_from_data: bool = True
    trunk_from_data: bool = True
    trailing_root: bool = True
    lift_swing: bool = True
    step_crossfade: bool = True
    clamped_join: bool = True
    toe_off_c1: bool = True
    pin_ball: bool = True
    data_toe_off: bool = False
    stop_settle: bool = False
    restart_c1: bool = False
    exact_hip_offset: bool = False

    def __post_init__(self) -> None:
        for name in ("step_width", "sway", "pelvic_list", "arm_swing", "elbow_flexion"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise invalid("GaitStyle", name, "finite and >= 0", value)
        if not (np.isfinite(self.toe_out) and abs(self.toe_out) < np.pi / 3):
            raise invalid("GaitStyle", "toe_out", "finite and in (-60°, 60°) [rad]", self.toe_out)
        if not (np.isfinite(self.tolerance) and self.tolerance > 0):
            raise invalid("GaitStyle", "tolerance", "finite and > 0", self.tolerance)
        if not self.max_iterations >= 1:
            raise invalid("GaitStyle", "max_iterations", ">= 1", self.max_iterations)


@dataclass(frozen=True, eq=False)
class WarmStart:
    """Gauss–Newton starting points: stance ankle (k, 2) [rad] (talocrural, subtalar) and
    swing hip (k, 3) [rad] (intrinsic Y-X-Z Euler angles of the hip's local rotation), and
    optionally the previous frame's Jacobians (k, 2, 2) and (k, 3, 3) (NaN: none)."""

    ankle: np.ndarray
    hip: np.ndarray
    ankle_jacobian: np.ndarray | None = None
    hip_jacobian: np.ndarray | None = None

    @classmethod
    def neutral(cls, k: int) -> WarmStart:
        """Zero angles for k agents."""
        return cls(np.zeros((k, 2)), np.zeros((k, 3)))


@dataclass(frozen=True, eq=False)
class StanceHalf:
    """What :func:`elevwalker_pose` solves for k agents before the swing leg: the stance
    leg, pelvis and root, which the swing leg's toe-out and ankle goal do not change.

    Attributes
    ----------
    side : (k,) +1 where the left leg is the stance leg, else −1.
    normal : (k, 3) sagittal-plane normal (left).
    w_swing : (k,) required swing width [m].
    phi_st : (k, 4) stance elevations followed [rad] (shank and thigh moved by the
        stance hip's offset).
    r_pelvis : (k, 3, 3); root, hip_sw : (k, 3) [m].
    x_ankle, ok_ankle, jac_ankle : the stance ankle solve, (k, 2) [rad], (k,), (k, 2, 2).
    knee_rel, ok_knee_st : (k,) stance knee [rad] and whether it was solvable.
    r_thigh_st : (k, 3, 3); toe_angle : (k,) stance toe angle [rad].
    """

    side: np.ndarray
    normal: np.ndarray
    w_swing: np.ndarray
    phi_st: np.ndarray
    r_pelvis: np.ndarray
    root: np.ndarray
    hip_sw: np.ndarray
    x_ankle: np.ndarray
    ok_ankle: np.ndarray
    jac_ankle: np.ndarray
    knee_rel: np.ndarray
    ok_knee_st: np.ndarray
    r_thigh_st: np.ndarray
    toe_angle: np.ndarray

    def take(self, rows: np.ndarray) -> StanceHalf:
        """The agents at ``rows`` (m,)."""
        return StanceHalf(**{f.name: getattr(self, f.name)[rows] for f in fields(self)})


@dataclass(frozen=True, eq=False)
class WalkerPose:
    """ElevWalker output for k agents.

    Attributes
    ----------
    root_position : (k, 3) ``HumanoidRoot`` (mid-hip) world position [m].
    root_rotation : (k, 3, 3) pelvis world orientation.
    local : (k, J, 3, 3) local joint rotations (entry 0 = ``root_rotation``).
    positions : (k, J, 3) joint world positions [m].
    rotations : (k, J, 3, 3) world orientation of the segment distal to each joint.
    contact : (k, 2) bool, left/right foot on the ground.
    converged : (k,) bool, every analytic and Gauss–Newton solve succeeded.
    warm : WarmStart for the next frame.
    solves : (k, 5) bool, which solve succeeded: stance ankle GN, swing hip GN, stance
        knee, swing knee, swing talocrural (analytic).
    stance : StanceHalf, the stance half of the pose (for a pose of the same agents at the
        same phases that changes only the swing's inputs).
    """

    root_position: np.ndarray
    root_rotation: np.ndarray
    local: np.ndarray
    positions: np.ndarray
    rotations: np.ndarray
    contact: np.ndarray
    converged: np.ndarray
    warm: WarmStart
    solves: np.ndarray | None = None
    stance: StanceHalf | None = None


# --- geometry helpers -------------------------------------------------------------------


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ka,ka->k", a, b)


def sagittal_elevation(v: np.ndarray, heading: np.ndarray) -> np.ndarray:
    """Sagittal elevation angle of segment vectors (Eq. 1) [rad].

    Parameters
    ----------
    v : numpy.ndarray
        (k, 3) proximal→distal vectors, world frame.
    heading : numpy.ndarray
        (k,) sagittal-plane orientation ψ [rad].

    Returns
    -------
    numpy.ndarray
        (k,) angle from the downward vertical of the projection of ``v`` onto the sagittal
        plane, positive when the distal end is anterior.
    """
    fwd = v[:, 0] * np.cos(heading) + v[:, 1] * np.sin(heading)
    return np.arctan2(fwd, -v[:, 2])


_DOF_BASES: dict[bytes, np.ndarray] = {}


def _dof_basis(axis: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Columns (w − (a·w)a, a × w, (a·w)a) (3, 3) of a constant axis a and segment w."""
    key = axis.tobytes() + w.tobytes()
    basis = _DOF_BASES.get(key)
    if basis is None:
        qw = float(axis @ w)
        basis = np.stack([w - axis * qw, np.cross(axis, w), axis * qw], axis=1)
        basis.flags.writeable = False
        if len(_DOF_BASES) < 64:
            _DOF_BASES[key] = basis
    return basis


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of (k, 3) arrays (``np.cross``'s formula, less overhead)."""
    a0, a1, a2 = a[:, 0], a[:, 1], a[:, 2]
    b0, b1, b2 = b[:, 0], b[:, 1], b[:, 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=1)


def solve_single_dof(
    parent: np.ndarray, axis: np.ndarray, w: np.ndarray, heading: np.ndarray, phi: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Joint angle θ that gives a segment the sagittal elevation φ (§4.2, Eqs. 2–7).

    The segment direction is ``v(θ) = parent @ Rot(axis, θ) @ w``. Splitting ``w`` into
    its components along and around the (possibly skew) axis gives the circle of Eq. 2,
    ``v = d cos θ + e sin θ + f``; the elevation constraint (Eq. 3), multiplied by cos φ to
    stay finite at φ = ±90°, is ``A cos θ + B sin θ + C = 0`` with Eqs. 5–7's A, B, C.
    Of its two roots one gives φ and the other φ + π (the "−φ" of the paper); the one
    whose projected direction agrees with φ is returned.

    Parameters
    ----------
    parent : (k, 3, 3) world orientation of the joint's parent frame.
    axis : (3,) or (k, 3) unit joint axis in the parent frame.
    w : (3,) or (k, 3) segment direction in the child frame at θ = 0.
    heading : (k,) sagittal-plane orientation ψ [rad].
    phi : (k,) required elevation angle [rad].

    Returns
    -------
    theta : (k,) joint angle [rad] in (-π, π].
    ok : (k,) bool, False when no θ reaches φ (the closest angle is returned).
    """
    k = parent.shape[0]
    axis = np.asarray(axis, dtype=float)
    w = np.asarray(w, dtype=float)
    if axis.ndim == 1 and w.ndim == 1:
        # constant axis and segment: split w once (cached), one batched product for d, e, f
        d, e, f = (parent @ _dof_basis(axis, w)).transpose(2, 0, 1)
    else:
        axis = np.broadcast_to(axis, (k, 3))
        w = np.broadcast_to(w, (k, 3))
        qw = _dot(axis, w)
        wc = w - axis * qw[:, None]
        ws = _cross(axis, w)
        wq = axis * qw[:, None]
        d, e, f = mat_vec(parent, wc), mat_vec(parent, ws), mat_vec(parent, wq)
    ch, sh = np.cos(heading), np.sin(heading)
    cphi, sphi = np.cos(phi), np.sin(phi)
    # horizontal (along ψ) and vertical components of d, e, f
    hd, he, hf = (u[:, 0] * ch + u[:, 1] * sh for u in (d, e, f))
    A, B, C = hd * cphi + d[:, 2] * sphi, he * cphi + e[:, 2] * sphi, hf * cphi + f[:, 2] * sphi
    R = np.hypot(A, B)
    ratio = -C / np.where(R > 1e-12, R, 1e-12)
    ok = (np.abs(ratio) <= 1.0) & (R > 1e-12)
    base = np.arctan2(B, A)
    delta = np.arccos(np.clip(ratio, -1.0, 1.0))
    best = np.empty(k)
    score = np.full(k, -np.inf)
    for cand in (base + delta, base - delta):
        c, s = np.cos(cand), np.sin(cand)
        # v · (unit vector at φ) of v = d cos θ + e sin θ + f
        g = (hd * c + he * s + hf) * sphi - (d[:, 2] * c + e[:, 2] * s + f[:, 2]) * cphi
        better = g > score
        best = np.where(better, cand, best)
        score = np.where(better, g, score)
    return _wrap(best), ok & (score > 1e-6)  # a vanishing projection has no elevation


# --- the walker -------------------------------------------------------------------------


def elevwalker_pose(
    body: Body,
    stance_left: np.ndarray,
    phase: np.ndarray,
    stance_angles: np.ndarray,
    swing_angles: np.ndarray,
    heading: np.ndarray,
    foot: StanceFoot,
    toe_out: np.ndarray,
    warm: WarmStart,
    style: GaitStyle | None = None,
    stance_fraction: np.ndarray | float = 0.6,
    swing_offset: np.ndarray | None = None,
    swing_target: np.ndarray | None = None,
    swing_blend: np.ndarray | None = None,
    stance_hip_offset: np.ndarray | None = None,
    swing_goal: np.ndarray | None = None,
    swing_toe_angle: np.ndarray | None = None,
    attributes=None,
    list_scale: np.ndarray | None = None,
    stance: StanceHalf | None = None,
) -> WalkerPose:
    """Full-body poses of k walkers for one frame (§4, §8).

    Parameters
    ----------
    body : Body
        k bodies.
    stance_left : (k,) bool
        True where the left foot is the stance foot.
    phase : (k,) normalised stride time t ∈ [0, 0.5) of the stance leg [1].
    stance_angles, swing_angles : (k, 4)
        Elevation angles [rad] (foot, shank, thigh, pelvis) of the stance leg at ``t`` and
        the swing leg at ``t + 0.5``.
    heading : (k,) sagittal-plane orientation ψ [rad].
    foot : StanceFoot
        Stance-foot ground contact.
    toe_out : (k,) swing-leg toe-out O(t), positive outward [rad].
    warm : WarmStart
        Previous frame's Gauss–Newton solutions.
    style : GaitStyle, optional
    stance_fraction : float or (k,)
        Stance phase of the data [1] (for the swing foot's contact flag in double support).
    swing_offset : (k, 3), optional
        Displacement added to the data-driven swing ankle [m].
    swing_target : (k, 3), optional
        World position the (displaced) swing ankle is blended toward [m].
    swing_blend : (k,), optional
        Weight of ``swing_target`` in [0, 1]. Where the offset or the blend is non-zero
        the swing leg reaches the resulting ankle goal by two-link IK.
    stance_hip_offset : (k, 3), optional
        Displacement of the stance hip from where the data put it [m]: the stance shank
        and thigh elevations are replaced by a sagittal two-link IK solution and the
        stance width shifted (the Animator uses it to keep the root continuous when the
        legs swap roles).
    swing_goal : (k, 3), optional
        Absolute swing-ankle goal [m] overriding the above where finite (NaN rows: none);
        the Animator pins the trailing foot with it during push-off.
    swing_toe_angle : (k,), optional
        Swing-foot toe (metatarsal) angle [rad] where finite; default: toes bent to lie
        flat at the swing leg's t = 0.5, straightening by toe-off.
    attributes : crowdwalk.style.Style, optional
        The k walkers' KLAW attributes (:func:`styled`); None: ``style`` alone.
    list_scale : (k,), optional
        Factor [1] on the pelvic list (the Animator starts a walk from a level pelvis).
    stance : StanceHalf, optional
        The stance half of a pose of these agents with the same arguments but the swing's
        (``toe_out``, ``swing_offset``, ``swing_target``, ``swing_blend``, ``swing_goal``,
        ``swing_toe_angle``): taken instead of solved again (the same values).

    Returns
    -------
    WalkerPose
    """
    style = style or GaitStyle()
    k = len(body)
    left = _rows(stance_left, k, bool)
    st_row = np.where(left, 0, 1)
    sw_row = 1 - st_row
    heading = _vector(heading, k)
    phase = _vector(phase, k)
    phi_st = as_rows(stance_angles, (k, 4))
    phi_sw = as_rows(swing_angles, (k, 4))
    toe_out = np.broadcast_to(np.asarray(toe_out, dtype=float), (k,))
    tc_axis, sub_axis = _TC_AXES[st_row], _SUB_AXES[st_row]
    if stance is None:
        stance = _stance_half(body, left, phase, heading, phi_st, phi_sw, foot, warm, style,
                              stance_hip_offset, attributes, list_scale, tc_axis, sub_axis)
    # steps 1-3 but the swing hip's solve: the stance half (_stance_half)
    side_st, normal, phi_st, r_pelvis = stance.side, stance.normal, stance.phi_st, stance.r_pelvis
    hip_sw = stance.hip_sw
    # 3. (cont.) The swing hip's 3 DOFs: thigh elevation, swing width and toe-out (GN).
    x_hip, ok_hip, jac_hip, r_thigh_sw, knee_sw, ok_knee_sw, r_shank_sw, ankle_sw = (
        solve_swing_hip(r_pelvis, hip_sw, body.thigh, body.shank, heading, phi_sw[:, 1],
                        phi_sw[:, 2], normal, -side_st, toe_out, stance.w_swing, warm.hip,
                        warm.hip_jacobian, style.tolerance, style.max_iterations)
    )  # fmt: skip
    # Optional swing-ankle goal, reached with two-link IK on the swing leg (compiled:
    # ek.swing_goal).
    goal = use = None
    blended = swing_target is not None and swing_blend is not None
    if swing_offset is not None or swing_goal is not None or blended:
        none3 = np.zeros((k, 3))
        goal, use = ek.swing_goal(
            ankle_sw, none3 if swing_offset is None else as_rows(swing_offset, (k, 3)),
            swing_offset is not None, as_rows(swing_target, (k, 3)) if blended else none3,
            _vector(swing_blend, k) if blended else np.zeros(k), blended,
            none3 if swing_goal is None else as_rows(swing_goal, (k, 3)),
            swing_goal is not None)  # fmt: skip

    # Swing IK, swing talocrural (analytic for the data foot elevation; the swing subtalar
    # stays neutral), push-off toes flat on the ground (double support), every joint's
    # local rotation, upper body (§8: trunk upright along ψ, arms with the opposite
    # thigh) — compiled, per agent.
    # Then the KLAW upper body and forward kinematics (both compiled): the three on parts
    # of the rows at once (_joint_rows; each row's values its own)
    toe_given = np.nan if swing_toe_angle is None else swing_toe_angle
    args = assemble_arguments(
        left, phase, heading, stance_fraction, r_pelvis, stance.r_thigh_st, stance.knee_rel,
        tc_axis, sub_axis, stance.x_ankle, stance.toe_angle, hip_sw, r_thigh_sw, knee_sw,
        r_shank_sw, _TC_AXES[sw_row], phi_sw, phi_st, body.thigh, body.shank, use, goal, toe_given,
        style.arm_swing, style.elbow_flexion, len(JOINT_NAMES),
    )  # fmt: skip
    upper = [] if attributes is None else _upper_body_arguments(
        k, r_pelvis, heading, phase, left, side_st, phi_st, phi_sw, attributes, style)
    kinematics = [body.offsets(), np.ascontiguousarray(stance.root, dtype=float),
                  np.ascontiguousarray(r_pelvis, dtype=float), PARENTS]
    local, knee_sw, ok_foot_sw, positions, rotations, finite = row_threads().map(
        _joint_rows, k, len(args), len(upper), *args, *upper, *kinematics,
        min_rows=MIN_POSE_ROWS)
    rows = np.arange(k)
    swing_phase = phase + 0.5
    contact = np.empty((k, 2), dtype=bool)
    contact[rows, st_row] = True
    contact[rows, sw_row] = swing_phase < np.asarray(stance_fraction, dtype=float)
    converged = stance.ok_ankle & ok_hip & stance.ok_knee_st & ok_knee_sw & ok_foot_sw
    converged &= finite  # every joint position and rotation finite
    return WalkerPose(
        root_position=stance.root,
        root_rotation=r_pelvis,
        local=local,
        positions=positions,
        rotations=rotations,
        contact=contact,
        converged=converged,
        warm=WarmStart(stance.x_ankle, x_hip, stance.jac_ankle, jac_hip),
        solves=np.stack([stance.ok_ankle, ok_hip, stance.ok_knee_st, ok_knee_sw, ok_foot_sw],
                        axis=1),
        stance=stance,
    )


_EXACT_ROUNDS = 3  # exact_hip_offset's stance solves after the first
_EXACT_RATIO = (0.1, 1.5)  # ... the secants' slopes d(offset)/d(shift) [1]
_EXACT_MISS = (0.005, 0.02)  # ... faded in as the first solve misses by this much [m]


def _stance_half(body: Body, left, phase, heading, phi_st, phi_sw, foot: StanceFoot,
                 warm: WarmStart, style: GaitStyle, stance_hip_offset, attributes, list_scale,
                 tc_axis, sub_axis) -> StanceHalf:
    """:func:`elevwalker_pose`'s stance leg, pelvis and root (steps 1–3 without the swing
    hip): arrays (k,) or (k, 4) as it makes them; the stance axes (k, 3). With
    ``GaitStyle.exact_hip_offset`` the offset given to the stance IK is corrected by
    secants (per component, along ψ and vertical) until the root moves by
    ``stance_hip_offset``, faded in as the first solve misses by 0.5 → 2 cm."""
    args = (body, left, phase, heading, phi_st, phi_sw, foot, warm, style)
    rest = (attributes, list_scale, tc_axis, sub_axis)
    half = _stance_half_once(*args, stance_hip_offset, *rest)
    if not (style.exact_hip_offset and stance_hip_offset is not None):
        return half
    k = len(body)
    want = np.array(as_rows(stance_hip_offset, (k, 3)), dtype=float)
    free = _stance_half_once(*args, None, *rest).root
    axes = np.zeros((k, 2, 3))  # along ψ, vertical
    axes[:, 0, 0], axes[:, 0, 1], axes[:, 1, 2] = np.cos(heading), np.sin(heading), 1.0
    w = np.einsum("kcd,kd->kc", axes, want)
    got = np.einsum("kcd,kd->kc", axes, half.root - free)
    # faded in (smoothstep) as the first solve misses by _EXACT_MISS
    lo, hi = _EXACT_MISS
    x = np.clip((np.linalg.norm(w - got, axis=1) - lo) / (hi - lo), 0.0, 1.0)
    fade = (x * x * (3.0 - 2.0 * x))[:, None]
    turned = fade[:, 0] > 0.0
    if not turned.any():
        return half
    # the first step: the secant through 0 (slope 1 where the shift has the wrong sign),
    # then secants per component
    same = (w * got > 0.0) & (np.abs(got) > 1e-6)
    slope = np.where(same, np.clip(w / np.where(same, got, 1.0), *_EXACT_RATIO), 1.0)
    u_prev, g_prev = w.copy(), got
    best, miss = half, np.linalg.norm(w - got, axis=1)
    u = w + fade * slope * (w - got)
    for i in range(_EXACT_ROUNDS):
        used = want + np.einsum("kc,kcd->kd", u - w, axes)
        half = _stance_half_once(*args, used, *rest)
        got = np.einsum("kcd,kd->kc", axes, half.root - free)
        # each row keeps the solve that missed least (a secant can overshoot)
        m = np.linalg.norm(w - got, axis=1)
        better = turned & half.ok_ankle & (m < miss)
        best, miss = _rows_of(better, half, best), np.where(better, m, miss)
        if i + 1 == _EXACT_ROUNDS:
            break
        dg, du = got - g_prev, u - u_prev
        slope = np.where(np.abs(dg) > 1e-6, du / np.where(np.abs(dg) > 1e-6, dg, 1.0), 1.0)
        slope = np.clip(slope, *_EXACT_RATIO)
        u_prev, g_prev = u, got
        u = u + fade * slope * (w - got)
    return best


def _rows_of(rows: np.ndarray, a: StanceHalf, b: StanceHalf) -> StanceHalf:
    """The stance half with ``a``'s values at ``rows`` (k,) bool and ``b``'s elsewhere."""
    return StanceHalf(**{f.name: np.where(
        rows.reshape((-1,) + (1,) * (getattr(a, f.name).ndim - 1)),
        getattr(a, f.name), getattr(b, f.name)) for f in fields(a)})


def _stance_half_once(body: Body, left, phase, heading, phi_st, phi_sw, foot: StanceFoot,
                      warm: WarmStart, style: GaitStyle, stance_hip_offset, attributes,
                      list_scale, tc_axis, sub_axis) -> StanceHalf:
    """One solve of :func:`_stance_half` with the stance hip offset as given."""
    k = len(body)
    h = body.height
    list_shape, rotation_shape = pelvis_shapes(style, phase)
    styled = attributes is not None
    width = style.step_width * h if attributes is None else attributes.stride_width
    list_amplitude = style.pelvic_list if attributes is None else attributes.pelvic_list
    # compiled (elevwalker_kernels.stance_terms): the side, Eq. 8's W_st(t) = (a - h)·n and
    # the swing width, the sway, the pelvis's list and rotation, KLAW's bounce dip added
    # to the stance hip's offset, the stance leg moved by it (shifted_stance_leg); the
    # trigonometric terms numpy's
    shifted = stance_hip_offset is not None
    zeros, hips = np.zeros(k), _vector(body.hip_separation, k)
    side_st, normal, w_stance, w_swing, phi_st, lst, yaw, tilt_data = ek.stance_terms(
        left, _vector(h, k), hips, _vector(width, k),
        float(style.sway), np.sin(2.0 * np.pi * phase), _vector(list_amplitude, k),
        _vector(list_shape, k), zeros if list_scale is None else _vector(list_scale, k),
        list_scale is not None, _vector(attributes.pelvic_rotation, k) if styled else zeros,
        _vector(rotation_shape, k), styled,
        _vector(attributes.bounciness, k) if styled else zeros, BOUNCE_DIP,
        np.cos(4.0 * np.pi * (phase - BOUNCE_LOW)) if styled else zeros, heading,
        np.cos(heading), np.sin(heading), phi_st, phi_sw, _vector(body.thigh, k),
        _vector(body.shank, k), as_rows(stance_hip_offset, (k, 3)) if shifted
        else np.zeros((k, 3)), shifted)  # fmt: skip

    # 1. Foot–floor interaction (§4.1). The foot's own pitch p gives the data elevation
    #    in the sagittal plane of ψ: tan φ = tan p / cos(yaw − ψ).
    pitch = np.arctan(np.tan(phi_st[:, 0]) * np.cos(foot.yaw - heading))
    r_foot, ankle, toe_angle = stance_foot_pose(body, foot, pitch)

    # 2. Stance ankle complex (§4.3, Eq. 8) with the analytic stance knee inside.
    x_ankle, ok_ankle, jac_ankle, r_shank_st, knee_rel, ok_knee_st, r_thigh_st, hip_st = (
        solve_stance_ankle(r_foot, ankle, tc_axis, sub_axis, body.shank, body.thigh, heading,
                           phi_st[:, 1], phi_st[:, 2], normal, w_stance, warm.ankle,
                           warm.ankle_jacobian, style.tolerance, style.max_iterations)
    )  # fmt: skip

    # 3. Hip complex: pelvis from data tilt (exact under list), list and heading; root and
    #    swing hip half the hip separation along its y axis (compiled: ek.pelvis_hips).
    tilt = np.arctan(np.tan(tilt_data) * np.cos(lst))
    r_pelvis, root, hip_sw = ek.pelvis_hips(yaw, lst, tilt, hip_st, side_st, hips)
    return StanceHalf(side_st, normal, w_swing, phi_st, r_pelvis, root, hip_sw, x_ankle,
                      ok_ankle, jac_ankle, knee_rel, ok_knee_st, r_thigh_st, toe_angle)


def pelvis_shapes(style: GaitStyle, phase: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pelvic list and rotation at stance phases (k,) [1], peak 1, + stance side up /
    forward: Bovi's measured shapes (``style.pelvis_from_data``) or sin / cos 2πt."""
    if style.pelvis_from_data:
        from crowdwalk.gait.datasets import pelvis_motion

        return pelvis_motion().shapes(phase)
    return np.sin(2.0 * np.pi * phase), np.cos(2.0 * np.pi * phase)


# KLAW attributes on this engine (crowdwalk.style; docs/architecture.md). The arm follows
# the opposite thigh's elevation normalised over the natural-speed cycle (Bovi 2011 level
# walking, the shipped `level_natural` data: thigh elevation -17.4° .. +25.3°); bounciness
# lowers the stance hip around double support by BOUNCE_DIP body heights per unit above 1.
THIGH_MID, THIGH_HALF = np.deg2rad(3.97), np.deg2rad(21.38)
BOUNCE_DIP, BOUNCE_LOW = 0.006, 0.05  # [body heights], stance phase of the lowest hip [1]


def _upper_body_arguments(k: int, r_pelvis, heading, phase, left, side_st, phi_st, phi_sw,
                          attributes, style: GaitStyle) -> list:
    """The arguments of ``elevwalker_kernels.styled_upper_body`` after ``local`` (a list)
    for k walkers: it overwrites trunk, head, arm and elbow rotations in ``local`` (k, J,
    3, 3) with the KLAW attributes: trunk tilt and sway over the stance leg, shoulders
    against the pelvis, arms with the opposite thigh (abducted by arm_out), elbows between
    their least (arm back) and greatest (arm forward) flexion; the head stays upright.

    trunk = Rz(heading + shoulder) Rx(sway) Ry(tilt); vl5 = r_pelvisᵀ trunk; skullbase =
    trunkᵀ Rz(heading); shoulders trunkᵀ Rz(heading + shoulder) Rx(±arm_out) Ry(-swing
    signal); elbows Ry(-elbow): compiled (``elevwalker_kernels.styled_upper_body``), the
    trunk's measured shapes and the sines numpy's."""
    a = attributes
    from_data = bool(style.trunk_from_data)
    if from_data:
        from crowdwalk.gait.datasets import trunk_motion

        motion = trunk_motion()  # + stance side forward: negative at heel strike
        shape, wave = motion.rotation_shape(phase), motion.tilt_wave(phase)
    else:
        shape, wave = np.cos(2.0 * np.pi * phase), np.zeros(k)
    f = _vector
    return [
        np.ascontiguousarray(r_pelvis), f(heading, k), left, side_st, phi_st, phi_sw,
        from_data, f(shape, k), f(wave, k), np.sin(2.0 * np.pi * phase),
        f(a.shoulder_rotation, k), f(a.torso_tilt, k), f(a.torso_sway, k), f(a.arm_out, k),
        f(a.arm_swing, k), f(a.elbow_min, k), f(a.elbow_max, k), float(THIGH_MID),
        float(THIGH_HALF), JOINT["vl5"], JOINT["skullbase"], _SHOULDERS, _ELBOWS]



def _joint_rows(n_joints: int, n_upper: int, *args):
    """The compiled end of :func:`elevwalker_pose` on its rows (all, or a part of them in
    a row thread): the joints (``joints._assemble`` of ``args``' first ``n_joints``,
    :func:`~crowdwalk.gait.joints.assemble_arguments`), the KLAW upper body of the next
    ``n_upper`` (:func:`_upper_body_arguments`; none: no KLAW attributes), forward
    kinematics (the last four: offsets, root, pelvis, parents) and whether each row is
    finite. Returns local (k, J, 3, 3), swing knee (k,), swing foot reached (k,),
    positions (k, J, 3) [m], rotations (k, J, 3, 3), finite (k,) bool."""
    local, knee_sw, ok_foot_sw = _assemble(*args[:n_joints])
    if n_upper:
        ek.styled_upper_body(local, *args[n_joints:n_joints + n_upper])
    offsets, root, r_pelvis, parents = args[-4:]
    positions, rotations = _forward_kinematics(offsets, root, r_pelvis, local, parents)
    return local, knee_sw, ok_foot_sw, positions, rotations, rows_finite(positions, local)


# --- measurements on poses ------------------------------------------------------------


def leg_elevations(
    body: Body, positions: np.ndarray, rotations: np.ndarray, heading: np.ndarray
) -> np.ndarray:
    """Elevation angles measured on posed skeletons, (k, 2, 4) [rad].

    Axis 1 is left/right; columns foot (heel→ball from the horizontal, toe-up
    positive), shank (knee→ankle), thigh (hip→knee), pelvis (anterior tilt of the pelvis's
    up axis in the sagittal plane) — the conventions of the datasets.
    """
    out = np.empty((len(body), 2, 4))
    pts = foot_points(body, positions, rotations)
    for s in range(2):
        hip, knee, ankle = (positions[:, LEG_JOINTS[s, i]] for i in range(3))
        foot = pts[:, s, 1] - pts[:, s, 0]
        out[:, s, 0] = sagittal_elevation(foot, heading) - 0.5 * np.pi
        out[:, s, 1] = sagittal_elevation(ankle - knee, heading)
        out[:, s, 2] = sagittal_elevation(knee - hip, heading)
        # the pelvis's up axis leaning forward = anterior tilt
        out[:, s, 3] = -sagittal_elevation(-rotations[:, 0, :, 2], heading)
    return out


def joint_flexion(elevations: np.ndarray) -> np.ndarray:
    """Sagittal hip, knee and ankle flexion [rad] from elevation angles (..., 4).

    hip = thigh + pelvic anterior tilt (flexion +), knee = thigh − shank (flexion +),
    ankle = foot − shank (dorsiflexion +; 0 with a vertical shank and a flat foot) — the
    sign conventions of Winter (1991). Returns shape (..., 3).
    """
    e = np.asarray(elevations, dtype=float)
    foot, shank, thigh, pelvis = e[..., 0], e[..., 1], e[..., 2], e[..., 3]
    return np.stack([thigh + pelvis, thigh - shank, foot - shank], axis=-1)


def walk_cycle(
    angles: np.ndarray, height: float, samples: int = 100, style: GaitStyle | None = None,
    heading: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """One stride of ElevWalker on level ground, measured on the posed skeleton.

    The left leg is the stance leg for t ∈ [0, 0.5) and the swing leg after, so the
    returned curves cover the left leg's whole cycle from its heel strike.

    Parameters
    ----------
    angles : (N, 4) elevation-angle dataset [rad].
    height : body height [m].
    samples : number of stride times t = i / samples.
    style : GaitStyle, optional.
    heading : sagittal-plane orientation ψ [rad].

    Returns
    -------
    elevations : (samples, 4) left-leg elevation angles measured on the poses [rad].
    converged : (samples,) bool.
    """
    from crowdwalk.gait.datasets import sample

    t = np.arange(samples) / samples
    body = Body.from_heights(np.full(samples, height))
    left_stance = t < 0.5
    phase = np.where(left_stance, t, t - 0.5)
    psi = np.full(samples, heading)
    stance = sample(angles, phase)
    swing = sample(angles, phase + 0.5)
    foot = StanceFoot.from_foothold(body, np.zeros((samples, 3)), psi, np.zeros(samples))
    toe = np.full(samples, (style or GaitStyle()).toe_out)
    pose = elevwalker_pose(
        body, left_stance, phase, stance, swing, psi, foot, toe, WarmStart.neutral(samples),
        style,
    )  # fmt: skip
    measured = leg_elevations(body, pose.positions, pose.rotations, psi)
    return measured[:, 0], pose.converged
