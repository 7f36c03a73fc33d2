"""The walker's skeleton: segment lengths from body height and batched forward kinematics.

The lower body has the 14 joint DOFs of Sun & Metaxas (2001, §3, Fig. 2; 2000, §2):
3-DOF hips, 1-DOF knees, a 1-DOF talocrural (upper ankle) and a 1-DOF subtalar (lower
ankle) joint per foot with **skew axes** after Inman (1976), and a 1-DOF first
metatarsophalangeal (toe) joint per foot; plus the 6-DOF root. The upper body (§8) has a
lumbar joint, a skull base and 3-joint arms.

Joint names are H-Anim level of articulation 1 (ISO/IEC 19774, ``HumanoidRoot``,
``sacroiliac``, ``vl5``, ``skullbase``, ``*_hip``, ``*_knee``, ``*_talocrural``,
``*_shoulder``, ``*_elbow``, ``*_wrist``) plus the LOA 2 joints ``*_subtalar`` and
``*_metatarsal`` that the paper's foot needs.

Frames: every segment frame coincides with the world axes in the rest pose (standing,
facing +x): x forward, y left, z up. A joint's local rotation turns the segment distal
to it relative to its parent segment (BVH semantics): ``R_world[j] = R_world[parent] @
R_local[j]`` and ``p[j] = p[parent] + R_world[parent] @ offset[j]``. Lengths in metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np

import planners.leg as _leg
from crowdwalk.errors import invalid

__all__ = [
    "JOINT_NAMES",
    "PARENTS",
    "JOINT",
    "LEG_JOINTS",
    "END_SITES",
    "PROPORTIONS",
    "TALOCRURAL_AXIS",
    "SUBTALAR_AXIS",
    "Body",
    "axis_angle_matrix",
    "rotation_x",
    "rotation_y",
    "rotation_z",
    "matrix_to_quaternion",
    "quaternion_to_matrix",
    "forward_kinematics",
]

JOINT_NAMES: tuple[str, ...] = (
    "HumanoidRoot", "sacroiliac",
    "l_hip", "l_knee", "l_talocrural", "l_subtalar", "l_metatarsal",
    "r_hip", "r_knee", "r_talocrural", "r_subtalar", "r_metatarsal",
    "vl5", "skullbase",
    "l_shoulder", "l_elbow", "l_wrist",
    "r_shoulder", "r_elbow", "r_wrist",
)  # fmt: skip
"""H-Anim joint names, index order of every joint array."""

JOINT: dict[str, int] = {name: i for i, name in enumerate(JOINT_NAMES)}
"""Joint index by name."""

PARENTS: np.ndarray = np.array(
    [-1, 0, 1, 2, 3, 4, 5, 1, 7, 8, 9, 10, 0, 12, 12, 14, 15, 12, 17, 18], dtype=int
)
"""Parent joint index of each joint (-1 for the root), shape (J,)."""

LEG_JOINTS: np.ndarray = np.array([[2, 3, 4, 5, 6], [7, 8, 9, 10, 11]], dtype=int)
"""Joint indices (hip, knee, talocrural, subtalar, metatarsal) of the left (row 0) and
right (row 1) leg, shape (2, 5)."""

END_SITES: dict[str, str] = {
    "l_metatarsal": "l_toe_tip", "r_metatarsal": "r_toe_tip", "skullbase": "head_top",
    "l_wrist": "l_hand_tip", "r_wrist": "r_hand_tip",
}  # fmt: skip
"""Joints that end a chain and the name of the end site after them."""

PROPORTIONS: dict[str, float] = {
    # Winter (2009), Biomechanics and Motor Control of Human Movement, 4th ed., Fig. 4.1,
    # after Drillis & Contini (1966): segment lengths as fractions of body height H. The
    # leg's (thigh, shank, ankle height, foot and the ankle's place on it) are the
    # planners' (planners.leg), so that planned and animated legs are one leg.
    "hip_height": 0.530,  # greater trochanter ≈ hip joint centre
    "thigh": _leg.THIGH_RATIO,  # 0.245 = 0.530 - 0.285 (knee)
    "shank": _leg.SHANK_RATIO,  # 0.246 = 0.285 - 0.039 (ankle)
    "ankle_height": _leg.ANKLE_HEIGHT_RATIO,  # 0.039
    "foot_length": _leg.FOOT_LENGTH_RATIO,  # 0.152
    "upper_arm": 0.186,
    "forearm": 0.146,
    "hand": 0.108,
    "shoulder_height": 0.818,
    "chin_height": 0.870,  # skull base placed at chin level
    "shoulder_width": 0.259,
    "hip_width": 0.191,
    # Estimates (not in Winter's figure), documented:
    # - the ankle lies a quarter foot length ahead of the heel (heel 0.038 H, toe 0.114 H;
    #   planners.leg.HEEL_FRACTION), the convention shared with
    #   crowdwalk.gait.elevinterp.SagittalLeg;
    # - the first metatarsal head (ball) 0.073 H ahead of the ankle (72 % of foot length
    #   from the heel);
    # - hip joint centres 0.52 x Winter's hip width apart (Bell et al. 1990: each HJC lies
    #   14 % of the inter-ASIS width medial to the ASIS);
    # - shoulder joint centres 0.8 x Winter's shoulder width apart;
    # - the L5 joint 0.05 H above the hip joint centres.
    "heel_offset": _leg.HEEL_FRACTION * _leg.FOOT_LENGTH_RATIO,
    "toe_offset": (1 - _leg.HEEL_FRACTION) * _leg.FOOT_LENGTH_RATIO,
    "ball_offset": 0.073,
    "hip_separation": 0.52 * 0.191,
    "shoulder_separation": 0.8 * 0.259,
    "lumbar_height": 0.05,
}
"""Anthropometric proportions of body height [1], with sources in the comments."""


def _unit(v: tuple[float, float, float]) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


_d = np.deg2rad
# Inman (1976), The Joints of the Ankle: the talocrural axis runs through the malleoli,
# inclined ~8 deg downward laterally (frontal plane) and ~6 deg posterior-laterally
# (transverse plane); the subtalar axis rises 42 deg from the horizontal and deviates
# 23 deg medially from the long axis of the foot. Left foot, frame x fwd, y left, z up.
TALOCRURAL_AXIS = _unit((-np.sin(_d(6.0)), np.cos(_d(6.0)), -np.tan(_d(8.0))))
"""Left talocrural axis (unit (3,)), medial→lateral; the right one is mirrored."""
SUBTALAR_AXIS = _unit((np.cos(_d(42.0)) * np.cos(_d(23.0)),
                       -np.cos(_d(42.0)) * np.sin(_d(23.0)), np.sin(_d(42.0))))  # fmt: skip
"""Left subtalar axis (unit (3,)), posterior-lateral-inferior → anterior-medial-superior."""


def mirrored_axis(axis: np.ndarray) -> np.ndarray:
    """The right-side joint axis of a left-side axis (unit (3,)).

    Reflecting y turns a rotation about ``a`` by θ into a rotation about ``-M a`` by θ
    (``M = diag(1, -1, 1)``), so equal joint angles give mirror-image motions.
    """
    return np.array([-axis[0], axis[1], -axis[2]])


@dataclass(frozen=True, eq=False)
class Body:
    """Segment lengths of n walkers [m], each an (n,) array.

    Build with :meth:`from_heights`. ``thigh`` hip→knee, ``shank`` knee→ankle,
    ``ankle_height`` ankle centre above the sole, ``heel_offset`` / ``ball_offset`` /
    ``toe_offset`` horizontal distance from the ankle to the back of the heel / the first
    metatarsal head / the toe tip, ``hip_separation`` between the hip joint centres,
    ``hip_height`` of the hip centres when standing.
    """

    height: np.ndarray
    thigh: np.ndarray
    shank: np.ndarray
    ankle_height: np.ndarray
    heel_offset: np.ndarray
    ball_offset: np.ndarray
    toe_offset: np.ndarray
    foot_length: np.ndarray
    hip_separation: np.ndarray
    hip_height: np.ndarray
    lumbar: np.ndarray
    trunk: np.ndarray
    head: np.ndarray
    shoulder_drop: np.ndarray
    shoulder_separation: np.ndarray
    upper_arm: np.ndarray
    forearm: np.ndarray
    hand: np.ndarray

    @classmethod
    def from_heights(cls, heights: np.ndarray | float) -> Body:
        """Bodies scaled from heights (n,) [m] with :data:`PROPORTIONS`.

        Raises
        ------
        InputError
            When a height is not finite or outside [0.5, 2.5] m.
        """
        h = np.atleast_1d(np.asarray(heights, dtype=float))
        if h.ndim != 1 or h.size == 0:
            raise invalid("Body", "heights", "a non-empty (n,) array [m]", h.shape)
        bad = ~(np.isfinite(h) & (h >= 0.5) & (h <= 2.5))
        if bad.any():
            raise invalid("Body", "heights", "finite and in [0.5, 2.5] [m]", float(h[bad][0]))
        p = PROPORTIONS
        skull = p["chin_height"] - p["hip_height"] - p["lumbar_height"]
        drop = p["chin_height"] - p["shoulder_height"]
        return cls(
            height=h,
            thigh=p["thigh"] * h,
            shank=p["shank"] * h,
            ankle_height=p["ankle_height"] * h,
            heel_offset=_leg.HEEL_FRACTION * (p["foot_length"] * h),
            ball_offset=p["ball_offset"] * h,
            toe_offset=(1 - _leg.HEEL_FRACTION) * (p["foot_length"] * h),
            foot_length=p["foot_length"] * h,
            hip_separation=p["hip_separation"] * h,
            hip_height=p["hip_height"] * h,
            lumbar=p["lumbar_height"] * h,
            trunk=skull * h,
            head=(1.0 - p["chin_height"]) * h,
            shoulder_drop=drop * h,
            shoulder_separation=p["shoulder_separation"] * h,
            upper_arm=p["upper_arm"] * h,
            forearm=p["forearm"] * h,
            hand=p["hand"] * h,
        )

    def __len__(self) -> int:
        return int(self.height.shape[0])

    def take(self, index: np.ndarray) -> Body:
        """The bodies at ``index`` (integer or boolean array)."""
        return Body(**{k: getattr(self, k)[index] for k in self.__dataclass_fields__})

    def planning_legs(self) -> list:
        """The ``planners.Leg`` of each body (n,): the same thigh, shank, ankle height and
        foot the body is animated with [m]."""
        from planners import Leg

        return [Leg(thigh=float(self.thigh[i]), shank=float(self.shank[i]),
                    foot_length=float(self.foot_length[i]),
                    heel_offset=float(self.heel_offset[i]),
                    toe_offset=float(self.toe_offset[i]),
                    ankle_height=float(self.ankle_height[i])) for i in range(len(self))]

    @property
    def leg_length(self) -> np.ndarray:
        """Hip joint centre to sole when standing: thigh + shank + ankle height, (n,) [m]."""
        return self.thigh + self.shank + self.ankle_height

    def offsets(self) -> np.ndarray:
        """Rest-pose joint offsets from the parent joint, (n, J, 3) [m], parent frame."""
        n = len(self)
        off = np.zeros((n, len(JOINT_NAMES), 3))
        hw = 0.5 * self.hip_separation
        sw = 0.5 * self.shoulder_separation
        for side, sign in (("l", 1.0), ("r", -1.0)):
            off[:, JOINT[f"{side}_hip"], 1] = sign * hw
            off[:, JOINT[f"{side}_knee"], 2] = -self.thigh
            off[:, JOINT[f"{side}_talocrural"], 2] = -self.shank
            off[:, JOINT[f"{side}_metatarsal"], 0] = self.ball_offset
            off[:, JOINT[f"{side}_metatarsal"], 2] = -self.ankle_height
            off[:, JOINT[f"{side}_shoulder"], 1] = sign * sw
            off[:, JOINT[f"{side}_shoulder"], 2] = self.trunk - self.shoulder_drop
            off[:, JOINT[f"{side}_elbow"], 2] = -self.upper_arm
            off[:, JOINT[f"{side}_wrist"], 2] = -self.forearm
        off[:, JOINT["vl5"], 2] = self.lumbar
        off[:, JOINT["skullbase"], 2] = self.trunk
        return off

    def end_site_offsets(self) -> dict[str, np.ndarray]:
        """End-site offsets (n, 3) [m] in the frame of the joint named by the key."""
        n = len(self)
        z = np.zeros(n)
        return {
            "l_metatarsal": np.stack([self.toe_offset - self.ball_offset, z, z], axis=1),
            "r_metatarsal": np.stack([self.toe_offset - self.ball_offset, z, z], axis=1),
            "skullbase": np.stack([z, z, self.head], axis=1),
            "l_wrist": np.stack([z, z, -self.hand], axis=1),
            "r_wrist": np.stack([z, z, -self.hand], axis=1),
        }


# --- rotations (batched) ----------------------------------------------------------------


def axis_angle_matrix(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotation matrices about unit axes by angles (Rodrigues).

    Parameters
    ----------
    axis : numpy.ndarray
        Unit axis (3,) or (k, 3).
    angle : numpy.ndarray
        Angles (k,) [rad], right-hand rule.

    Returns
    -------
    numpy.ndarray
        Shape (k, 3, 3).
    """
    angle = np.asarray(angle, dtype=float)
    axis = np.broadcast_to(np.asarray(axis, dtype=float), angle.shape + (3,))
    x, y, z = axis[..., 0], axis[..., 1], axis[..., 2]
    c, s = np.cos(angle), np.sin(angle)
    C = 1.0 - c
    out = np.empty(angle.shape + (3, 3))
    out[..., 0, 0] = c + x * x * C
    out[..., 0, 1] = x * y * C - z * s
    out[..., 0, 2] = x * z * C + y * s
    out[..., 1, 0] = y * x * C + z * s
    out[..., 1, 1] = c + y * y * C
    out[..., 1, 2] = y * z * C - x * s
    out[..., 2, 0] = z * x * C - y * s
    out[..., 2, 1] = z * y * C + x * s
    out[..., 2, 2] = c + z * z * C
    return out


