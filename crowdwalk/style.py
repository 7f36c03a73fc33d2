"""A walker's style: KLAW's locomotion parameters and 15 attributes (Bruderlin & Calvert 1993).

Every walker of a crowd has its own style, held as a struct-of-arrays (:class:`Style`, one
(n,) array per attribute, SI units) that every gait engine and the planner read:

- **Locomotion parameters** (§3, Fig. 7): step length [m], step frequency [steps/s] and
  velocity [m/s], tied by velocity = step length × step frequency. In *normal* mode the
  step length follows the walker's current speed through the measured normal-mode
  relation (:func:`normal_step_length`, ``planners.normal_mode``) and the frequency is
  their ratio. In *locked* mode one parameter is held (``lock: {step_length: 0.75}``);
  a second given parameter sets one of the two sliders (the paper's proud walk: velocity
  4 km/h locked, step length 0.75 m), the third follows from the product.
- **15 locomotion attributes** (§3, Fig. 8) in five arm, two torso, two pelvis and six
  leg attributes (:data:`ATTRIBUTES`, each with its unit, default and range).
- **Presets** after Fig. 11 (:data:`PRESETS`): normal, proud, muscle_man, marching,
  bouncy, loose, happy, tired.

In scenario files a group says ``style: {preset: <name>, <attribute>: <value> or {mean,
sd}}`` and ``lock: {...}``; angles are degrees there and radians here. The paper's own
normalising formulae for normal mode are in its ref. [3] (Bruderlin & Calvert 1989), which
is not among the project's sources; normal mode uses the measured step-length relation
of ``planners.normal_mode`` instead (Alexander's power law fitted to WBDS).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from typing import Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, create_model, field_validator, model_validator

from crowdwalk.errors import invalid

__all__ = [
    "Attribute",
    "ATTRIBUTES",
    "ATTRIBUTE_NAMES",
    "PRESETS",
    "PRESET_NAMES",
    "LOCKS",
    "GAIT_NAMES",
    "Style",
    "StyleSpec",
    "LockSpec",
    "Spread",
    "normal_step_length",
    "sample_styles",
    "summary_by_style",
]

GaitName = Literal["elevation_angles", "klaw", "ko_badler"]
GAIT_NAMES: tuple[str, ...] = ("elevation_angles", "klaw", "ko_badler")

#: Lock codes of :attr:`Style.lock`, index = code.
LOCKS: tuple[str, ...] = ("none", "step_length", "step_frequency", "velocity")


@dataclass(frozen=True)
class Attribute:
    """One locomotion attribute: ``unit`` in files (``deg``, ``m`` or ``1``), its default
    and range [lo, hi] in that unit, and what it controls."""

    name: str
    unit: str
    default: float
    lo: float
    hi: float
    doc: str

    @property
    def to_si(self) -> float:
        """Factor from the file unit to SI (degrees to radians)."""
        return math.pi / 180.0 if self.unit == "deg" else 1.0


#: The 15 attributes (Fig. 8).
ATTRIBUTES: tuple[Attribute, ...] = (
    Attribute("shoulder_rotation", "deg", 5.0, 0.0, 20.0,
              "amplitude of the shoulder line's rotation about the vertical, against the "
              "pelvis (transverse plane)"),
    Attribute("arm_swing", "deg", 15.0, 0.0, 45.0,
              "amplitude of the upper arm's swing in the sagittal plane, forward with the "
              "opposite leg"),
    Attribute("arm_out", "deg", 5.0, 0.0, 30.0,
              "abduction of the upper arms (coronal plane)"),
    Attribute("elbow_min", "deg", 15.0, 0.0, 120.0,
              "least elbow flexion over a stride (arm back)"),
    Attribute("elbow_max", "deg", 35.0, 0.0, 150.0,
              "greatest elbow flexion over a stride (arm forward); >= elbow_min"),
    Attribute("torso_tilt", "deg", 0.0, -10.0, 40.0,
              "forward tilt of the trunk from the vertical (0 upright)"),
    Attribute("torso_sway", "deg", 0.0, 0.0, 15.0,
              "amplitude of the trunk's lateral lean over the stance leg (coronal plane)"),
    Attribute("pelvic_rotation", "deg", 4.0, 0.0, 20.0,
              "amplitude of the pelvis's rotation about the vertical, greatest at heel "
              "strike (transverse plane)"),
    Attribute("pelvic_list", "deg", 4.0, 0.0, 15.0,
              "amplitude of the pelvic list, swing side down (coronal plane)"),
    Attribute("bounciness", "1", 1.0, 0.0, 4.0,
              "KLAW's bounce_factor (§2.2): the dip of the stance hip in double support, "
              "and the vertical pelvis excursion, relative to the normal walk"),
    Attribute("knee_stance_min", "deg", 8.0, 0.0, 40.0,
              "KLAW's knee_bend (§2.2): least knee flexion in single stance"),
    Attribute("knee_impact", "deg", 3.0, 0.0, 30.0,
              "knee flexion at heel strike"),
    Attribute("toe_clearance", "m", 0.02, 0.005, 0.08,
              "least height of the swing foot above the ground (planner and gait engine)"),
    Attribute("foot_angle", "deg", 7.0, -15.0, 30.0,
              "toe-out of the feet from the walking direction"),
    Attribute("stride_width", "m", 0.1, 0.0, 0.4,
              "lateral distance between the left and right ankle lines (adult 8-10 cm)"),
)
ATTRIBUTE_NAMES: tuple[str, ...] = tuple(a.name for a in ATTRIBUTES)
_ATTR = {a.name: a for a in ATTRIBUTES}

#: Fig. 11's walks as attribute sets (file units), with ``lock`` and ``velocity`` [m/s]
#: where the walk sets them. proud and tired follow §4's description ("almost maximum" =
#: 90 % of the range, "slightly" = a quarter of it for tilt, a few degrees for sway); the
#: others are chosen here (the paper shows them only as pictures) and documented in
#: docs/architecture.md.
PRESETS: dict[str, dict] = {
    "normal": {},
    "proud": {"lock": {"velocity": 4.0 / 3.6, "step_length": 0.75},
              "foot_angle": 26.0, "arm_swing": 40.0, "arm_out": 27.0,
              "shoulder_rotation": 18.0},
    "muscle_man": {"arm_out": 25.0, "elbow_min": 30.0, "elbow_max": 50.0,
                   "shoulder_rotation": 12.0, "stride_width": 0.2, "torso_sway": 4.0,
                   "pelvic_list": 2.0, "pelvic_rotation": 2.0, "arm_swing": 20.0},
    # quick time: 120 steps/min of 30 in (0.76 m), US Army FM 3-21.5 (2003), §4-1.
    "marching": {"lock": {"step_frequency": 2.0, "step_length": 0.76},
                 "arm_swing": 35.0, "elbow_min": 0.0, "elbow_max": 5.0,
                 "knee_impact": 0.0, "knee_stance_min": 2.0, "toe_clearance": 0.06,
                 "pelvic_rotation": 3.0, "shoulder_rotation": 2.0, "torso_tilt": 0.0},
    "bouncy": {"bounciness": 3.5, "knee_stance_min": 18.0, "knee_impact": 10.0,
               "toe_clearance": 0.06, "arm_swing": 20.0},
    "loose": {"arm_swing": 30.0, "elbow_min": 5.0, "elbow_max": 55.0, "pelvic_rotation": 10.0,
              "pelvic_list": 8.0, "shoulder_rotation": 12.0, "torso_sway": 5.0,
              "knee_stance_min": 12.0},
    "happy": {"velocity": 1.5, "bounciness": 2.0, "arm_swing": 25.0, "elbow_max": 50.0,
              "toe_clearance": 0.04, "torso_tilt": -3.0},
    "tired": {"velocity": 3.0 / 3.6, "arm_swing": 3.0, "torso_tilt": 10.0, "torso_sway": 3.0,
              "bounciness": 1.5},
}
PRESET_NAMES: tuple[str, ...] = tuple(PRESETS)
PresetName = Literal[PRESET_NAMES]  # type: ignore[valid-type]


# --- the struct-of-arrays -------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Style:
    """Styles of n walkers, SI units, one (n,) array per field.

    The 15 attributes of :data:`ATTRIBUTES` (angles [rad], ``toe_clearance`` and
    ``stride_width`` [m], ``bounciness`` [1]) and the locomotion parameters:
    ``velocity`` the walker's desired speed [m/s]; ``step_length`` [m] and
    ``step_frequency`` [steps/s] where held (locked or set), NaN where they follow
    (normal mode); ``lock`` the locked parameter's code in :data:`LOCKS`; ``preset`` the
    preset index in :data:`PRESET_NAMES` (-1: none).
    """

    shoulder_rotation: np.ndarray
    arm_swing: np.ndarray
    arm_out: np.ndarray
    elbow_min: np.ndarray
    elbow_max: np.ndarray
    torso_tilt: np.ndarray
    torso_sway: np.ndarray
    pelvic_rotation: np.ndarray
    pelvic_list: np.ndarray
    bounciness: np.ndarray
    knee_stance_min: np.ndarray
    knee_impact: np.ndarray
    toe_clearance: np.ndarray
    foot_angle: np.ndarray
    stride_width: np.ndarray
    velocity: np.ndarray
    step_length: np.ndarray
    step_frequency: np.ndarray
    lock: np.ndarray
    preset: np.ndarray

    def __post_init__(self) -> None:
        n = self.velocity.shape[0]
        for f in fields(self):
            arr = getattr(self, f.name)
            if arr.shape != (n,):
                raise invalid("Style", f.name, f"of shape ({n},)", arr.shape)
        for a in ATTRIBUTES:
            x = getattr(self, a.name) / a.to_si
            if not np.all((x >= a.lo - 1e-9) & (x <= a.hi + 1e-9)):
                bad = x[~((x >= a.lo - 1e-9) & (x <= a.hi + 1e-9))][0]
                raise invalid("Style", a.name, f"in [{a.lo:g}, {a.hi:g}] [{a.unit}]", float(bad))
        if np.any(self.elbow_max < self.elbow_min - 1e-12):
            raise invalid("Style", "elbow_max", ">= elbow_min [deg]",
                          float(np.rad2deg(self.elbow_max).min()))
        if not np.all(self.velocity > 0):
            raise invalid("Style", "velocity", "> 0 [m/s]", float(self.velocity.min()))

    def __len__(self) -> int:
        return int(self.velocity.shape[0])

    @classmethod
    def default(cls, body_height: np.ndarray, velocity: np.ndarray) -> Style:
        """The normal walk (defaults, normal mode) for bodies (n,) [m] at speeds (n,) [m/s]."""
        h = np.asarray(body_height, dtype=float)
        cols = {a.name: np.full(h.shape, a.default * a.to_si) for a in ATTRIBUTES}
        nan = np.full(h.shape, np.nan)
        return cls(**cols, velocity=np.broadcast_to(np.asarray(velocity, float), h.shape).copy(),
                   step_length=nan, step_frequency=nan.copy(),
                   lock=np.zeros(h.shape, np.int8), preset=np.full(h.shape, -1, np.int8))

    def take(self, index) -> Style:
        """The styles at ``index`` (integer or boolean array)."""
        index = np.asarray(index)
        if index.ndim != 1:
            return Style(**{f.name: getattr(self, f.name)[index] for f in fields(self)})
        # rows of validated columns: the checks of __post_init__ hold, skip them
        out = object.__new__(Style)
        for name in _STYLE_FIELDS:
            object.__setattr__(out, name, getattr(self, name)[index])
        return out

    def with_values(self, **columns) -> Style:
        """A copy with the given (n,) columns replaced (SI units)."""
        n = len(self)
        dtype = {"lock": np.int8, "preset": np.int8}
        return replace(self, **{k: np.broadcast_to(np.asarray(v, dtype.get(k, float)), (n,)).copy()
                                for k, v in columns.items()})

    def locomotion(self, speed: np.ndarray, body_height: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
        """Step length [m] and step frequency [steps/s] (n,) at current speeds (n,) [m/s].

        Normal mode: the step length of the measured relation at ``speed`` for bodies
        (n,) [m] (:func:`normal_step_length`); the frequency is speed / step length. A held step
        length stays; a held frequency gives step length = speed / frequency (§3).
        """
        v = np.maximum(np.asarray(speed, dtype=float), 1e-3)
        held_l = np.isfinite(self.step_length)
        held_f = np.isfinite(self.step_frequency) & ~held_l
        sl = np.where(held_l, self.step_length,
                      np.where(held_f, v / np.where(held_f, self.step_frequency, 1.0),
                               normal_step_length(v, body_height)))
        return sl, v / sl

    @property
    def preset_name(self) -> np.ndarray:
        """Preset name per walker (n,) (``""`` where none)."""
        names = np.asarray(PRESET_NAMES + ("",), dtype=object)
        return names[self.preset]


_STYLE_FIELDS = tuple(f.name for f in fields(Style))

def normal_step_length(speed: np.ndarray, body_height: np.ndarray) -> np.ndarray:
    """Normal-mode step length [m] at ``speed`` (n,) [m/s] for bodies (n,) [m]: the
    measured relation ``planners.normal_mode.step_length`` (WBDS fit) at the body's leg
    length."""
    from planners.normal_mode import leg_length_from_height, step_length

    return step_length(speed, leg_length_from_height(body_height))


# --- the scenario file's edge -----------------------------------------------------------


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class Spread(_Model):
    """A normal distribution of an attribute over a group, truncated to its range."""

    mean: float
    sd: float = Field(0.0, ge=0)


class LockSpec(_Model):
    """Locked mode (§3): the locked parameter and at most one more (the third follows from
    velocity = step length × step frequency)."""

    step_length: float | None = Field(None, gt=0.1, le=1.5, description="[m], (0.1, 1.5]")
    step_frequency: float | None = Field(None, gt=0.3, le=4.0,
                                         description="[steps/s], (0.3, 4]")
    velocity: float | None = Field(None, gt=0.1, le=3.0, description="[m/s], (0.1, 3]")

    @model_validator(mode="after")
    def _one_or_two(self):
        given = [k for k in LOCKS[1:] if getattr(self, k) is not None]
        if not 1 <= len(given) <= 2:
            raise ValueError("give one locked parameter (step_length, step_frequency or "
                             "velocity) and at most one more")
        return self

    @property
    def locked(self) -> str:
        """The locked parameter: velocity if given, else step_frequency, else step_length
        (a second given parameter is a slider setting)."""
        return next(k for k in ("velocity", "step_frequency", "step_length")
                    if getattr(self, k) is not None)

    def held(self) -> tuple[float, float, float | None]:
        """(step length [m] or NaN, step frequency [steps/s] or NaN, velocity [m/s] or
        None) that this lock holds; a pair of given values fixes the third."""
        sl, f, v = self.step_length, self.step_frequency, self.velocity
        if sl is not None and f is not None:
            v = sl * f
        if self.locked == "step_frequency":
            return math.nan, f, v
        return (math.nan if sl is None else sl), (math.nan if f is None else f), v


def _attribute_field(a: Attribute):
    default = f"{a.default:g}"
    return (float | Spread | None,
            Field(None, description=f"{a.doc} [{a.unit}], range [{a.lo:g}, {a.hi:g}], "
                                    f"default {default}; a value or {{mean, sd}}"))


def _check_range(cls, value, info):
    a = _ATTR[info.field_name]
    mean = value.mean if isinstance(value, Spread) else value
    if mean is not None and not (math.isfinite(mean) and a.lo <= mean <= a.hi):
        raise ValueError(f"must be in [{a.lo:g}, {a.hi:g}] [{a.unit}]")
    return value


StyleSpec = create_model(
    "StyleSpec",
    __base__=_Model,
    __doc__="A group's KLAW style: a preset (Fig. 11) and attributes overriding it.",
    __validators__={"_ranges": field_validator(*ATTRIBUTE_NAMES)(_check_range)},
    preset=(PresetName | None, Field(None, description=f"one of {', '.join(PRESET_NAMES)}")),
    **{a.name: _attribute_field(a) for a in ATTRIBUTES},
)


def _draw(value, a: Attribute, rng: np.random.Generator, n: int) -> np.ndarray:
    """(n,) values in the file unit: a constant, or normal draws resampled into the range."""
    if not isinstance(value, Spread):
        return np.full(n, float(value))
    if value.sd == 0:
        return np.full(n, value.mean)
    x = rng.normal(value.mean, value.sd, n)
    for _ in range(100):
        bad = (x < a.lo) | (x > a.hi)
        if not bad.any():
            break
        x[bad] = rng.normal(value.mean, value.sd, int(bad.sum()))
    return np.clip(x, a.lo, a.hi)


def sample_styles(groups, group: np.ndarray, body_height: np.ndarray, free_speed: np.ndarray,
                  rng: np.random.Generator) -> Style:
    """Draw the styles of n walkers from their groups' scenario entries.

    Parameters
    ----------
    groups : sequence of crowdwalk.scenario.Group
        With ``style`` (StyleSpec or None), ``lock`` (LockSpec or None) and whether
        ``free_speed`` was given (``model_fields_set``).
    group : (n,) int
        Each walker's group index.
    body_height, free_speed : (n,)
        [m], [m/s] as drawn for the population.
    rng : numpy.random.Generator
        Used only for attributes given as ``{mean, sd}`` with sd > 0 (group order, then
        attribute order), so scenarios without spreads draw nothing.

    Returns
    -------
    Style
        A preset's ``velocity`` replaces the free speed unless the group sets
        ``free_speed``; a locked velocity always does.
    """
    style = Style.default(body_height, free_speed)
    cols = {f.name: getattr(style, f.name).copy() for f in fields(style)}
    for gi, g in enumerate(groups):
        rows = np.flatnonzero(group == gi)
        spec = g.style
        preset = dict(PRESETS[spec.preset]) if spec is not None and spec.preset else {}
        if spec is not None and spec.preset:
            cols["preset"][rows] = PRESET_NAMES.index(spec.preset)
        values = {k: v for k, v in preset.items() if k in _ATTR}
        if spec is not None:
            values.update({k: getattr(spec, k) for k in ATTRIBUTE_NAMES
                           if getattr(spec, k) is not None})
        for name, value in values.items():
            a = _ATTR[name]
            cols[name][rows] = _draw(value, a, rng, rows.size) * a.to_si
        if "velocity" in preset and "free_speed" not in g.model_fields_set:
            cols["velocity"][rows] = preset["velocity"]
        lock = g.lock if g.lock is not None else (
            LockSpec(**preset["lock"]) if "lock" in preset else None)
        if lock is not None:
            sl, f, v = lock.held()
            cols["step_length"][rows], cols["step_frequency"][rows] = sl, f
            cols["lock"][rows] = LOCKS.index(lock.locked)
            if v is not None:
                cols["velocity"][rows] = v
    return Style(**cols)



def summary_by_style(agents: list[dict]) -> dict[str, dict]:
    """Per style (the agents' ``style`` key, a preset name or ``"custom"``): agents,
    arrived, mean travel time [s], energy per metre [J/(kg m)] (steps' energy over the
    distance walked), mean step length [m] and cadence [steps/s] of the agents in a
    run summary's ``agents`` list that stepped."""
    out: dict[str, dict] = {}
    for name in sorted({a.get("style", "") for a in agents}):
        rows = [a for a in agents if a.get("style", "") == name and a["steps"] > 0]
        if not rows:
            continue
        travel = [a["travel_time_s"] for a in rows if a["travel_time_s"] is not None]
        dist = sum(a["distance_m"] for a in rows)

        def mean(key, rows=rows):
            values = [a[key] for a in rows if a.get(key) is not None]
            return float(np.mean(values)) if values else None

        out[name or "custom"] = {
            "agents": len(rows), "arrived": len(travel),
            "gait": sorted({a.get("gait", "elevation_angles") for a in rows}),
            "travel_time_s": float(np.mean(travel)) if travel else None,
            "energy_per_metre_J_per_kg_m": (sum(a["energy_J_per_kg"] for a in rows) / dist
                                            if dist > 0 else None),
            "mean_step_length_m": mean("mean_step_length_m"),
            "cadence_steps_per_s": mean("cadence_steps_per_s"),
        }
    return out
