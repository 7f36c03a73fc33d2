"""Gait generation from sagittal elevation angles (Sun & Metaxas 2001): ElevInterp,
ElevWalker, MetaGait and the batched Animator the crowd drives."""

from crowdwalk.gait.animator import Animator, PoseFrame, StepCommand
from crowdwalk.gait.datasets import ElevationDataset, load_datasets, sample
from crowdwalk.gait.elevinterp import ElevInterp
from crowdwalk.gait.elevwalker import GaitStyle, StanceFoot, WarmStart, elevwalker_pose
from crowdwalk.gait.metagait import MetaGait, MetaGaitConfig, animate_paths, level_step_length

__all__ = [
    "Animator",
    "PoseFrame",
    "StepCommand",
    "ElevationDataset",
    "load_datasets",
    "sample",
    "ElevInterp",
    "GaitStyle",
    "StanceFoot",
    "WarmStart",
    "elevwalker_pose",
    "MetaGait",
    "MetaGaitConfig",
    "animate_paths",
    "level_step_length",
]
