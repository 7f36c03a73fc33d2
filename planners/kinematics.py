"""Two-link inverse kinematics and the three key frames of a step (§5.1, Fig. 5).

All functions work on arrays of steps at once (leading shape ``(...)``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planners.leg import Leg

__all__ = ["KeyFrames", "leg_angles", "key_frames", "TOE_OFF_FOOT_ANGLE",
           "TOE_OFF_PELVIS_FRACTION"]

#: Foot pitch at toe-off of the back leg (key frame 3) [rad]; Winter (1990) ~30-40 deg.
TOE_OFF_FOOT_ANGLE = np.radians(35.0)
#: Pelvis position at toe-off, as a fraction of the step from back to front foot [-].
TOE_OFF_PELVIS_FRACTION = 0.70
#: Hip-ankle distance of the straighter leg in double support, fraction of leg length.
DOUBLE_SUPPORT_REACH = 0.99


def leg_angles(hip_s, hip_z, ankle_s, ankle_z, leg: Leg, min_reach: float):
    """Elevation angles of thigh and shank for a hip and an ankle, knee forward.

    Parameters
    ----------
    hip_s, hip_z, ankle_s, ankle_z : ndarray
        Hip and ankle positions in the sagittal (s, z) plane [m], same shapes.
    leg : Leg
        Segment lengths [m].
    min_reach : float
        Shortest hip-ankle distance the knee flexion limit allows [m].

    Returns
    -------
    thigh, shank : ndarray
        Elevation angles from the downward vertical, positive anterior [rad].
    reachable : ndarray of bool
        Whether the distance lies within ``[min_reach, thigh + shank]``.
    """
    ds = ankle_s - hip_s
    dz = hip_z - ankle_z
    d = np.hypot(ds, dz)
    reachable = (d <= leg.length * (1 + 1e-9)) & (d >= min_reach)
    # np.minimum(np.maximum(...)) is np.clip without its per-call overhead (hot: several
    # calls per step on a batch of many steps)
    dc = np.minimum(np.maximum(d, np.maximum(min_reach, 1e-6)), leg.length)
    direction = np.arctan2(ds, dz)
    a, b = leg.thigh, leg.shank
    at_hip = np.arccos(np.minimum(np.maximum((a * a + dc * dc - b * b) / (2 * a * dc), -1.0),
                                  1.0))
    at_ankle = np.arccos(np.minimum(np.maximum((b * b + dc * dc - a * a) / (2 * b * dc),
                                               -1.0), 1.0))
    return direction + at_hip, direction - at_ankle, reachable


def _soft_min(a, b, scale: float = 0.02):
    """Smooth minimum (within ``scale * ln 2`` [m] of the true one, never above it)."""
    return np.minimum(a, b) - scale * np.log1p(np.exp(-np.abs(a - b) / scale))


@dataclass(frozen=True)
class KeyFrames:
    """Joint rotation amounts of one step and whether every key frame is reachable.

    Attributes
    ----------
    thigh_rotation, calf_rotation : ndarray
        Summed |change| of both thighs / both calves over K1 -> K2 -> K3 -> K1' [rad].
    reachable : ndarray of bool
        Knee reachable (within reach and flexion limit) at every key frame.
    """

    thigh_rotation: np.ndarray
    calf_rotation: np.ndarray
    reachable: np.ndarray


def key_frames(stance_s, stance_z, front_s, front_z, summit_s, summit_z, leg: Leg,
               pelvis_ratio: float, knee_max_flexion: float, nominal_lift: float) -> KeyFrames:
    """Key frames of one step (§5.1) and the joint rotations between them (Eq. 3).

    The swing foot moves past the ``stance`` foot to ``front``; ground heights are of the
    footholds [m], ``summit`` is the highest ankle point of the swing curve [m]. ``leg``
    may hold arrays (one leg per step) instead of floats.

    Key frames (Fig. 5): K1 mid-swing (pelvis above the stance ankle, swing ankle at
    the summit); K2 front heel strike (pelvis midway, both feet flat); K3 back toe-off
    (pelvis at 70 % of the step, back foot pitched 35 deg about its toe); K1' the next
    mid-swing with the legs swapped (swing ankle ``nominal_lift`` above the new stance
    foot). The pelvis is ``pelvis_ratio`` x leg length above the stance ankle at
    mid-stance; in double support it is as high as both legs allow with the straighter
    leg at 99 % of its length (knees nearly straight at heel strike and toe-off).
    """
    a = leg.ankle_height
    L = leg.length
    H = pelvis_ratio * L
    cos_knee = np.cos(np.pi - knee_max_flexion)
    min_reach = np.sqrt(leg.thigh**2 + leg.shank**2 - 2 * leg.thigh * leg.shank * cos_knee)
    zs, zf = stance_z + a, front_z + a  # ankle heights

    reach = DOUBLE_SUPPORT_REACH * L

    def pelvis_between(p_s, s1, z1, s2, z2):
        # Highest pelvis from which both ankles are at most ``reach`` away.
        r1 = np.sqrt(np.maximum(reach * reach - (p_s - s1) ** 2, 0.0))
        r2 = np.sqrt(np.maximum(reach * reach - (p_s - s2) ** 2, 0.0))
        return _soft_min(z1 + r1, z2 + r2)

    # K1: mid-swing of the front-going leg F, stance leg S.
    p1s, p1z = stance_s, zs + H
    f1 = leg_angles(p1s, p1z, summit_s, summit_z, leg, min_reach)
    s1 = leg_angles(p1s, p1z, stance_s, zs, leg, min_reach)
    # K2: heel strike of F, pelvis midway.
    p2s = 0.5 * (stance_s + front_s)
    p2z = pelvis_between(p2s, stance_s, zs, front_s, zf)
    f2 = leg_angles(p2s, p2z, front_s, zf, leg, min_reach)
    s2 = leg_angles(p2s, p2z, stance_s, zs, leg, min_reach)
    # K3: toe-off of S; its ankle rotates about the toe.
    toe_s = stance_s + leg.toe_offset
    r_toe = np.hypot(leg.toe_offset, a)
    pitch = TOE_OFF_FOOT_ANGLE + np.arctan2(a, leg.toe_offset)
    back_ankle_s = toe_s - r_toe * np.cos(pitch)
    back_ankle_z = stance_z + r_toe * np.sin(pitch)
    p3s = stance_s + TOE_OFF_PELVIS_FRACTION * (front_s - stance_s)
    p3z = pelvis_between(p3s, back_ankle_s, back_ankle_z, front_s, zf)
    f3 = leg_angles(p3s, p3z, front_s, zf, leg, min_reach)
    s3 = leg_angles(p3s, p3z, back_ankle_s, back_ankle_z, leg, min_reach)
    # K1': legs swapped, S at a nominal mid-swing above F; F stands as S did at K1.
    p4s, p4z = front_s, zf + H
    f4 = s1
    s4 = leg_angles(p4s, p4z, front_s, np.maximum(zf, zs) + nominal_lift, leg, min_reach)

    def rotation(frames, part):
        angles = [frame[part] for frame in frames]
        return sum(np.abs(b - a) for a, b in zip(angles[:-1], angles[1:], strict=True))

    thigh = rotation((f1, f2, f3, f4), 0) + rotation((s1, s2, s3, s4), 0)
    calf = rotation((f1, f2, f3, f4), 1) + rotation((s1, s2, s3, s4), 1)
    reachable = np.ones(np.shape(thigh), dtype=bool)
    for frame in (f1, s1, f2, s2, f3, s3, f4, s4):
        reachable &= frame[2]
    return KeyFrames(thigh, calf, reachable)
