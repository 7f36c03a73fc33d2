"""Sagittal elevation-angle datasets derived from measured gait data.

A dataset is one mean gait cycle of one leg in the representation of Sun & Metaxas
(2001, §4): the sagittal elevation angles of foot, shank, thigh and pelvis over a
normalised stride ``t ∈ [0, 1)``, ``t = 0`` at heel strike of the leg it describes (the
other leg uses ``t + 0.5``; the measured curves are time-warped so that the other foot's
measured heel strike falls at ``t = 0.5``). Angle conventions are those of ``docs/architecture.md``
("crowdwalk.gait"):

- shank, thigh: angle of the proximal→distal vector (hip→knee, knee→ankle) from the
  downward vertical, positive when the distal end is anterior [rad];
- foot: heel→toe vector from the forward horizontal, positive toe-up, 0 when the foot is
  flat on the ground at mid-stance [rad];
- pelvis: anterior tilt of the pelvis [rad], relative to the adult natural-speed cycle
  mean (≈ the standing posture), positive anterior.

The shipped file ``crowdwalk/data/elevation_datasets.npz`` is produced by
``scripts/derive_gait_data.py`` from Bovi et al. (2011), Gait & Posture 33:6–13 (adult
group means); see ``crowdwalk/data/README.md``. Spatiotemporal references (step length
and cadence against speed, stance and double-support fractions) are in
``crowdwalk/data/normative.json`` and read by :func:`normative`.

Lengths in a dataset are **normalised by body height** (dimensionless); multiply by the
walker's body height [m] to get metres.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from typing import Literal, get_args

import numba as nb
import numpy as np

from crowdwalk.errors import invalid

__all__ = [
    "ANGLE_NAMES",
    "DATASET_KINDS",
    "ElevationDataset",
    "load_datasets",
    "STAIR_CLOSURES",
    "dataset_by_name",
    "sample",
    "normative",
    "PelvisMotion",
    "pelvis_motion",
    "TrunkMotion",
    "trunk_motion",
]

ANGLE_NAMES: tuple[str, ...] = ("foot", "shank", "thigh", "pelvis")
"""Column order of :attr:`ElevationDataset.angles`."""

DatasetKind = Literal["level", "stairs_up", "stairs_down"]

DATASET_KINDS: tuple[str, ...] = get_args(DatasetKind)


@dataclass(frozen=True, eq=False)
class ElevationDataset:
    """One mean gait cycle as sagittal elevation angles (Sun & Metaxas 2001, §4).

    Attributes
    ----------
    name : str
        Identifier, e.g. ``"level_natural"``, ``"stairs_up"``.
    kind : {"level", "stairs_up", "stairs_down"}
        The task the data were measured in.
    speed : float
        Mean walking speed of the source group [m/s] (for ``body_height``).
    body_height : float
        Mean body height of the source group [m] (for converting the normalised lengths).
    stride_length : float
        Measured stride length (two steps) normalised by body height [1].
    step_height : float
        Height gained per step normalised by body height [1] (0 on level ground; positive
        up the stairs), measured from the angles by sagittal forward kinematics.
    stance_fraction : float
        Foot-off of this leg in dataset time t [1].
    double_support : float
        Part of the stride (in t) with both feet on the ground [1].
    stride_time : float
        Duration of one stride [s].
    angles : numpy.ndarray
        Shape (N, 4), elevation angles [rad] at ``t = arange(N) / N``, columns
        foot, shank, thigh, pelvis (:data:`ANGLE_NAMES`). Read-only.
    source : str
        Citation of the measured data.
    """

    name: str
    kind: DatasetKind
    speed: float
    body_height: float
    stride_length: float
    step_height: float
    stance_fraction: float
    double_support: float
    stride_time: float
    angles: np.ndarray = field(repr=False)
    source: str = ""

    def __post_init__(self) -> None:
        owner = "ElevationDataset"
        if self.kind not in DATASET_KINDS:
            raise invalid(owner, "kind", f"one of {DATASET_KINDS}", self.kind)
        units = {"speed": "m/s", "body_height": "m", "stride_length": "1", "stride_time": "s"}
        for name, unit in units.items():
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise invalid(owner, name, f"finite and > 0 [{unit}]", value)
        for name in ("stance_fraction", "double_support"):
            value = getattr(self, name)
            if not (np.isfinite(value) and 0 < value < 1):
                raise invalid(owner, name, "in (0, 1) [1]", value)
        if not np.isfinite(self.step_height):
            raise invalid(owner, "step_height", "finite [1]", self.step_height)
        angles = np.array(self.angles, dtype=float)
        if angles.ndim != 2 or angles.shape[1] != 4 or angles.shape[0] < 8:
            raise invalid(owner, "angles", "an (N, 4) array with N >= 8 [rad]", angles.shape)
        if not np.all(np.isfinite(angles)):
            raise invalid(owner, "angles", "finite [rad]", "non-finite values")
        angles.setflags(write=False)
        object.__setattr__(self, "angles", angles)

    @property
    def samples(self) -> int:
        """Number of samples N per stride."""
        return self.angles.shape[0]

    @property
    def cadence(self) -> float:
        """Steps per second [1/s]."""
        return 2.0 / self.stride_time


def sample(angles: ElevationDataset | np.ndarray, t: np.ndarray | float,
           rows: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
    """Elevation angles at normalised stride times, periodic cubic interpolation.

    Catmull–Rom (C¹) interpolation of the uniformly sampled periodic curve; exact at the
    sample points.

    Parameters
    ----------
    angles : ElevationDataset or numpy.ndarray
        A dataset, an (N, 4) curve, or a batch of curves (n, N, 4) [rad] sampled at
        ``t = arange(N) / N``.
    t : float or numpy.ndarray
        Normalised stride times [1], any real values (wrapped into [0, 1)). For a batch of
        curves, shape (n,) — one time per curve — or broadcastable to it.
    rows : numpy.ndarray, optional
        For a batch of curves: the curve (k,) of each of k times ``t`` (k,), instead of
        one time per curve (saves gathering the curves first).

    Returns
    -------
    numpy.ndarray
        Angles [rad]: shape ``t.shape + (4,)`` for one curve, (n, 4) for a batch, (k, 4)
        with ``rows``.
    """
    curves = angles.angles if isinstance(angles, ElevationDataset) else np.asarray(angles)
    t = np.asarray(t, dtype=float)
    if not np.all(np.isfinite(t)):
        raise invalid("sample", "t", "finite [1]", t[~np.isfinite(t)].ravel()[:3])
    if curves.ndim not in (2, 3) or curves.shape[-1] != 4:
        raise invalid("sample", "angles", "an (N, 4) or (n, N, 4) array [rad]", curves.shape)
    fast = _sample_fast(curves, t, rows)
    return _sample_numpy(curves, t, rows) if fast is None else fast


def _sample_numpy(curves: np.ndarray, t: np.ndarray, rows) -> np.ndarray:
    """:func:`sample` in numpy (checked arguments): what ``_sample_kernel`` compiles."""
    n_samples = curves.shape[-2]
    u = np.mod(t, 1.0) * n_samples
    i1 = np.floor(u).astype(np.intp)
    s = (u - i1)[..., None]
    i0, i2, i3 = (i1 - 1) % n_samples, (i1 + 1) % n_samples, (i1 + 2) % n_samples
    i1 = i1 % n_samples
    if curves.ndim == 2:
        p0, p1, p2, p3 = curves[i0], curves[i1], curves[i2], curves[i3]
    else:
        rows = np.arange(curves.shape[0]) if rows is None else np.asarray(rows)
        i0, i1, i2, i3 = np.broadcast_arrays(i0, i1, i2, i3, rows)[:4]
        p0, p1, p2, p3 = (curves[rows, i] for i in (i0, i1, i2, i3))
    s2 = s * s
    s3 = s2 * s
    return 0.5 * (
        2.0 * p1
        + (p2 - p0) * s
        + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * s2
        + (3.0 * p1 - p0 - 3.0 * p2 + p3) * s3
    )


@nb.njit(cache=True, nogil=True)
def _sample_kernel(curves, t, rows, out):  # pragma: no cover - compiled
    """Catmull-Rom samples out (m, 4) of curves (B, N, 4) at times t (m,) of rows (m,);
    the arithmetic of :func:`sample`'s numpy code in the same order (bitwise equal)."""
    n = curves.shape[1]
    for a in range(t.shape[0]):
        u = (t[a] % 1.0) * n
        i1 = int(np.floor(u))
        s = u - float(i1)
        if n >= 3 and 0 <= i1 <= n:  # the common case without integer divisions
            i0 = i1 - 1 if i1 > 0 else i1 - 1 + n
            i2 = i1 + 1 if i1 + 1 < n else i1 + 1 - n
            i3 = i1 + 2 if i1 + 2 < n else i1 + 2 - n
            i1 = i1 if i1 < n else i1 - n
        else:
            i0, i2, i3 = (i1 - 1) % n, (i1 + 1) % n, (i1 + 2) % n
            i1 = i1 % n
        r = rows[a]
        s2 = s * s
        s3 = s2 * s
        for c in range(4):
            p0, p1, p2, p3 = curves[r, i0, c], curves[r, i1, c], curves[r, i2, c], curves[r, i3, c]
            out[a, c] = 0.5 * (
                2.0 * p1
                + (p2 - p0) * s
                + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * s2
                + (3.0 * p1 - p0 - 3.0 * p2 + p3) * s3
            )


