"""Planner parameters: search grid, legality limits and energy weights."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from planners.errors import invalid

__all__ = ["EnergyWeights", "PlannerConfig"]


#: Fitted by ``scripts/fit_energy_constants.py`` (see :meth:`EnergyWeights.fitted`).
FITTED_BETA = 0.0361
FITTED_DOWN_RATIO = 0.148
FITTED_C_CALF = 0.1


@dataclass(frozen=True)
class EnergyWeights:
    """Weights of the energy model, Eqs. (3)-(4) of Chen & Li.

    ``E = alpha*En + beta*Ev + gamma*Ej`` in J/kg per step.

    Parameters
    ----------
    alpha : float
        J/cal: Eq. (1) gives Ralston's energy in cal/kg per step; 4.184 J/cal.
    beta : float or None
        J/kg per unit of Eq. (2), chosen so that a 17 cm step up costs g*h/0.25 = 6.7 J/kg
        (25 % muscle efficiency for positive work, Margaria 1976): 0.0961 for the printed
        quadratic, 0.0549 for the linear form (None picks the one for ``vertical``).
    gamma : float
        Dimensionless weight of the joint-rotation term Ej.
    c_thigh, c_calf : float
        J/kg per radian of thigh and calf rotation (Eq. 3); chosen so that the flat-ground
        efficiency peaks near a 0.6 m step (Fig. 2) for the standard 1.75 m body.
    down_ratio : float
        Cost of stepping down relative to stepping up by the same height: negative
        work costs about a third of positive work (Abbott, Bigland & Ritchie 1952).
    vertical : {"linear", "paper"}
        Form of Ev (see :func:`planners.energy.vertical_energy`). Deviation: the default
        is ``"linear"`` (7.14 h, work against gravity at constant efficiency). With the
        printed concave quadratic a larger rise is cheaper per cm, so on ramps of 8 %
        or more the optimal step jumps to the longest of the grid (0.90 m for a 1.75 m
        body), while people shorten their steps uphill; with the linear form it drops
        from 0.65 m (level) to 0.60 m (5 %) and 0.55 m (10 %). Both cost the same for a
        17 cm stair riser. (Those figures are of the paper's step grid,
        ``step_model="paper"``; with the default normal-mode steps both forms give the
        same steps on ramps of 0-15 %: ``scripts/planner_switches.py``, which measures
        both under today's defaults.)
    frequency : float
        Weight kappa of the step-frequency term (``PlannerConfig.step_model =
        "normal_mode"``, :func:`planners.energy.frequency_energy`): a step taken at a
        frequency a fraction x off the normal-mode frequency for the speed costs
        ``kappa x^2`` times its Eq. 1 walking energy more [-].
    """

    alpha: float = 4.184
    beta: float | None = None
    gamma: float = 1.0
    c_thigh: float = 1.0
    c_calf: float = 0.1
    down_ratio: float = 1.0 / 3.0
    vertical: str = "linear"
    frequency: float = 10.0

    @classmethod
    def fitted(cls) -> EnergyWeights:
        """Constants fitted to measured metabolic costs (``scripts/fit_energy_constants.py``).

        ``beta`` and ``down_ratio`` from the gross cost of one 15 cm stair step up and down
        (Teh & Aziz 2002), validated against Bassett et al. 1997 (stairs) and Minetti et
        al. 2002 (slopes). ``c_calf / c_thigh`` stays 0.1: fitted to WBDS preferred step
        lengths at the comfortable speed (Fukuchi et al. 2018: 0.375 body heights) any
        ratio from 0 to 1 gives the same flat optimum, 0.375 body heights, so the data
        cannot fix it. The default of :class:`PlannerConfig` (closer than the hand-set
        constants to every validation figure; ``docs/architecture.md``).
        """
        return cls(beta=FITTED_BETA, down_ratio=FITTED_DOWN_RATIO, c_calf=FITTED_C_CALF)

    @classmethod
    def hand_set(cls) -> EnergyWeights:
        """The hand-set constants (the field defaults: ``beta`` from 25 % muscle
        efficiency, ``down_ratio`` 1/3), :class:`PlannerConfig`'s default until the fit."""
        return cls()

    @classmethod
    def paper(cls) -> EnergyWeights:
        """Chen & Li's Eq. 2 as printed (the concave quadratic, ``vertical="paper"``) with
        the hand-set weights."""
        return cls(vertical="paper")

    def __post_init__(self) -> None:
        if self.vertical not in ("paper", "linear"):
            raise invalid("EnergyWeights", "vertical", "'linear' or 'paper'", self.vertical)
        if self.beta is None:
            object.__setattr__(self, "beta", 0.0961 if self.vertical == "paper" else 0.0549)
        for name in ("alpha", "beta", "gamma", "c_thigh", "c_calf", "down_ratio",
                     "frequency"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0):
                raise invalid("EnergyWeights", name, "finite and >= 0", value)


@dataclass(frozen=True)
class PlannerConfig:
    """Search grid and legality limits (defaults follow §4.2 and §6.2).

    Lengths are in metres; ratios are fractions of the leg length (hip to ankle).

    Parameters
    ----------
    n_steps : int
        Planning horizon n (§4.2: three or four steps); 1..5.
    intervals : int
        Step-length grid intervals (§6.2: 13, also 11 and 7); the grid has
        ``intervals + 1`` step lengths.
    min_step_ratio, max_step_ratio : float
        Range of reasonable step lengths as fractions of the leg length [-].
    clearance : float
        Sole clearance of the swing foot over the ground [m].
    edge_margin : float
        Distance the foot keeps from a stair edge or riser [m].
    support_tolerance : float
        Largest unevenness tolerated under a foot, and largest height change that is
        not an edge [m].
    max_step_rise : float
        Largest height change of one step [m]. Eq. 2 is given for h < 40 cm, but with
        Eq. 5 over a fixed number of steps the model then prefers climbing stairs two
        treads at a time (more progress per step); 0.25 m (above the 0.22 m highest
        building-code riser) keeps walkers on one tread per step.
    max_foot_slope : float
        Steepest ground under a foot [rise/run].
    swing_lift : float
        Initial height of both Bezier control points above the chord midpoint [m] (§5.2).
    max_swing_lift : float
        Legal region of the control points: at most this high above the higher end [m].
    bezier_samples : int
        Samples of the swing curve used for collision checks.
    max_adjustments : int
        Most §5.2 adjustment rounds per curve before the step is illegal.
    knee_max_flexion : float
        Largest knee flexion at a key frame [rad].
    pelvis_height_ratio : float
        Pelvis above the stance ankle at mid-stance, fraction of the leg length [-].
    turn_threshold : float
        Largest foot rotation per step on curved paths (§5.4) [rad].
    search_starts : int
        Initial configurations of ``best_first_multistart`` (``best_first`` is the
        paper's single FIND_INIT + BFP and ignores this): 1 is the nearest legal
        configuration to the neutral one; 2 adds the energy-budget start, 3 the greedy
        one, more add constant-step starts, used only where the first three end in
        different local optima.
    snap : bool
        Let each lattice foothold slide by up to half a grid increment to the nearest
        position where the whole foot is supported (deviation from the fixed grid of
        §6.2: a 28-30 cm tread leaves a 26.6 cm foot only 2-3 cm of play, which a 5 cm
        grid usually misses). False gives the paper's rigid grid (measured in
        ``scripts/planner_switches.py``: 18 of 100 random-terrain walks then end at a
        missing foothold).
    terminal_cost : bool
        Compare the plans of a horizon for the same progress (deviation from §4.2, where
        Eq. 5 is taken over the n planned steps alone): every plan is scored by the
        efficiency of reaching the farthest foothold of the lattice, its own steps plus
        the estimated energy of walking on from its last foothold
        (:func:`planners.energy.terminal_energy`). Eq. 5 over the steps alone rewards a
        plan for leaving an expensive stretch (a stair flight, a curb) beyond the horizon:
        walked with a receding horizon, it shuffles up to a flight in ever shorter steps
        and costs more per metre than the unplanned walker (measured in
        ``docs/architecture.md``). On level ground the plans are the same either way.
        False gives the paper's criterion.
    step_model : {"normal_mode", "paper"}
        ``"normal_mode"`` (deviation from Chen & Li, issue 11): steps follow the speed as
        people's do. Each agent's step-length grid is shifted (by under half an
        increment) so that the normal-mode step for its speed and leg
        (:mod:`planners.normal_mode`, fitted to WBDS) is a grid node, that node is the
        neutral step (s_init), and every step pays the step-frequency term of
        :func:`planners.energy.frequency_energy`. ``"paper"``: the fixed grid of §6.2, the
        neutral step the most efficient on flat ground, Eqs. 1-4 alone (the step is then
        the same at every speed: 0.668 m for a 1.75 m body).
    weights : EnergyWeights
        Energy model weights; default :meth:`EnergyWeights.fitted` (the measured
        constants; :meth:`EnergyWeights.hand_set` and :meth:`EnergyWeights.paper` by
        name).
    """

    n_steps: int = 4
    intervals: int = 13
    min_step_ratio: float = 0.30
    max_step_ratio: float = 1.05
    clearance: float = 0.02
    edge_margin: float = 0.0
    support_tolerance: float = 0.02
    max_step_rise: float = 0.25
    max_foot_slope: float = 0.5
    swing_lift: float = 0.15
    max_swing_lift: float = 0.60
    bezier_samples: int = 20
    max_adjustments: int = 10
    knee_max_flexion: float = math.radians(130.0)
    pelvis_height_ratio: float = 0.96
    turn_threshold: float = math.radians(45.0)
    search_starts: int = 8
    snap: bool = True
    terminal_cost: bool = True
    step_model: str = "normal_mode"
    weights: EnergyWeights = field(default_factory=EnergyWeights.fitted)

    def __post_init__(self) -> None:
        ints = {"n_steps": (1, 5), "intervals": (2, 40), "bezier_samples": (4, 200),
                "max_adjustments": (0, 1000), "search_starts": (1, 41)}
        for name, (lo, hi) in ints.items():
            value = getattr(self, name)
            if not (isinstance(value, int) and lo <= value <= hi):
                raise invalid("PlannerConfig", name, f"an integer in [{lo}, {hi}]", value)
        positive = ("min_step_ratio", "max_step_ratio", "max_step_rise", "max_foot_slope",
                    "max_swing_lift", "knee_max_flexion", "pelvis_height_ratio",
                    "turn_threshold")
        for name in positive:
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise invalid("PlannerConfig", name, "finite and > 0", value)
        for name in ("clearance", "edge_margin", "support_tolerance", "swing_lift"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0):
                raise invalid("PlannerConfig", name, "finite and >= 0 [m]", value)
        if self.max_step_ratio <= self.min_step_ratio:
            raise invalid("PlannerConfig", "max_step_ratio",
                          f"> min_step_ratio = {self.min_step_ratio:g}", self.max_step_ratio)
        if self.pelvis_height_ratio > 1:
            raise invalid("PlannerConfig", "pelvis_height_ratio", "<= 1",
                          self.pelvis_height_ratio)
        if not isinstance(self.snap, bool):
            raise invalid("PlannerConfig", "snap", "True or False", self.snap)
        if not isinstance(self.terminal_cost, bool):
            raise invalid("PlannerConfig", "terminal_cost", "True or False", self.terminal_cost)
        if self.step_model not in ("normal_mode", "paper"):
            raise invalid("PlannerConfig", "step_model", "'normal_mode' or 'paper'",
                          self.step_model)
        if not isinstance(self.weights, EnergyWeights):
            raise invalid("PlannerConfig", "weights", "an EnergyWeights", self.weights)
