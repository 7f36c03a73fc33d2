"""Gait engines: the protocol every full-body gait generator implements, the pose frame
it returns, and the registry of engines by name (docs/architecture.md, "Gait engines").

An engine receives the steps the crowd decided (:class:`crowdwalk.steps.StepBatch`) at
their heel strikes and answers poses at output frames. ``elevation_angles`` (Sun &
Metaxas 2001, :class:`crowdwalk.gait.animator.Animator`) is the default; other engines
register a factory here under their name and are chosen per group (scenario
``groups[].gait``).
"""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import Protocol, runtime_checkable

import numpy as np

from crowdwalk.body import Body
from crowdwalk.errors import invalid
from crowdwalk.steps import StepBatch

__all__ = ["PoseFrame", "GaitEngine", "GroundHeight", "GAIT_ENGINES", "make_engine",
           "MixedEngine", "join_frames"]

GroundHeight = Callable[[np.ndarray], np.ndarray]
"""Ground height ``z (p,)`` [m] at points ``xy (p, 2)`` [m], e.g. ``Terrain.height``."""


@dataclass(frozen=True, eq=False)
class PoseFrame:
    """Poses of k agents at one time (J = ``len(crowdwalk.body.JOINT_NAMES)`` = 20).

    Attributes
    ----------
    agents : (k,) agent indices.
    time : float [s].
    root_position : (k, 3) ``HumanoidRoot`` world position [m].
    root_quaternion : (k, 4) pelvis world orientation, wxyz.
    joints : (k, J, 4) local joint rotations, wxyz (joint 0 repeats the root's).
    positions : (k, J, 3) joint world positions [m].
    contact : (k, 2) bool, left/right foot on the ground.
    fallback : (k,) bool, a solve did not converge and the previous pose was kept.
    stance_left : (k,) bool, the left foot is the stance foot (the one the root is
        computed from, §4.1); in double support both feet are in ``contact``.
    """

    agents: np.ndarray
    time: float
    root_position: np.ndarray
    root_quaternion: np.ndarray
    joints: np.ndarray
    positions: np.ndarray
    contact: np.ndarray
    fallback: np.ndarray
    stance_left: np.ndarray


@runtime_checkable
class GaitEngine(Protocol):
    """Full-body poses of n agents from the steps they take.

    ``command(steps)``
        Called with the steps the crowd decided (one :class:`~crowdwalk.steps.StepBatch`,
        batched over the ticks since the last pose; at most one step per agent per call,
        in the order of the heel strikes), before any pose later than their
        ``start_time``. An agent's first command places it; each later one starts its
        next step from where the previous one landed.
    ``pose(t, agents)``
        Poses at time ``t`` [s] of ``agents`` (k,) int (each has received a command), as
        a :class:`PoseFrame` whose rows follow ``agents``; finite everywhere.
    ``skeleton``
        ``(names (J,), parents (J,))``: joint names and parent indices (-1 for the root);
        every engine uses :data:`crowdwalk.body.JOINT_NAMES` / ``PARENTS``.
    """

    @property
    def skeleton(self) -> tuple[tuple[str, ...], np.ndarray]: ...

    def command(self, steps: StepBatch) -> None: ...

    def pose(self, t: float, agents: np.ndarray) -> PoseFrame: ...


#: Engine name -> "module:callable" of its factory ``factory(body=Body (n),
#: ground=GroundHeight[, attributes=crowdwalk.style.Style (n)]) -> GaitEngine`` (imported
#: only when the engine is used; a factory with an ``attributes`` parameter gets the
#: walkers' styles).
GAIT_ENGINES: dict[str, str] = {
    "elevation_angles": "crowdwalk.gait.animator:Animator",
    "klaw": "crowdwalk.gait.klaw:KlawEngine",
    "ko_badler": "crowdwalk.gait.ko_badler.engine:KoBadlerEngine",
}


def make_engine(name: str, *, body: Body, ground: GroundHeight | None,
                attributes=None) -> GaitEngine:
    """The gait engine registered as ``name`` for the n agents of ``body``; ``attributes``
    the n walkers' :class:`crowdwalk.style.Style` (None: the default style)."""
    if name not in GAIT_ENGINES:
        raise invalid("make_engine", "name", f"one of {sorted(GAIT_ENGINES)}", name)
    module, attr = GAIT_ENGINES[name].split(":")
    factory = importlib.import_module(module)
    for part in attr.split("."):
        factory = getattr(factory, part)
    extra = {"attributes": attributes} if "attributes" in inspect.signature(factory).parameters \
        else {}
    return factory(body=body, ground=ground, **extra)


class MixedEngine:
    """Several engines behind one, each agent driven by the engine of its group.

    Parameters
    ----------
    engines : sequence of GaitEngine
        Engines built over all n agents' bodies (agent indices are shared).
    choice : (n,) int
        Index into ``engines`` per agent.
    """

    def __init__(self, engines, choice: np.ndarray) -> None:
        self.engines = list(engines)
        self.choice = np.asarray(choice, dtype=np.intp)

    @property
    def skeleton(self) -> tuple[tuple[str, ...], np.ndarray]:
        return self.engines[0].skeleton

    def command(self, steps: StepBatch) -> None:
        which = self.choice[steps.agent]
        for e, engine in enumerate(self.engines):
            rows = np.flatnonzero(which == e)
            if rows.size:
                engine.command(steps.take(rows))

    def pose(self, t: float, agents: np.ndarray) -> PoseFrame:
        agents = np.asarray(agents)
        if agents.size == 0:
            return self.engines[0].pose(t, agents)
        which = self.choice[agents]
        parts, order = [], []
        for e, engine in enumerate(self.engines):
            rows = np.flatnonzero(which == e)
            if rows.size:
                parts.append(engine.pose(t, agents[rows]))
                order.append(rows)
        return join_frames(t, parts, order)


def join_frames(t: float, parts: list[PoseFrame], order: list[np.ndarray]) -> PoseFrame:
    """One frame at time ``t`` [s] of the rows of ``parts``, part i's rows going to the
    positions ``order[i]`` of the joined frame."""
    back = np.argsort(np.concatenate(order), kind="stable")
    cat = {f.name: np.concatenate([getattr(p, f.name) for p in parts])[back]
           for f in fields(PoseFrame) if f.name != "time"}
    return PoseFrame(time=float(t), **cat)
