"""The crowd model's parameters (:class:`CrowdParams`)."""

from __future__ import annotations

import ast
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np

from crowdwalk.body import PROPORTIONS
from crowdwalk.crowd.steering import SteeringParams
from crowdwalk.errors import invalid

__all__ = ["CROWD_MODELS", "CrowdParams", "crowd_model", "parse_overrides"]


@dataclass(frozen=True)
class CrowdParams:
    """Crowd model parameters.

    Attributes
    ----------
    radius_ratio : float
        Half the body's depth over body height [-] (the centre disc of the outline,
        :class:`~crowdwalk.crowd.shape.BodyShape`). Calibrated on one data set only:
        0.105 gives 0.18 m for a 1.71 m person, so that two bodies standing one behind
        the other are 0.36 m apart, the standstill spacing Seyfried et al. (2005, J.
        Stat. Mech. P10002) measured in single file. The bottleneck flows (Seyfried et
        al. 2009) are validation, not calibration: the value is not changed to fit them.
    half_width_ratio : float
        Half the body's shoulder width over body height [-]: 0.1295, half of Winter's
        (2009, Biomechanics and Motor Control of Human Movement, Fig. 4.1) shoulder width
        0.259 H (``crowdwalk.body.PROPORTIONS``), anthropometry, not tuned. The outline
        is 0.44 m broad and 0.36 m deep for a 1.71 m person. Used with
        ``body="three_discs"``.
    body : {"disc", "three_discs"}
        The body outline. ``"disc"`` (default): one disc ``2 radius_ratio H`` across.
        ``"three_discs"``: broader than deep (:class:`~crowdwalk.crowd.shape.BodyShape`),
        turning its shoulders through gaps. Not the default, measured: in the 2 × 50
        counterflow (``crowdwalk verify --only counterflow --seeds 5``) three seeds of
        five jammed with it (19, 47, 32 of 100 arrived; stands of 44–54 s), none with
        the disc; since oncoming walkers are anticipated among all neighbours
        (``SteeringParams.oncoming_neighbours``) all 100 arrive at every seed, but trips
        take 2.64 / 1.60 / 1.31 / 1.33 / 1.78 × the free walk (disc: 1.90 / 1.33 / 1.38
        / 1.40 / 1.34) and bottleneck flows are 0.89 / 1.49 / 1.95 /s at 0.8 / 1.0 /
        1.2 m (disc 1.18 / 1.77 / 2.06; Seyfried 2009: 1.3–1.6 / 1.7–1.9 / 2.0–2.3).
    wait_time : float
        How long an agent stands before deciding again when it cannot step [s].
    target_distance : float
        How far ahead along the route the steering target lies [m].
    centre_pull : float
        Fraction of the lateral offset from the route's centre line the target corrects
        over ``target_distance`` [-].
    arrive_distance : float
        An agent has arrived within this distance of its route's end [m].
    neighbours : int
        Neighbours considered per deciding agent (nearest first).
    neighbour_range : float
        Search radius for neighbours [m].
    reroute_after : float
        Time without ``progress_step`` of progress along the route after which an agent
        looks for another route [s].
    sight_after, sight_reach : float
        A walker without ``progress_step`` of progress for ``sight_after`` seconds whose
        steering target is behind a wall (it does not see it: pushed through a side door
        into a room, say) heads for the farthest point of its route within
        ``sight_reach`` metres ahead that it sees (inf: never). Named deviation, measured
        on RiMEA 10 full (``crowdwalk verify --full --only rimea10``): with re-routing
        when the route line is not seen and this rule, 114 → 120 of 120 left by their
        assigned exit (docs/architecture.md).
    progress_step : float
        Progress along the route that counts as getting on [m].
    stair_rise : float
        A step with a larger height change is a stair step (Weidmann speed) [m].
    planning_horizon : int
        Steps the footstep planner looks ahead (Chen & Li §4.2: three or four) [-].
    min_step_ratio : float
        Shortest planned step as a fraction of the leg length [-].
    replan_turn_deg : float
        A walker that turns by more than this at a heel strike re-plans; otherwise it
        takes the next step of its current plan [deg].
    speed_model : "free", "time_gap", "contact_gap" or "headway"
        ``free``: a step goes at the walker's free speed (stairs and slopes scaled);
        ``time_gap``: limited by the gap to the walker ahead (Tordeux et al. 2016,
        :func:`crowdwalk.crowd.speed.time_gap_speed`); ``contact_gap``: limited by the
        distance to the first contact along the walking line (Moussaïd et al. 2011),
        to the neighbours' committed step ends, not counting walkers that face or
        come towards the walker, and steering scores each direction at the step this
        allows (:func:`crowdwalk.crowd.speed.contact_gap_speed`).
    time_gap : float
        T of the time-gap model [s]: 0.8, calibrated on the SFPE handbook's corridor
        speeds (``scripts/calibrate_time_gap.py --model time_gap``; single-seed runs are
        noisy: RMS against SFPE 0.083 m/s at 0.8 s against 0.093-0.096 at 0.6-0.7 s in
        the first runs, 0.135 against 0.099 at 0.7 s on the final version); validated
        on Weidmann (1993).
    contact_time_gap : float
        T of the contact-gap model [s]: 1.2, calibrated on the SFPE handbook's
        corridor speeds as ``time_gap`` (``scripts/calibrate_time_gap.py --model
        contact_gap``: RMS 0.129 / 0.114 / 0.117 / 0.109 m/s at 0.9 / 1.0 / 1.1 / 1.2 s,
        flat within single-seed noise; most of it is the 0.75 /m² point, 0.16 m/s above
        SFPE at every T); validated on Weidmann (1993).
    headway_time, headway_lane : float
        The ``"headway"`` model (:func:`crowdwalk.crowd.speed.headway_speed`): b = 1.06 s
        and a = r_i + r_j from Seyfried et al.'s (2005) single-file data (their fit, not
        tuned here); a walker follows the nearest same-way walker ahead whose centre is
        within ``headway_lane`` × its own holding radius of its line (2.0: the two
        bodies' reach, Tordeux et al.'s criterion). Validated on Weidmann (1993) and
        SFPE; 1.0 (the own lateral extent only, so that zipper lanes close up) ran
        0.77 m/s at 2 /m² against Weidmann's 0.62. 1.233 (half the shoulder width,
        0.1295 / 0.105, so that a zipper neighbour is not followed; measured, not the
        default): full ring within Weidmann ± 0.15 at all seven densities, counterflow
        trips 1.58 / 1.55 / 1.55 / 3.41 / 1.67 × the free walk (seed 4 gridlocks),
        doors with ``headway_free_margin`` 1.0 as with 2.0 (docs/architecture.md,
        "Headway leader's lateral rule"). 1.75 with ``headway_route_lane``,
        ``headway_same_time``, ``headway_overtake`` (session 15, "S175"): ring 7 / 7 and
        free speed 0.980–1.000 — chosen among 1.5 / 1.75 / 2.0 on those two cases, so
        tuned on Weidmann; checked on SFPE's corridor speeds (RMS 0.081 m/s).
    headway_free_margin : float, optional
        With ``"headway"``: walkers inside an opening zone (corridors at most
        ``opening_width`` wide, minus the rooms, grown by this margin [m]) follow
        nobody (free speed; the hard swept-body test keeps them apart). None: off.
        Opt-in, measured (docs/architecture.md, "Headway free zone at openings"): 1.0
        (not calibrated: chosen among 0–2 m on seed 4) raises the headway model's door
        flows to 1.22 / 1.49 / 1.66 / 1.94 / 1.95 /s at 0.8–1.2 m (full, seeds 4–6;
        alone 0.76 / 0.93 / 1.34 at 0.8 / 1.0 / 1.2, fast); counterflow still fails.
    headway_same_way : {"heading", "route"}
        With ``"headway"``: which neighbours count as walking the same way (the only ones
        followed; the others are avoided by steering). ``"heading"`` (model ``free``): the
        neighbour's last step direction within 90° of the walker's own. ``"route"``
        ("route-direction leaders"): the neighbour's desired direction (the direction
        of its route segment, Helbing & Molnár 1995's e_α) within 120° of the walker's
        (a 90° corner keeps following the walker who has turned already):
        Seyfried et al.'s and Weidmann's relations are for walkers going one way, and
        an oncoming walker is one going the other way whatever its last step did. Named
        deviation, measured in the 2 × 50 counterflow (docs/architecture.md,
        "Route-direction headway leaders"): with ``"heading"`` an oncoming walker that
        side-steps or steps back (the clog fan turned round) is followed, face to face.
    headway_steer : bool
        With ``"headway"``: steering scores each candidate direction at the step the
        model allows along it, as ``"contact_gap"`` does; not inside the
        ``headway_free_margin`` zone, where the model is off (session 14: 0.8 m door,
        seeds 4–9, with C0 + ``line_up`` 1.14 → 1.20 /s; C0 + ``line_up`` alone 1.28).
        It lets walkers overtake: with C0 + ``line_up`` RiMEA 7's 1.6 m/s group ×0.886
        → ×0.992 and lone walkers 0.814 → 0.999 of their free speed at worst
        (docs/architecture.md, "C0 + line_up through the whole verify").
    headway_overtake : bool
        With ``"headway"``: steering scores each candidate direction at the step the
        model allows along it, as ``headway_steer``, but counting only the leaders the
        model follows (same-way walkers), not oncoming ones (``headway_steer`` counted
        every neighbour). Session 15, with C0 + ``line_up``: RiMEA 7 ×0.998 / 0.994 /
        0.992, free speed 0.999–1.000, RiMEA 10 120 / 120, counterflow 1.71 / 1.61 /
        1.46 / 1.46 / 1.73 × the free walk (``headway_steer`` 1.77 / 1.63 / 1.51 / 1.49 /
        1.64); the ring fails at 1.25 /m² (1.10 m/s, Weidmann 0.92): a step a little off
        the line leaves the leader's narrow lane and walks free.
    headway_route_lane : bool
        With ``"headway"``: the leader is the nearest followed walker ahead along the
        route direction whose centre is within the lane of the line parallel to the
        route through the step's end (the nominal step along the candidate direction),
        and Seyfried's relation limits the speed along the route only (a step across or
        back is not limited): the headway of the lane the walker steps into, not of
        the step's own line (Seyfried et al. 2005's relation is one-dimensional, along
        the file). Measured (docs/architecture.md, "Overtaking under the headway
        model"): in the 2 × 50 counterflow the step-line headway slowed side steps to
        0.6 of the free speed (a walker stepping towards its neighbour in the next file
        followed it at 0.5 m).
    headway_same_time : bool
        With a gap model scoring directions (``headway_overtake``, ``headway_steer``):
        each direction is scored at what its allowed speed covers in one step at the
        *free* cadence, so that directions compare by speed. Scored by step length a
        walker 1.3 m behind a slower one kept behind it (a slow step is also a longer
        one in time: at 1.03 against 1.56 m/s the step is 0.6 against 0.74 m), free
        speed 0.814 at worst.
    headway_overtake_open_lanes : bool
        With ``headway_overtake``: a walker whose lane runs into a wall
        (:func:`crowdwalk.crowd.routing.lane_runs_into_wall`: a door or bend ahead off
        its axis) does not overtake (there is no side lane), so the queue in front of a
        door is not fanned out (0.8 m door with overtaking and the route lane 1.11 →
        1.25 /s, full, seeds 4–6).
    lane_keep : bool
        Where a walker's lane runs into a wall (a door ahead off its axis), aim at the
        same side of the opening as far off its axis as fits, instead of at its centre
        line (:func:`crowdwalk.crowd.routing.steering_targets`). On in S175 (the default);
        alone: through 0.8 / 1.0 / 1.2 m (seed 4) 1.32 / 1.68 / 2.03 /s with it against
        1.33 / 1.67 / 2.18 without; it spreads walkers entering 0.8 m (|y| 0.08 against 0.05 m at
        mid-opening) but no zipper forms.
    line_up : bool
        Where a walker's lane runs into a wall (and ``lane_keep`` found no lane that
        fits), aim at the route's centre-line point farthest ahead, up to 1.5 m, that is
        reached in a straight line clear of the walls (tested at the line's quarters),
        down to the walker's own projection on it, instead of the centre-line point
        ``target_distance`` ahead (:func:`crowdwalk.crowd.routing.steering_targets`): a
        walker beside a door lines up with it before entering; never a point within
        the walker's own radius (a lone walker whose route ran beneath it along RiMEA 9's
        wall stood there for 300 s). Opt-in, measured (docs/architecture.md, "Lining up
        at doors"; with C0 it empties RiMEA 10's rooms sooner and the corridor's
        counterflow then locks: "C0 + line_up through the whole verify").
    opening_ease : bool
        Scale the soft wall term (``SteeringParams.wall_weight``) by
        ``opening_wall_factor`` for walkers inside an opening zone
        (:class:`~crowdwalk.crowd.openings.Openings`: corridors at most ``opening_width``
        wide, minus the rooms at their ends, grown by ``opening_margin``), so that two
        staggered lanes (a zipper) fit where the full term keeps everybody on the axis.
        The hard wall limit is unchanged (no body closer to a wall than its radius).
        Named deviation, opt-in (docs/architecture.md): the zipper forms (lane
        separation at 1.0 m 0.31 → 0.43 m), but the door flows do not rise (0.8 m:
        1.11 → 1.09 /s over seeds 4–9).
    opening_width, opening_margin : float
        [m]. 1.25: the bottleneck series' widths; margin 0: a 0.5 m margin into the
        rooms (the zone covering the mouth) jammed 0.9 m at seed 4 (0.82 /s).
    opening_wall_factor, opening_personal_factor : float
        Factors on the soft wall and neighbour terms inside [-]. The wall factor 0.0
        **calibrated on Hoogendoorn & Daamen 2005** (Transp. Sci. 39:147: layers about
        0.45 m apart in a 1 m bottleneck; 0.0 gives 0.43 m, 0.2 gives 0.39 m), validated
        on Seyfried et al. 2009's flows (not met at 0.8 m). The neighbour factor 1.0
        (0.4 measured: 0.8 / 0.9 / 1.0 m 1.17 / 1.58 / 1.79 /s with wall factor 0.2).
    zipper : bool
        The zipper entry (:mod:`crowdwalk.crowd.zipper`): a walker in or within 1 m of an
        opening (a corridor at most ``opening_width`` wide) heads for the lane a quarter
        of the opening's width off its axis, on the side opposite to the walker ahead of
        it, so that successive walkers enter staggered (Seyfried et al. 2009, Transp.
        Sci. 43:395; Hoogendoorn & Daamen 2005). Only the steering target changes (no
        body overlaps). Named deviation, opt-in (docs/architecture.md, "Zipper entry"):
        with ``opening_ease`` successive walkers alternate sides 0.82–0.89 (off
        0.55–0.77) and the lanes are 0.43 m apart at 1.0 m (H&D 0.45), but the flows at
        0.8–1.2 m are 1.29 / 1.44 / 1.61 / 1.86 / 1.96 /s (off 1.27 / 1.44 / 1.74 /
        1.91 / 2.21; full, seeds 4–6; both with ``wake_on_step`` and ``mouth_priority``
        off): the pace of the queue at the mouth limits them.
    mouth_priority : bool
        Priority in front of narrow openings (:mod:`crowdwalk.crowd.mouth_priority`): a
        walker within 1 m in front of an opening's mouth, heading into it, keeps its step
        clear of the next step (one nominal step on from the committed one) of every
        same-way neighbour there nearer the mouth point (ties by index), so that of the
        two walkers at the wall corners one goes first (Kirchner et al. 2003's conflicts
        resolved without friction). Only the hard test gains constraints (no body
        overlaps). Named deviation, on by default since session 21 (docs/architecture.md,
        "Priority at the mouth"): with ``wake_on_step`` (no zipper) the flows at 0.8–1.2 m
        are 1.28 / 1.55 / 1.77 / 1.98 / 2.20 /s (both off 1.27 / 1.44 / 1.74 / 1.91 /
        2.21, wake alone 1.16 / 1.49 / 1.76 / 1.96 / 2.20; full, seeds 4–6) and RiMEA 10
        passes; 0.8 m stays just below Seyfried's 1.30.
    wake_on_step : bool
        A walker standing in or within 1 m of an opening decides again at the tick after
        the first heel strike of a walking same-way neighbour that could be in its way,
        when that comes before its ``wait_time`` is over (:mod:`crowdwalk.crowd.wake`): it
        moves up when the one in front moves. Only the decision times change (no body
        overlaps). Named deviation, on by default since session 21 with
        ``mouth_priority`` (docs/architecture.md, "Waking at a neighbour's step"; the
        two together: see ``mouth_priority``): with ``zipper`` and ``opening_ease`` the
        flows at 0.8–1.2 m are 1.32 / 1.53 / 1.65 / 1.92 / 2.05 /s (full, seeds 4–6;
        0.8 and 0.9 m in Seyfried 2009's band, 1.0 m below it), but RiMEA 10 fails (89 /
        120: a gridlock at a side door); alone 0.8 m is less reliable (more arches at the
        mouth).
    steering : SteeringParams
    """

    radius_ratio: float = 0.105
    half_width_ratio: float = 0.5 * PROPORTIONS["shoulder_width"]
    wait_time: float = 0.25
    target_distance: float = 2.0
    centre_pull: float = 0.25
    arrive_distance: float = 0.6
    neighbours: int = 32
    neighbour_range: float = 3.0
    reroute_after: float = 8.0
    sight_after: float = 8.0
    sight_reach: float = 10.0
    progress_step: float = 0.5
    stair_rise: float = 0.05
    planning_horizon: int = 3
    min_step_ratio: float = 0.15
    replan_turn_deg: float = 3.0
    body: Literal["disc", "three_discs"] = "disc"
    speed_model: Literal["free", "time_gap", "contact_gap", "headway"] = "headway"
    time_gap: float = 0.8
    contact_time_gap: float = 1.2
    headway_time: float = 1.06
    headway_lane: float = 1.75
    headway_same_way: Literal["heading", "route"] = "route"
    headway_steer: bool = False
    headway_overtake: bool = True
    headway_route_lane: bool = True
    headway_same_time: bool = True
    headway_overtake_open_lanes: bool = True
    headway_free_margin: float | None = 1.0
    lane_keep: bool = True
    line_up: bool = True
    opening_ease: bool = False
    opening_width: float = 1.25
    opening_margin: float = 0.0
    opening_wall_factor: float = 0.0
    opening_personal_factor: float = 1.0
    zipper: bool = False
    mouth_priority: bool = True
    wake_on_step: bool = True
    steering: SteeringParams = field(default_factory=SteeringParams)

    def with_overrides(self, fields: Mapping[str, object]) -> CrowdParams:
        """A copy with ``fields`` replaced: CrowdParams field names, or ``steering.NAME``
        for a :class:`SteeringParams` field (what :func:`parse_overrides` gives)."""
        steer = {k.split(".", 1)[1]: v for k, v in fields.items() if k.startswith("steering.")}
        own = {k: v for k, v in fields.items() if not k.startswith("steering.")}
        return replace(self, **own, steering=replace(self.steering, **steer))

    def body_axes(self, height: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Half depth and half width (n,) [m] of bodies ``height`` (n,) [m] tall."""
        h = np.asarray(height, float)
        width = self.half_width_ratio if self.body == "three_discs" else self.radius_ratio
        return self.radius_ratio * h, width * h


def parse_overrides(items: Sequence[str]) -> dict[str, object]:
    """``FIELD=VALUE`` texts (the study scripts' ``--set``) as {field: value}, each VALUE
    a Python literal, or the text itself where it is none."""
    fields: dict[str, object] = {}
    for item in items:
        name, text = item.split("=", 1)
        try:
            fields[name] = ast.literal_eval(text)
        except (ValueError, SyntaxError):
            fields[name] = text
    return fields


#: Named crowd models (``crowdwalk run`` / ``verify --crowd-model NAME``): the
#: :class:`CrowdParams` fields each sets over the defaults; every field stays a switch of
#: its own for experiments. ``"headway_s175"``, the default since session 17 (it passes every
#: verify case the former default passes, and the ring at all densities; "S175" in
#: docs/architecture.md, "Overtaking under the headway model"): Seyfried et al. 2005's
#: headway speed model with the free zone at openings, lane keeping and lining up at
#: doors, same-way leaders by route, and overtaking in the route lane scored at equal
#: time; ``headway_lane`` 1.75 was chosen on the ring and free-speed cases (calibration).
#: Since session 21 the default (and so S175) also has ``wake_on_step`` and
#: ``mouth_priority`` on. ``"free"``: the former default, every S175 field back to its
#: value before (no headway speed model, no overtaking or door switches; waking and
#: mouth priority off).
CROWD_MODELS: dict[str, dict[str, object]] = {
    "free": {
        "speed_model": "free", "headway_lane": 2.0, "headway_free_margin": None,
        "lane_keep": False, "headway_same_way": "heading", "line_up": False,
        "headway_overtake": False, "headway_route_lane": False, "headway_same_time": False,
        "headway_overtake_open_lanes": False, "wake_on_step": False,
        "mouth_priority": False},
    "headway_s175": {},
}


def crowd_model(name: str, overrides: Mapping[str, object] | None = None) -> CrowdParams:
    """The :class:`CrowdParams` of the named crowd model (:data:`CROWD_MODELS`), with
    ``overrides`` (:meth:`CrowdParams.with_overrides` fields) on top."""
    if name not in CROWD_MODELS:
        raise invalid("crowd", "model", f"one of {', '.join(CROWD_MODELS)}", name)
    return CrowdParams().with_overrides({**CROWD_MODELS[name], **(overrides or {})})