def _sample_fast(curves: np.ndarray, t: np.ndarray, rows) -> np.ndarray | None:
    """:func:`sample` by :func:`_sample_kernel` (shape t.shape + (4,) or the broadcast of
    t and rows + (4,)); None where the numpy code has to run (not float64, odd rows)."""
    if curves.dtype != np.float64 or t.ndim == 0 and curves.ndim == 3:
        return None
    if curves.ndim == 2:
        shape, rr = t.shape, np.zeros(t.size, np.intp)
        curves = curves[None]
        tt = t.reshape(-1)
    else:
        rows = np.arange(curves.shape[0]) if rows is None else np.asarray(rows)
        if rows.dtype.kind not in "iu":
            return None
        tb, rb = (t, rows) if t.shape == rows.shape else np.broadcast_arrays(t, rows)
        shape, tt, rr = tb.shape, tb.reshape(-1), np.ascontiguousarray(rb.reshape(-1), np.intp)
        if rr.size and (rr.min() < -curves.shape[0] or rr.max() >= curves.shape[0]):
            return None
    out = np.empty((tt.size, 4))
    _sample_kernel(np.ascontiguousarray(curves), np.ascontiguousarray(tt), rr, out)
    return out.reshape(shape + (4,))


@nb.njit(cache=True, nogil=True)
def _series_kernel(coef, k, t, out):  # pragma: no cover - compiled
    """out (m,) = sum over h of coef[2h] cos(2 pi k_h t) + coef[2h+1] sin(2 pi k_h t), summed
    in harmonic order as :meth:`PelvisMotion._series`'s numpy code (bitwise equal)."""
    for a in range(t.shape[0]):
        acc = 0.0
        for h in range(k.shape[0]):
            x = 2 * np.pi * k[h] * t[a]
            term = coef[2 * h] * np.cos(x) + coef[2 * h + 1] * np.sin(x)
            acc = term if h == 0 else acc + term
        out[a] = acc


