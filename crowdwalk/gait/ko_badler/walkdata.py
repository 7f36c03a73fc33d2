"""Walk data W(S, sl) = {H, F1, F2, F3, M, A} of Ko & Badler (1992, §1).

All lengths in metres, angles in radians, times normalised to the step: the heel strike
that starts the step (HSM⁻) is t = 0, the other foot's heel strike (HSM⁺) t = 1.

Reading of the paper used throughout (docs/architecture.md, "Ko & Badler"):

- The step's **stance foot** is the foot that struck at HSM⁻; its ``N`` (the sole point
  below the ankle when the foot is flat) is the origin of every x coordinate, y is the
  height above the floor.
- ``F1`` is the stance foot's angle over [HSM⁻, FGM], ``F2`` over [FGM, 1 + TOM] (flat,
  heel rise and push-off until its toe-off early in the next step) and ``M`` its meta
  (toe) angle over [MOM, 1 + TOM]; ``F3`` and ``A`` are the **swing** foot's angle and
  ankle over [TOM, HSM⁺], TOM being the swing foot's toe-off. In a symmetric walk the
  stance foot's toe-off is one step after the swing foot's, so one TOM serves both.
- Foot angles are signed, toe-up positive (the heel→ball sole line from the floor; flat
  foot 0): the heel strike angle μ2 is positive, the toe-off angle is −μ3. The meta angle
  is the toes' angle from the floor, positive with the ball above the toe tip.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from functools import lru_cache
from importlib import resources

import numpy as np

from crowdwalk.errors import invalid

__all__ = [
    "TimedSequence",
    "interpolation",
    "BodyCondition",
    "GaitLaw",
    "WalkData",
    "StepStart",
    "load_prototype",
]


@dataclass(frozen=True, eq=False)
class TimedSequence:
    """A timed sequence Q = {(t_i, v_i)} (Eq. 1).

    Attributes
    ----------
    t : numpy.ndarray
        (n,) strictly increasing times, normalised to the step.
    v : numpy.ndarray
        (..., n) values (angles [rad]) or (..., n, 2) points (x, y) [m]; the leading
        dimensions are walkers (the generalisations broadcast over them).
    """

    t: np.ndarray
    v: np.ndarray

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float)
        if t.ndim != 1 or t.size < 2 or np.any(np.diff(t) <= 0):
            raise invalid("TimedSequence", "t", "strictly increasing (n >= 2,) times", t)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "v", np.asarray(self.v, dtype=float))

    @property
    def is_path(self) -> bool:
        """True when the values are points (..., n, 2)."""
        return self.v.ndim >= 2 and self.v.shape[-1] == 2 and self.v.shape[-2] == self.t.size

    @property
    def x(self) -> np.ndarray:
        """(..., n) x values of a path [m]."""
        return self.v[..., 0]

    @property
    def y(self) -> np.ndarray:
        """(..., n) y values of a path [m]."""
        return self.v[..., 1]

    @property
    def values(self) -> np.ndarray:
        """(..., n, d) values, d = 1 for angles."""
        return self.v if self.is_path else self.v[..., None]

    def with_values(self, v: np.ndarray) -> TimedSequence:
        """The same times with new values."""
        return TimedSequence(self.t, v)

    def __call__(self, t: np.ndarray | float) -> np.ndarray:
        return interpolation(self, t)


def interpolation(q: TimedSequence, t: np.ndarray | float) -> np.ndarray:
    """Eq. 2: piecewise-linear value of ``q`` at times ``t`` (clamped to its ends).

    ``t`` has the walkers' batch shape (or broadcasts to it); the result has that shape
    (angles) or that shape + (2,) (paths).
    """
    tq = np.asarray(t, dtype=float)
    vals = q.values  # (..., n, d)
    batch = np.broadcast_shapes(vals.shape[:-2], tq.shape)
    vals = np.broadcast_to(vals, (*batch, *vals.shape[-2:]))
    tq = np.broadcast_to(tq, batch)
    i = np.clip(np.searchsorted(q.t, tq, side="right") - 1, 0, q.t.size - 2)
    t0, t1 = q.t[i], q.t[i + 1]
    w = np.clip((tq - t0) / (t1 - t0), 0.0, 1.0)[..., None]
    v0 = np.take_along_axis(vals, i[..., None, None], axis=-2)[..., 0, :]
    v1 = np.take_along_axis(vals, (i + 1)[..., None, None], axis=-2)[..., 0, :]
    out = v0 + w * (v1 - v0)
    return out if q.is_path else out[..., 0]


@dataclass(frozen=True, eq=False)
class BodyCondition:
    """B(S): the segment lengths the walk data depend on [m] (§1, Fig. 7).

    Each field is a float or an array of the walkers' batch shape. ``thigh`` hip→knee,
    ``shin`` knee→ankle, ``ankle_height`` aN (ankle above the sole point N below it when
    the foot is flat), ``heel`` hN and ``ball`` bN (horizontal N→heel and N→ball of the
    foot on the sole), ``toes`` bt (ball → tip of the toes).
    """

    thigh: np.ndarray | float
    shin: np.ndarray | float
    ankle_height: np.ndarray | float
    heel: np.ndarray | float
    ball: np.ndarray | float
    toes: np.ndarray | float

    def __post_init__(self) -> None:
        for name in ("thigh", "shin", "ankle_height", "heel", "ball", "toes"):
            value = np.asarray(getattr(self, name), dtype=float)
            if not np.all(np.isfinite(value) & (value > 0)):
                raise invalid("BodyCondition", name, "finite and > 0 [m]", value)
            object.__setattr__(self, name, value)

    @classmethod
    def from_body(cls, body) -> BodyCondition:
        """The body condition of :class:`crowdwalk.body.Body` walkers ((n,) fields)."""
        return cls(
            thigh=body.thigh,
            shin=body.shank,
            ankle_height=body.ankle_height,
            heel=body.heel_offset,
            ball=body.ball_offset,
            toes=body.toe_offset - body.ball_offset,
        )

    @property
    def leg_length(self) -> np.ndarray:
        """ll(S) = thigh + shin [m] (§1)."""
        return self.thigh + self.shin

    @property
    def ankle_heel(self) -> np.ndarray:
        """ah: ankle → heel [m]."""
        return np.hypot(self.heel, self.ankle_height)

    @property
    def ankle_ball(self) -> np.ndarray:
        """ab: ankle → ball of the foot [m]."""
        return np.hypot(self.ball, self.ankle_height)

    @property
    def heel_angle(self) -> np.ndarray:
        """θh: inner angle of the foot at the heel [rad]."""
        return np.arctan2(self.ankle_height, self.heel)

    @property
    def ball_angle(self) -> np.ndarray:
        """θb: inner angle of the foot at the ball [rad]."""
        return np.arctan2(self.ankle_height, self.ball)

    def take(self, index) -> BodyCondition:
        """The walkers at ``index``."""
        return BodyCondition(**{k: np.asarray(getattr(self, k))[index] for k in _BODY_FIELDS})


_BODY_FIELDS = ("thigh", "shin", "ankle_height", "heel", "ball", "toes")


@dataclass(frozen=True, eq=False)
class GaitLaw:
    """The constants of μ1…μ4 (Eqs. 5, 6, 21, 24), a property of the prototype walk.

    Attributes
    ----------
    alpha : numpy.ndarray
        (4,) α1…α4 [rad per unit step length / leg length].
    mu_star : numpy.ndarray
        (4,) μ1* (knee angle at heel strike, interior, π = straight) [rad], μ2* (foot
        angle at heel strike, toe up), μ3* (foot angle at toe-off, heel up), μ4* (meta
        angle at toe-off) [rad] of the prototype.
    step_ratio : float
        sl*/ll(S*): the prototype's step length over its leg length [1] (the paper's sl*
        in Eqs. 5–24, read as normalised so that μ_i(S*, sl*) = μ_i*).
    """

    alpha: np.ndarray
    mu_star: np.ndarray
    step_ratio: float

    def __post_init__(self) -> None:
        for name in ("alpha", "mu_star"):
            value = np.asarray(getattr(self, name), dtype=float)
            if value.shape != (4,) or not np.all(np.isfinite(value)):
                raise invalid("GaitLaw", name, "a finite (4,) array [rad]", value)
            object.__setattr__(self, name, value)
        if not 0.0 <= self.alpha[0] <= 0.3:
            raise invalid("GaitLaw", "alpha[0]", "in [0, 0.3] (§2.1, after Inman)", self.alpha[0])


@dataclass(frozen=True, eq=False)
class StepStart:
    """What the walker brings to a step: the previous step and the current posture.

    ``step_length`` sl_before [m] (Eqs. 15, 20); ``hip_height`` ỹ1 [m] above the floor at
    HSM⁻ (Eq. 14). Floats or arrays of the walkers' batch shape.
    """

    step_length: np.ndarray | float
    hip_height: np.ndarray | float


@dataclass(frozen=True, eq=False)
class WalkData:
    """W(S, sl) = {H, F1, F2, F3, M, A} (Eq. 4) with its walk condition.

    Attributes
    ----------
    body : BodyCondition
        S.
    step_length : numpy.ndarray | float
        sl [m]: N of the stance foot to N of the next one.
    previous_step_length : numpy.ndarray | float
        The step before this one [m] (the swing foot toes off one previous step behind).
    hip, ankle : TimedSequence
        H over [0, 1] and the swing ankle A over [TOM, 1], paths (..., n, 2) [m].
    foot1, foot2, foot3, meta : TimedSequence
        F1 [0, FGM], F2 [FGM, 1 + TOM], F3 [TOM, 1], M [MOM, 1 + TOM], angles [rad].
    law : GaitLaw
        μ1…μ4 of the prototype this walk was generalised from.
    """

    body: BodyCondition
    step_length: np.ndarray | float
    previous_step_length: np.ndarray | float
    hip: TimedSequence
    foot1: TimedSequence
    foot2: TimedSequence
    foot3: TimedSequence
    meta: TimedSequence
    ankle: TimedSequence
    law: GaitLaw

    def __post_init__(self) -> None:
        for name in ("step_length", "previous_step_length"):
            value = np.asarray(getattr(self, name), dtype=float)
            if not np.all(np.isfinite(value) & (value > 0)):
                raise invalid("WalkData", name, "finite and > 0 [m]", value)
            object.__setattr__(self, name, value)

    @property
    def fgm(self) -> float:
        """Flat ground moment of the stance foot (step time)."""
        return float(self.foot1.t[-1])

    @property
    def tom(self) -> float:
        """Toe-off moment of the swing foot (step time); the stance foot's is 1 + TOM."""
        return float(self.foot3.t[0])

    @property
    def mom(self) -> float:
        """Meta-off moment of the stance foot (step time, > 1 when after HSM⁺)."""
        return float(self.meta.t[0])

    @property
    def start(self) -> StepStart:
        """The walk's own previous step and hip height at HSM⁻."""
        return StepStart(self.previous_step_length, self.hip.y[..., 0])

    def replace(self, **changes) -> WalkData:
        """A copy with some fields changed."""
        return replace(self, **changes)

    def take(self, index) -> WalkData:
        """The walkers at ``index`` of a batched walk (integer or boolean array)."""
        seqs = {k: q.with_values(q.v[index]) for k, q in self.sequences().items()}
        return self.replace(body=self.body.take(index),
                            step_length=self.step_length[index],
                            previous_step_length=self.previous_step_length[index],
                            **seqs)  # fmt: skip

    def sequences(self) -> dict[str, TimedSequence]:
        """The six timed sequences by name (H, F1, F2, F3, M, A order)."""
        return {k: getattr(self, k) for k in SEQUENCES}


