"""Two-link inverse kinematics and the three key frames of a step (§5.1, Fig. 5).

All functions work on arrays of steps at once (leading shape ``(...)``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np

from planners.leg import Leg

__all__ = ["KeyFrames", "leg_angles", "key_frames", "TOE_OFF_FOOT_ANGLE",
           "TOE_OFF_PELVIS_FRACTION"]

#: Foot pitch at toe-off of the back leg (key frame 3) [rad]; Winter (1990) ~30-40 deg.
TOE_OFF_FOOT_ANGLE = float(np.radians(35.0))
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
    may hold arrays (one leg per step) instead of floats; everything broadcasts.

    Key frames (Fig. 5): K1 mid-swing (pelvis above the stance ankle, swing ankle at
    the summit); K2 front heel strike (pelvis midway, both feet flat); K3 back toe-off
    (pelvis at 70 % of the step, back foot pitched 35 deg about its toe); K1' the next
    mid-swing with the legs swapped (swing ankle ``nominal_lift`` above the new stance
    foot). The pelvis is ``pelvis_ratio`` x leg length above the stance ankle at
    mid-stance; in double support it is as high as both legs allow with the straighter
    leg at 99 % of its length (knees nearly straight at heel strike and toe-off).
    Compiled (:func:`_key_frames`), one step at a time.
    """
    arrays = [np.asarray(x, dtype=float) for x in (
        stance_s, stance_z, front_s, front_z, summit_s, summit_z, leg.thigh, leg.shank,
        leg.toe_offset, leg.ankle_height, nominal_lift)]
    shape = np.broadcast_shapes(*(x.shape for x in arrays))
    # numba gets contiguous writeable (n,) arrays: the inputs as they are where they can,
    # copies of broadcast ones
    flat = [x.reshape(-1) if x.shape == shape and x.flags.c_contiguous and x.flags.writeable
            else np.broadcast_to(x, shape).flatten() for x in arrays]
    thigh = np.empty(flat[0].size)
    calf = np.empty(flat[0].size)
    reachable = np.empty(flat[0].size, dtype=np.bool_)
    _key_frames(*flat, float(pelvis_ratio), float(np.cos(np.pi - knee_max_flexion)),
                thigh, calf, reachable)
    return KeyFrames(thigh.reshape(shape), calf.reshape(shape), reachable.reshape(shape))


_jit = nb.njit(cache=True, nogil=True)


@_jit
def _angles(hip_s, hip_z, ankle_s, ankle_z, a, b, L, min_reach):
    """:func:`leg_angles` of one leg: thigh and shank elevation, reachable."""
    ds = ankle_s - hip_s
    dz = hip_z - ankle_z
    if ds == 0.0 and dz > 0.0:
        # the ankle straight below the hip (K1's legs, K1' of the former stance leg):
        # hypot(+-0, dz) = |dz| and atan2(+-0, dz > 0) = +-0 exactly (C99 Annex F), the
        # same bits without the two calls
        d = dz
        direction = ds
    else:
        d = np.hypot(ds, dz)
        direction = np.arctan2(ds, dz)
    ok = (d <= L * (1 + 1e-9)) and (d >= min_reach)
    dc = min(max(d, max(min_reach, 1e-6)), L)
    at_hip = np.arccos(min(max((a * a + dc * dc - b * b) / (2 * a * dc), -1.0), 1.0))
    at_ankle = np.arccos(min(max((b * b + dc * dc - a * a) / (2 * b * dc), -1.0), 1.0))
    return direction + at_hip, direction - at_ankle, ok


@_jit
def _soft_min_1(a, b):
    """:func:`_soft_min` of two floats (scale 0.02 m)."""
    return min(a, b) - 0.02 * np.log1p(np.exp(-abs(a - b) / 0.02))


@_jit
def _pelvis_between(p_s, s1, z1, s2, z2, reach):
    r1 = np.sqrt(max(reach * reach - (p_s - s1) ** 2, 0.0))
    r2 = np.sqrt(max(reach * reach - (p_s - s2) ** 2, 0.0))
    return _soft_min_1(z1 + r1, z2 + r2)


@_jit
def leg_constants(a_len, b_len, toe, ankle, pelvis_ratio, cos_knee):
    """What :func:`key_frame` needs of a leg alone: leg length, pelvis height at
    mid-stance, shortest and double-support hip-ankle distances [m], and the toe-off
    pivot (toe-to-ankle distance [m], cos and sin of the ankle's angle about the toe)."""
    L = a_len + b_len
    min_reach = np.sqrt(a_len**2 + b_len**2 - 2 * a_len * b_len * cos_knee)
    r_toe = np.hypot(toe, ankle)
    pitch = TOE_OFF_FOOT_ANGLE + np.arctan2(ankle, toe)
    return (L, pelvis_ratio * L, min_reach, DOUBLE_SUPPORT_REACH * L, r_toe, np.cos(pitch),
            np.sin(pitch))


