"""Route following: every agent walks along a polyline from its route on the graph.

All route polylines live in one concatenated table (struct-of-arrays) with a global arc
length that jumps by a gap between routes. Projecting agents onto their routes, finding the
point some distance ahead ("carrot") and testing arrival are then single vectorised numpy
operations over all deciding agents, whatever routes they follow.
"""

from __future__ import annotations

import numpy as np

from crowdwalk.crowd.geometry import point_segment_distance
from crowdwalk.errors import invalid

__all__ = ["RouteTable"]

_GAP = 1.0e3  # [m] arc-length gap between consecutive routes in the table


class RouteTable:
    """Concatenated route polylines.

    Routes are appended with :meth:`add` and addressed by the returned integer id.
    Vertices: ``xy`` (V, 2) [m]; ``s`` (V,) global arc length [m]; per route ``start`` and
    ``stop`` vertex indices and ``s0``, ``s1`` global arc length of its ends [m].
    """

    def __init__(self) -> None:
        self.xy = np.zeros((0, 2))
        self.s = np.zeros(0)
        self.start = np.zeros(0, dtype=np.int64)
        self.stop = np.zeros(0, dtype=np.int64)
        self.s0 = np.zeros(0)
        self.s1 = np.zeros(0)
        self._keys: dict[bytes, int] = {}

    def __len__(self) -> int:
        return self.start.size

    def add(self, polyline: np.ndarray) -> int:
        """Append a route polyline (k, 2) [m], k >= 2 (an identical route is shared);
        returns its id."""
        p = np.asarray(polyline, dtype=float)
        if p.ndim != 2 or p.shape[1] != 2 or len(p) < 1:
            raise invalid("RouteTable", "polyline", "an array of shape (k, 2) [m]", p.shape)
        seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
        p = np.concatenate([p[:1], p[1:][seg > 1e-9]])
        if len(p) == 1:
            p = np.concatenate([p, p + [1e-6, 0.0]])
        key = p.tobytes()
        if key in self._keys:
            return self._keys[key]
        base = (self.s[-1] + _GAP) if self.s.size else 0.0
        local = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
        rid = len(self)
        self.start = np.append(self.start, self.xy.shape[0])
        self.xy = np.concatenate([self.xy, p])
        self.s = np.concatenate([self.s, base + local])
        self.stop = np.append(self.stop, self.xy.shape[0] - 1)
        self.s0 = np.append(self.s0, base)
        self.s1 = np.append(self.s1, base + local[-1])
        self._keys[key] = rid
        return rid

    def length(self, route: np.ndarray) -> np.ndarray:
        """Route lengths [m] for route ids (n,)."""
        return self.s1[route] - self.s0[route]

    def project(
        self, route: np.ndarray, segment: np.ndarray, xy: np.ndarray, window: int = 6
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Project agents onto their routes, searching ``window`` segments forward from
        their current segment (agents only move forward along a route).

        Parameters
        ----------
        route, segment : (n,) int
            Route id and current segment (global index of its first vertex).
        xy : (n, 2) float
            Positions [m].

        Returns
        -------
        segment : (n,) int
            Updated segment index.
        s : (n,) float
            Global arc length of the projection [m].
        offset : (n,) float
            Distance from the route [m].
        """
        n = len(route)
        if n == 0:
            return segment.copy(), np.zeros(0), np.zeros(0)
        cand = segment[:, None] + np.arange(window)[None, :]  # (n, w)
        last_seg = self.stop[route] - 1
        cand = np.minimum(cand, last_seg[:, None])
        a, b = self.xy[cand], self.xy[cand + 1]
        d = point_segment_distance(xy[:, None, :], a, b)
        # prefer the earliest segment within 1 cm of the best one (no skipping ahead on
        # routes that fold back on themselves)
        best = d.min(axis=1, keepdims=True)
        pick = np.argmax(d <= best + 0.01, axis=1)
        seg = cand[np.arange(n), pick]
        a, b = self.xy[seg], self.xy[seg + 1]
        ab = b - a
        t = np.clip(np.einsum("ij,ij->i", xy - a, ab) / np.maximum(
            np.einsum("ij,ij->i", ab, ab), 1e-18), 0.0, 1.0)
        s = self.s[seg] + t * (self.s[seg + 1] - self.s[seg])
        return seg, s, d[np.arange(n), pick]

    def point_at(self, route: np.ndarray, s: np.ndarray) -> np.ndarray:
        """Points (n, 2) [m] at global arc lengths ``s`` (n,) [m], clipped to each route."""
        s = np.clip(s, self.s0[route], self.s1[route])
        return np.column_stack([np.interp(s, self.s, self.xy[:, 0]),
                                np.interp(s, self.s, self.xy[:, 1])])