@nb.njit(cache=True, nogil=True)
def _elementary_kernel(angle, i, j, out):  # pragma: no cover - compiled
    k = 3 - i - j
    for a in range(angle.shape[0]):
        c, s = np.cos(angle[a]), np.sin(angle[a])
        out[a, k, k] = 1.0
        out[a, i, i] = c
        out[a, j, j] = c
        out[a, i, j] = -s
        out[a, j, i] = s


def _elementary(angle: np.ndarray, i: int, j: int) -> np.ndarray:
    angle = np.asarray(angle, dtype=float)
    if angle.ndim:  # the numpy code below, compiled (bitwise equal)
        out = np.zeros((angle.size, 3, 3))
        _elementary_kernel(np.ascontiguousarray(angle).reshape(-1), i, j, out)
        return out.reshape(angle.shape + (3, 3))
    return _elementary_numpy(angle, i, j)


def _elementary_numpy(angle: np.ndarray, i: int, j: int) -> np.ndarray:
    """Rotations (..., 3, 3) in the (i, j) plane by angles (...) [rad], in numpy: what
    ``_elementary_kernel`` compiles."""
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros(angle.shape + (3, 3))
    k = 3 - i - j
    out[..., k, k] = 1.0
    out[..., i, i] = c
    out[..., j, j] = c
    out[..., i, j] = -s
    out[..., j, i] = s
    return out