@nb.njit(cache=True, nogil=True)
def _series2_kernel(coef_a, coef_b, k, t, out_a, out_b):  # pragma: no cover - compiled
    """:func:`_series_kernel` of two coefficient sets over the same harmonics and times,
    each cosine and sine evaluated once (the same values as two calls)."""
    for a in range(t.shape[0]):
        acc_a = acc_b = 0.0
        for h in range(k.shape[0]):
            x = 2 * np.pi * k[h] * t[a]
            c, s = np.cos(x), np.sin(x)
            term_a = coef_a[2 * h] * c + coef_a[2 * h + 1] * s
            term_b = coef_b[2 * h] * c + coef_b[2 * h + 1] * s
            acc_a = term_a if h == 0 else acc_a + term_a
            acc_b = term_b if h == 0 else acc_b + term_b
        out_a[a], out_b[a] = acc_a, acc_b


#: How the stair cycles, which do not close, were made periodic (``load_datasets``):
#: "swing" — the drift removed over the swing alone, the stance as measured (default);
#: "linear" — removed linearly over the whole cycle, as the level cycles (before gait11).
STAIR_CLOSURES: tuple[str, ...] = ("swing", "linear")


@cache
def _load_npz(stair_closure: str = "swing") -> tuple[ElevationDataset, ...]:
    if stair_closure not in STAIR_CLOSURES:
        raise invalid("load_datasets", "stair_closure", f"one of {STAIR_CLOSURES}",
                      stair_closure)
    suffix = "" if stair_closure == "swing" else "_linear"
    ref = resources.files("crowdwalk").joinpath("data", "elevation_datasets.npz")
    with ref.open("rb") as handle, np.load(handle, allow_pickle=False) as data:
        meta = json.loads(str(data["meta" + suffix]))
        angles = data["angles" + suffix].astype(float)
    return tuple(
        ElevationDataset(angles=angles[k], **entry) for k, entry in enumerate(meta["datasets"])
    )


