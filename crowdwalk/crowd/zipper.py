"""The zipper entry at narrow openings (``CrowdParams.zipper``).

In a bottleneck 0.8–1.2 m wide people do not pass in one file: each walker enters the
opening beside the one who entered before it, so that successive walkers are offset
laterally by about half the width and their bodies (broader than deep) interlock; the
spacing along the opening then shrinks below one body depth (Seyfried, Passon, Steffen,
Boltes, Rupprecht & Klingsch 2009, "New insights into pedestrian flow through
bottlenecks", Transp. Sci. 43:395, the "zipper effect"; Hoogendoorn & Daamen 2005,
Transp. Sci. 39:147: two layers about 0.45 m apart in a 1 m bottleneck).

This module steers that entry: a walker in an opening zone (the narrow corridor and
``ZONE_MARGIN`` into the rooms at its ends) heads for the lane on the side of the
opening's axis opposite to its leader (the nearest walker ahead of it along the route
within the opening's width), a quarter of the opening's width off the axis (lanes half
the width apart, H&D's 0.45 m at 1 m), ``REACH`` metres ahead. Only the steering target
changes: the swept-body test still limits every step, so bodies never overlap.
"""

from __future__ import annotations

import numpy as np

from crowdwalk.crowd.openings import ZONE_MARGIN, Openings

__all__ = ["REACH", "ZONE_MARGIN", "ZipperEntry"]

#: how far ahead along the route the lane target lies [m]
REACH = 1.0
#: the centre line is sampled this often between the walker and its target to find the
#: opening's half width (the least clearance) [m]
_SAMPLE = 0.25
#: how far ahead the opening's narrowest point is looked for [m]
_LOOK = 2.0


class ZipperEntry:
    """Lane targets of walkers in and in front of the openings of a route graph.

    Parameters
    ----------
    graph : crowdwalk.routes.RouteGraph
    max_width : float
        Corridors at most this wide [m] are openings (``CrowdParams.opening_width``).
    """

    def __init__(self, graph, max_width: float) -> None:
        self.zone = Openings(graph, max_width, ZONE_MARGIN)
        self.max_width = max_width

    def targets(self, table, clearance, *, route: np.ndarray, progress: np.ndarray,
                xy: np.ndarray, radius: np.ndarray, target: np.ndarray, nbs) -> np.ndarray:
        """The steering targets (k, 2) [m]: ``target`` (k, 2), with the walkers at ``xy``
        (k, 2) inside an opening zone heading for the lane beside their leader.

        ``route``, ``progress`` (k,): route ids and arc lengths [m]; ``radius`` (k,) [m];
        ``nbs``: their :class:`~crowdwalk.crowd.neighbours.Neighbours` (``now``, ``valid``).
        """
        out = np.array(target, float)
        rows = np.flatnonzero(self.zone.inside(xy))
        if not rows.size:
            return out
        r, s, p = route[rows], progress[rows], xy[rows]
        ahead = np.arange(0.0, _LOOK + 1e-9, _SAMPLE)
        line = table.point_at(np.repeat(r, ahead.size), (s[:, None] + ahead).ravel()
                              ).reshape(rows.size, ahead.size, 2)  # (m, j, 2)
        half = clearance(line.reshape(-1, 2)).reshape(line.shape[:2]).min(axis=1)
        here = line[:, 0]
        e = table.point_at(r, s + 0.1) - here
        e /= np.maximum(np.linalg.norm(e, axis=1), 1e-12)[:, None]
        n = np.column_stack([-e[:, 1], e[:, 0]])
        rel = nbs.now[rows] - p[:, None, :]  # (m, K, 2)
        along = np.einsum("mkj,mj->mk", rel, e)
        off = np.einsum("mkj,mj->mk", nbs.now[rows] - here[:, None, :], n)
        near = (nbs.valid[rows] & (along > 0.05) & (along < _LOOK)
                & (np.abs(off) < half[:, None] + radius[rows, None]))
        lead = np.argmin(np.where(near, along, np.inf), axis=1)
        has = near.any(axis=1)
        lead_off = off[np.arange(rows.size), lead]
        own = np.einsum("mj,mj->m", p - here, n)
        side = np.where(own >= 0.0, 1.0, -1.0)
        side = np.where(has & (np.abs(lead_off) > 0.03), -np.sign(lead_off), side)
        shift = np.minimum(0.5 * half, half - radius[rows] - 0.02)
        go = (half <= 0.5 * self.max_width) & (shift > 0.0)
        aim = table.point_at(r, s + REACH) + (side * np.maximum(shift, 0.0))[:, None] * n
        out[rows[go]] = aim[go]
        return out