def rotation_x(angle: np.ndarray) -> np.ndarray:
    """Rotations about +x by angles (k,) [rad], shape (k, 3, 3)."""
    return _elementary(angle, 1, 2)


def rotation_y(angle: np.ndarray) -> np.ndarray:
    """Rotations about +y by angles (k,) [rad], shape (k, 3, 3)."""
    return _elementary(angle, 2, 0)


def rotation_z(angle: np.ndarray) -> np.ndarray:
    """Rotations about +z by angles (k,) [rad], shape (k, 3, 3)."""
    return _elementary(angle, 0, 1)


_QUAT_PICK = np.array([[0, 1, 2, 3], [1, 0, 4, 5], [2, 4, 0, 6], [3, 5, 6, 0]])
"""Shepperd candidates: for each pivot (w, x, y, z) the indices into the seven
distinct components (big, m21-m12, m02-m20, m10-m01, m01+m10, m02+m20, m12+m21)."""


def matrix_to_quaternion(matrix: np.ndarray) -> np.ndarray:
    """Unit quaternions wxyz (..., 4) of rotation matrices (..., 3, 3), w ≥ 0.

    Shepperd's method: each row uses the largest of |w|, |x|, |y|, |z| as the pivot, so the
    conversion is well conditioned for every rotation.
    """
    m = np.asarray(matrix, dtype=float)
    shape = m.shape[:-2]
    q = _matrix_to_quaternion(np.ascontiguousarray(m.reshape(-1, 3, 3)))
    return q.reshape(shape + (4,))