def load_datasets(stair_closure: str = "swing") -> list[ElevationDataset]:
    """The shipped elevation-angle datasets, derived from Bovi et al. (2011).

    Parameters
    ----------
    stair_closure : {"swing", "linear"}
        How the stair cycles (Bovi's do not close: the ascent thigh ends 48° below its
        start) are made periodic (:data:`STAIR_CLOSURES`); the level datasets are the
        same in both.

    Returns
    -------
    list of ElevationDataset
        Five level-ground speeds (``level_xs``, ``level_s``, ``level_natural``,
        ``level_m``, ``level_l``; increasing stride length) and ``stairs_up``,
        ``stairs_down``.
    """
    return list(_load_npz(stair_closure))


def dataset_by_name(name: str) -> ElevationDataset:
    """The shipped dataset called ``name`` (see :func:`load_datasets`)."""
    for dataset in _load_npz():
        if dataset.name == name:
            return dataset
    names = [d.name for d in _load_npz()]
    raise invalid("dataset_by_name", "name", f"one of {names}", name)


@cache
def _load_normative() -> str:
    ref = resources.files("crowdwalk").joinpath("data", "normative.json")
    return ref.read_text(encoding="utf-8")


def normative() -> dict:
    """Spatiotemporal reference values with citations (``crowdwalk/data/normative.json``).

    Returns
    -------
    dict
        A fresh copy: ``step_length_vs_speed`` (fitted relation with its range),
        ``cadence_vs_speed``, ``adult_normal_pace`` ranges, ``phases`` (stance and double
        support fractions), each entry with ``source``. Units are in the key names (SI).
    """
    return json.loads(_load_normative())


@dataclass(frozen=True, eq=False)
class PelvisMotion:
    """Pelvic list and transverse rotation over the stride, unit peak (Bovi 2011, adult
    natural level walking; ``crowdwalk/data/pelvis_motion.json``).

    ``list_shape(t)`` and ``rotation_shape(t)`` (shape of t) [1] are the measured curves
    divided by their largest magnitude over the stride: + the leg's own side up / forward,
    t the dataset stride time (t = 0 at its heel strike), and c(t + 0.5) = −c(t), so the
    other leg reads the same curve. ``list_peak``, ``rotation_peak`` [rad] are the
    measured amplitudes (the style's pelvic_list / pelvic_rotation scale the shapes).
    """

    harmonics: tuple[int, ...]
    list_coefficients: np.ndarray
    rotation_coefficients: np.ndarray
    list_peak: float
    rotation_peak: float

    @staticmethod
    def _series(coef: np.ndarray, harmonics, t) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        k = np.asarray(harmonics, dtype=float)
        if (t.ndim and coef.dtype == np.float64 and coef.ndim == 1 and k.size
                and coef.shape[0] == 2 * k.size):
            out = np.empty(t.size)
            _series_kernel(np.ascontiguousarray(coef), k, np.ascontiguousarray(t).reshape(-1),
                           out)
            return out.reshape(t.shape)
        t = t[..., None]
        return np.sum(coef[0::2] * np.cos(2 * np.pi * k * t)
                      + coef[1::2] * np.sin(2 * np.pi * k * t), axis=-1)

    def list_shape(self, t) -> np.ndarray:
        """Pelvic list at stride times t, + own side up, peak 1 [1]."""
        return self._series(self.list_coefficients, self.harmonics, t)

    def rotation_shape(self, t) -> np.ndarray:
        """Pelvic rotation at stride times t, + own side forward, peak 1 [1]."""
        return self._series(self.rotation_coefficients, self.harmonics, t)

    def shapes(self, t) -> tuple[np.ndarray, np.ndarray]:
        """(:meth:`list_shape`, :meth:`rotation_shape`) at stride times t, the harmonics
        evaluated once for both (the same values)."""
        t = np.asarray(t, dtype=float)
        la, ro = self.list_coefficients, self.rotation_coefficients
        k = np.asarray(self.harmonics, dtype=float)
        if not (t.ndim and la.dtype == ro.dtype == np.float64 and la.ndim == ro.ndim == 1
                and k.size and la.shape[0] == ro.shape[0] == 2 * k.size):
            return self.list_shape(t), self.rotation_shape(t)
        flat = np.ascontiguousarray(t).reshape(-1)
        out_a, out_b = np.empty(flat.size), np.empty(flat.size)
        _series2_kernel(np.ascontiguousarray(la), np.ascontiguousarray(ro), k, flat, out_a,
                        out_b)
        return out_a.reshape(t.shape), out_b.reshape(t.shape)


