"""2.5-D ground: flat base, slopes, stair flights, blocks, rough heightfields, meshes.

A :class:`Terrain` is a flat base plane over a rectangular extent plus an ordered tuple of
features. **Composition is by override order**: where several feature footprints cover a
point, the *last* one listed decides its height (a painter's rule). This lets a later
feature cut into an earlier one (a stair flight going down from a platform, a curb on a
slope) and keeps every height exact: no feature is ever blended with another, so every
edge stays a sharp vertical step exactly where it was built.

Every feature is *piecewise planar*: a block top, a stair tread, a ramp, a triangle of a
rough heightfield's grid, a triangle of a mesh. Each feature lists the 2-D segments where
its plane changes (``breaks``). That makes the ground profile along a path
(:meth:`Terrain.profile`, the input of the footstep planner, Chen & Li §3: "the locations
where height changes along a given path") exact up to floating point: the path is cut at
every break, each piece lies on one plane, and a height change shows as two profile rows
with the same arc length.

Footprints are closed sets (a point on a block's edge is on the block); stair treads are
half-open along the walking direction (a point on a riser line belongs to the upper tread
of an up flight). Outside the extent the flat base continues.

Design choices: override order rather than ``max`` composition, because ``max`` cannot
express a pit or a flight going down from a platform and makes the result depend on
heights rather than on the author's order; a rough heightfield is two planar triangles
per grid cell rather than bilinear, so that it too is exactly piecewise planar (profiles
and meshes agree with point queries to floating point); a mesh's height is the topmost
hit of a vertical ray (trimesh, embree when installed).

Modules: :mod:`~crowdwalk.terrain.features` (the features),
:mod:`~crowdwalk.terrain.ground` (:class:`Terrain`: composition, point queries, ground
profiles), :mod:`~crowdwalk.terrain.meshing` (one trimesh mesh, height steps).
"""

from crowdwalk.terrain.features import (
    Block,
    Feature,
    Heightfield,
    MeshFeature,
    Slope,
    StairFlight,
    TerrainKind,
)
from crowdwalk.terrain.ground import Terrain

__all__ = [
    "TerrainKind",
    "Block",
    "Slope",
    "StairFlight",
    "Heightfield",
    "MeshFeature",
    "Feature",
    "Terrain",
]