@nb.njit(cache=True, nogil=True)
def _matrix_to_quaternion(m):
    """Compiled Shepperd conversion of :func:`matrix_to_quaternion`, (p, 3, 3) → (p, 4)."""
    q = np.empty((m.shape[0], 4))
    squares = np.empty(4)
    parts = np.empty(7)
    for i in range(m.shape[0]):
        m00, m01, m02 = m[i, 0, 0], m[i, 0, 1], m[i, 0, 2]
        m10, m11, m12 = m[i, 1, 0], m[i, 1, 1], m[i, 1, 2]
        m20, m21, m22 = m[i, 2, 0], m[i, 2, 1], m[i, 2, 2]
        squares[0] = 0.25 * (1 + m00 + m11 + m22)
        squares[1] = 0.25 * (1 + m00 - m11 - m22)
        squares[2] = 0.25 * (1 - m00 + m11 - m22)
        squares[3] = 0.25 * (1 - m00 - m11 + m22)
        pivot = np.argmax(squares)
        big = np.sqrt(max(squares[pivot], 1e-300))
        f = 0.25 / big
        # the seven distinct candidate components; _QUAT_PICK[pivot] selects the four
        parts[0] = big
        parts[1], parts[2], parts[3] = (m21 - m12) * f, (m02 - m20) * f, (m10 - m01) * f
        parts[4], parts[5], parts[6] = (m01 + m10) * f, (m02 + m20) * f, (m12 + m21) * f
        norm = 0.0
        for c in range(4):
            q[i, c] = parts[_QUAT_PICK[pivot, c]]
            norm += q[i, c] * q[i, c]
        norm = np.sqrt(norm) * (-1.0 if q[i, 0] < 0 else 1.0)
        for c in range(4):
            q[i, c] /= norm
    return q