SEQUENCES = ("hip", "foot1", "foot2", "foot3", "meta", "ankle")


@lru_cache(maxsize=1)
def _prototype_text() -> str:
    ref = resources.files("crowdwalk").joinpath("data", "ko_badler_prototype.json")
    return ref.read_text(encoding="utf-8")


def load_prototype() -> WalkData:
    """The shipped prototype walk W̄(S*, sl*) (``crowdwalk/data/ko_badler_prototype.json``).

    Measured from Winter's normal-walk markers (see ``crowdwalk/data/README.md``).
    """
    return walk_from_dict(json.loads(_prototype_text()))


def walk_from_dict(d: dict) -> WalkData:
    """A :class:`WalkData` from the JSON layout written by the derive script."""
    seqs = {k: TimedSequence(np.array(d[k]["t"]), np.array(d[k]["v"])) for k in SEQUENCES}
    return WalkData(
        body=BodyCondition(**d["body"]),
        step_length=d["step_length"],
        previous_step_length=d["previous_step_length"],
        law=GaitLaw(np.array(d["law"]["alpha"]), np.array(d["law"]["mu_star"]),
                    float(d["law"]["step_ratio"])),
        **seqs,
    )  # fmt: skip


def walk_to_dict(w: WalkData, digits: int = 9) -> dict:
    """The JSON layout of a single (unbatched) walk, values rounded to ``digits``."""

    def r(a) -> list | float:
        return np.round(np.asarray(a, dtype=float), digits).tolist()

    out: dict = {
        "body": {k: float(getattr(w.body, k)) for k in _BODY_FIELDS},
        "step_length": float(w.step_length),
        "previous_step_length": float(w.previous_step_length),
        "law": {"alpha": r(w.law.alpha), "mu_star": r(w.law.mu_star),
                "step_ratio": round(float(w.law.step_ratio), digits)},
    }  # fmt: skip
    for k, q in w.sequences().items():
        out[k] = {"t": r(q.t), "v": r(q.v)}
    return out