@cache
def pelvis_motion(task: str = "Natural") -> PelvisMotion:
    """The shipped pelvic list / rotation shapes of one of Bovi's level tasks (``"XS"``,
    ``"S"``, ``"Natural"``, ``"M"``, ``"L"``), normalised to unit peak."""
    ref = resources.files("crowdwalk").joinpath("data", "pelvis_motion.json")
    data = json.loads(ref.read_text(encoding="utf-8"))
    if task not in data["tasks"]:
        raise invalid("pelvis_motion", "task", f"one of {list(data['tasks'])}", task)
    entry, harmonics = data["tasks"][task], tuple(data["harmonics"])
    grid = np.arange(1000) / 1000
    out = {}
    for key in ("list", "rotation"):
        coef = np.deg2rad(np.asarray(entry[key]["coefficients_deg"], dtype=float))
        peak = float(np.abs(PelvisMotion._series(coef, harmonics, grid)).max())
        out[key] = (coef / peak, peak)
    return PelvisMotion(harmonics, out["list"][0], out["rotation"][0], out["list"][1],
                        out["rotation"][1])


@dataclass(frozen=True, eq=False)
class TrunkMotion:
    """Trunk (thorax) rotation and sagittal tilt wave over the stride (Schwartz et al.
    2008, Free speed; ``crowdwalk/data/trunk_motion.json``; Bovi 2011 has no trunk).

    ``rotation_shape(t)`` [1]: + the leg's own side forward, unit peak, c(t + 0.5) =
    −c(t) (against the pelvis: −0.99 at heel strike); ``rotation_peak`` [rad];
    ``tilt_wave(t)`` [rad]: + anterior, about the cycle mean (the mean, Plug-in Gait's
    thorax offset, is not a lean and is not used).
    """

    rotation_harmonics: tuple[int, ...]
    rotation_coefficients: np.ndarray
    rotation_peak: float
    tilt_harmonics: tuple[int, ...]
    tilt_coefficients: np.ndarray

    def rotation_shape(self, t) -> np.ndarray:
        """Trunk rotation at stride times t, + own side forward, peak 1 [1]."""
        return PelvisMotion._series(self.rotation_coefficients, self.rotation_harmonics, t)

    def tilt_wave(self, t) -> np.ndarray:
        """Trunk tilt about its mean at stride times t, + anterior [rad]."""
        return PelvisMotion._series(self.tilt_coefficients, self.tilt_harmonics, t)


@cache
def trunk_motion() -> TrunkMotion:
    """The shipped trunk rotation shape (unit peak) and tilt wave."""
    ref = resources.files("crowdwalk").joinpath("data", "trunk_motion.json")
    data = json.loads(ref.read_text(encoding="utf-8"))
    rot, tilt = data["rotation"], data["tilt"]
    coef = np.deg2rad(np.asarray(rot["coefficients_deg"], dtype=float))
    harmonics = tuple(rot["harmonics"])
    peak = float(np.abs(PelvisMotion._series(coef, harmonics, np.arange(1000) / 1000)).max())
    return TrunkMotion(harmonics, coef / peak, peak, tuple(tilt["harmonics"]),
                       np.deg2rad(np.asarray(tilt["coefficients_deg"], dtype=float)))