def quaternion_to_matrix(quaternion: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of quaternions wxyz (..., 4) (normalised first)."""
    from scipy.spatial.transform import Rotation

    q = np.asarray(quaternion, dtype=float)
    shape = q.shape[:-1]
    flat = q.reshape(-1, 4)[:, [1, 2, 3, 0]]
    return Rotation.from_quat(flat).as_matrix().reshape(shape + (3, 3))


def forward_kinematics(
    body: Body, root_position: np.ndarray, root_rotation: np.ndarray, local: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Joint world positions and orientations of n posed skeletons.

    Parameters
    ----------
    body : Body
        n bodies.
    root_position : numpy.ndarray
        (n, 3) world position of ``HumanoidRoot`` [m].
    root_rotation : numpy.ndarray
        (n, 3, 3) world orientation of the pelvis (``HumanoidRoot``).
    local : numpy.ndarray
        (n, J, 3, 3) local joint rotations; entry 0 is ignored (the root uses
        ``root_rotation``).

    Returns
    -------
    positions : numpy.ndarray
        (n, J, 3) joint world positions [m].
    rotations : numpy.ndarray
        (n, J, 3, 3) world orientations of the segment distal to each joint.
    """
    n = len(body)
    nj = len(JOINT_NAMES)
    if local.shape != (n, nj, 3, 3):
        raise invalid("forward_kinematics", "local", f"shaped ({n}, {nj}, 3, 3)", local.shape)
    return _forward_kinematics(
        body.offsets(), np.ascontiguousarray(root_position, dtype=float),
        np.ascontiguousarray(root_rotation, dtype=float),
        np.ascontiguousarray(local, dtype=float), PARENTS,
    )


@nb.njit(cache=True, nogil=True)
def _forward_kinematics(offsets, root_position, root_rotation, local, parents):
    """Compiled joint loop of :func:`forward_kinematics`, one skeleton at a time."""
    n, nj = local.shape[0], local.shape[1]
    positions = np.empty((n, nj, 3))
    rotations = np.empty((n, nj, 3, 3))
    for i in range(n):
        positions[i, 0] = root_position[i]
        rotations[i, 0] = root_rotation[i]
        for j in range(1, nj):
            p = parents[j]
            rp, rl, rj = rotations[i, p], local[i, j], rotations[i, j]
            for a in range(3):
                positions[i, j, a] = positions[i, p, a] + (
                    rp[a, 0] * offsets[i, j, 0] + rp[a, 1] * offsets[i, j, 1]
                    + rp[a, 2] * offsets[i, j, 2]
                )
                for b in range(3):
                    rj[a, b] = rp[a, 0] * rl[0, b] + rp[a, 1] * rl[1, b] + rp[a, 2] * rl[2, b]
    return positions, rotations