@_jit
def key_frame(stance_s, stance_z, front_s, front_z, summit_s, summit_z, a_len, b_len,
              toe, ankle, nominal_lift, constants):
    """Joint rotations (thigh, calf) [rad] and reachability of one step (see
    :func:`key_frames`; ``constants`` from :func:`leg_constants`); compiled, for other
    kernels."""
    s1 = stance_leg(stance_s, stance_z, a_len, b_len, ankle, constants)
    s4 = next_swing_leg(front_s, front_z + ankle, max(front_z + ankle, stance_z + ankle),
                        a_len, b_len, nominal_lift, constants)
    return key_frame_from(stance_s, stance_z, front_s, front_z, summit_s, summit_z, a_len,
                          b_len, toe, ankle, constants, s1, s4)


@_jit
def stance_leg(stance_s, stance_z, a_len, b_len, ankle, constants):
    """The stance leg at K1 (thigh, shank, reachable): a function of the stance foothold
    alone, shared by every step from it (:func:`key_frame_from`)."""
    L, H, min_reach = constants[0], constants[1], constants[2]
    zs = stance_z + ankle
    return _angles(stance_s, zs + H, stance_s, zs, a_len, b_len, L, min_reach)


@_jit
def next_swing_leg(front_s, front_ankle, high_ankle, a_len, b_len, nominal_lift, constants):
    """The former stance leg at K1' (thigh, shank, reachable), its ankle ``nominal_lift``
    above the higher foothold's ankle ``high_ankle`` [m]: a function of the front foothold
    alone wherever that is the higher one (:func:`key_frame_from`)."""
    L, H, min_reach = constants[0], constants[1], constants[2]
    return _angles(front_s, front_ankle + H, front_s, high_ankle + nominal_lift, a_len, b_len,
                   L, min_reach)


@_jit
def key_frame_from(stance_s, stance_z, front_s, front_z, summit_s, summit_z, a_len, b_len,
                   toe, ankle, constants, s1, s4):
    """:func:`key_frame` given the stance leg at K1 ``s1`` (:func:`stance_leg` of the
    same stance foothold) and the former stance leg at K1' ``s4``
    (:func:`next_swing_leg`)."""
    L, H, min_reach, reach, r_toe, cos_pitch, sin_pitch = constants
    ss, fs = stance_s, front_s
    zs, zf = stance_z + ankle, front_z + ankle
    # K1: mid-swing of the front-going leg F, stance leg S
    p1z = zs + H
    f1 = _angles(ss, p1z, summit_s, summit_z, a_len, b_len, L, min_reach)
    # K2: heel strike of F, pelvis midway
    p2s = 0.5 * (ss + fs)
    p2z = _pelvis_between(p2s, ss, zs, fs, zf, reach)
    f2 = _angles(p2s, p2z, fs, zf, a_len, b_len, L, min_reach)
    s2 = _angles(p2s, p2z, ss, zs, a_len, b_len, L, min_reach)
    # K3: toe-off of S; its ankle rotates about the toe
    toe_s = ss + toe
    back_s = toe_s - r_toe * cos_pitch
    back_z = stance_z + r_toe * sin_pitch
    p3s = ss + TOE_OFF_PELVIS_FRACTION * (fs - ss)
    p3z = _pelvis_between(p3s, back_s, back_z, fs, zf, reach)
    f3 = _angles(p3s, p3z, fs, zf, a_len, b_len, L, min_reach)
    s3 = _angles(p3s, p3z, back_s, back_z, a_len, b_len, L, min_reach)
    # K1': legs swapped, S at a nominal mid-swing above F; F stands as S did at K1
    f4 = s1
    # summed as the reference: each leg's three changes, then both legs
    thigh = ((abs(f2[0] - f1[0]) + abs(f3[0] - f2[0]) + abs(f4[0] - f3[0]))
             + (abs(s2[0] - s1[0]) + abs(s3[0] - s2[0]) + abs(s4[0] - s3[0])))
    calf = ((abs(f2[1] - f1[1]) + abs(f3[1] - f2[1]) + abs(f4[1] - f3[1]))
            + (abs(s2[1] - s1[1]) + abs(s3[1] - s2[1]) + abs(s4[1] - s3[1])))
    ok = f1[2] and s1[2] and f2[2] and s2[2] and f3[2] and s3[2] and f4[2] and s4[2]
    return thigh, calf, ok


@_jit
def _key_frames(stance_s, stance_z, front_s, front_z, summit_s, summit_z, thigh, shank,
                toe_offset, ankle_height, nominal_lift, pelvis_ratio, cos_knee,
                out_thigh, out_calf, out_reachable):
    """Joint rotations and reachability of each step (see :func:`key_frames`)."""
    for i in range(stance_s.size):
        constants = leg_constants(thigh[i], shank[i], toe_offset[i], ankle_height[i],
                                  pelvis_ratio, cos_knee)
        out_thigh[i], out_calf[i], out_reachable[i] = key_frame(
            stance_s[i], stance_z[i], front_s[i], front_z[i], summit_s[i], summit_z[i],
            thigh[i], shank[i], toe_offset[i], ankle_height[i], nominal_lift[i], constants)
