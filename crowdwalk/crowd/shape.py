"""The body's outline in plan: three discs on the shoulder line, broader than deep.

A body is a centre disc of radius ``radius`` and two shoulder discs of radius
``shoulder_radius`` whose centres lie ``shoulder_offset`` to the left and right of the
body's centre along its shoulder line (the three-circle body of Thompson & Marchant 1995,
"A computer model for the evacuation of large building populations", Fire Safety J. 24,
131; Langston et al. 2006, Safety Sci. 44, 395). The torso faces ``yaw`` [rad]: the
shoulder line runs along (−sin yaw, cos yaw). Turned by a twist against its walking
direction, the body needs less width across the walking direction ("turning the
shoulders" to slip through a gap) and more depth along it.

While a body steps, its centre moves linearly and its yaw turns linearly in time; every
clearance test here takes a shoulder disc's centre along the chord between its start and
end and widens the disc by the largest distance between that chord and the true arc,
``offset (1 − cos(Δyaw / 2))`` (at mid-step), so a test that passes is a guarantee.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np

__all__ = ["BodyShape", "body_gaps", "clear_runs", "disc_centres", "shape_overlap"]


@dataclass(frozen=True, eq=False)
class BodyShape:
    """Outlines of n bodies (struct-of-arrays).

    Attributes
    ----------
    radius : (n,) float
        Centre disc radius [m] (half the body's depth facing forward).
    shoulder_radius : (n,) float
        Shoulder disc radius [m].
    shoulder_offset : (n,) float
        Distance of each shoulder disc's centre from the body's centre [m].
    """

    radius: np.ndarray
    shoulder_radius: np.ndarray
    shoulder_offset: np.ndarray

    @classmethod
    def from_axes(cls, half_depth: np.ndarray, half_width: np.ndarray) -> BodyShape:
        """The three discs for bodies ``2 half_depth`` deep and ``2 half_width`` broad
        (n,) [m]: the centre disc spans the depth; the shoulder discs are the osculating
        circles of the ellipse with these half-axes at its ends (radius
        ``half_depth² / half_width``), so the outline reaches the full width and follows
        the ellipse's curvature there. ``half_width <= half_depth`` gives one disc."""
        b = np.asarray(half_depth, float)
        a = np.maximum(np.asarray(half_width, float), b)
        rs = b * b / a
        return cls(radius=b, shoulder_radius=rs, shoulder_offset=a - rs)

    def __len__(self) -> int:
        return int(self.radius.shape[0])

    @property
    def bound(self) -> np.ndarray:
        """(n,) radius of the smallest disc about the centre holding the body [m] (half
        the shoulder width)."""
        return np.maximum(self.radius, self.shoulder_offset + self.shoulder_radius)

    def take(self, index: np.ndarray) -> BodyShape:
        """The bodies at ``index``."""
        return BodyShape(self.radius[index], self.shoulder_radius[index],
                         self.shoulder_offset[index])

    def packed(self, index: np.ndarray | None = None) -> np.ndarray:
        """(k, 3) float: radius, shoulder radius, shoulder offset per body (all, or those
        at ``index``), the layout the kernels read."""
        p = np.column_stack([self.radius, self.shoulder_radius, self.shoulder_offset])
        return p if index is None else p[index]


def disc_centres(xy: np.ndarray, yaw: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """(..., 3, 2) centres [m] of the centre, left and right disc of bodies at ``xy``
    (..., 2) [m] facing ``yaw`` (...) [rad] with shoulder ``offset`` (...) [m]."""
    side = np.stack([-np.sin(yaw), np.cos(yaw)], axis=-1) * np.asarray(offset)[..., None]
    return np.stack([xy, xy + side, xy - side], axis=-2)


@nb.njit(cache=True, nogil=True)
def _closest(rx, ry, wx, wy, span, exact=True):
    """min over s in [0, span] of |r + w s|: ``hypot`` of the nearest offset, or with
    ``exact`` False its ``sqrt(x x + y y)`` (a few ulp apart, about twice as fast; for
    decisions that fall back on the exact value near their threshold, see
    :data:`SURE`)."""
    ww = wx * wx + wy * wy
    s = 0.0
    if ww > 0.0:
        s = min(max(-(rx * wx + ry * wy) / ww, 0.0), span)
    x, y = rx + s * wx, ry + s * wy
    return np.hypot(x, y) if exact else np.sqrt(x * x + y * y)


@nb.njit(cache=True, nogil=True)
def _approach(ax, ay, avx, avy, ta, bx, by, bvx, bvy, tb, exact=True):
    """Closest approach [m] of two points moving from now (time 0) with velocities ``av``
    for ``ta`` s and ``bv`` for ``tb`` s, then standing (exact: piecewise linear; the
    norms as :func:`_closest` ``exact``)."""
    t1, t2 = min(ta, tb), max(ta, tb)
    rx, ry = ax - bx, ay - by
    wx, wy = avx - bvx, avy - bvy
    d = _closest(rx, ry, wx, wy, t1, exact)
    rx += t1 * wx
    ry += t1 * wy
    if ta < tb:
        wx, wy = -bvx, -bvy
    else:
        wx, wy = avx, avy
    return min(d, _closest(rx, ry, wx, wy, t2 - t1, exact))


@nb.njit(cache=True, nogil=True)
def _segment_distance(ax, ay, bx, by, cx, cy, dx, dy, exact=True):
    """Least distance [m] between the segments ab and cd (0 where they cross or touch,
    or are collinear; the norms as :func:`_closest` ``exact``)."""
    o1 = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    o2 = (bx - ax) * (dy - ay) - (by - ay) * (dx - ax)
    o3 = (dx - cx) * (ay - cy) - (dy - cy) * (ax - cx)
    o4 = (dx - cx) * (by - cy) - (dy - cy) * (bx - cx)
    if o1 * o2 <= 0.0 and o3 * o4 <= 0.0:
        return 0.0
    return min(min(_closest(cx - ax, cy - ay, dx - cx, dy - cy, 1.0, exact),
                   _closest(cx - bx, cy - by, dx - cx, dy - cy, 1.0, exact)),
               min(_closest(ax - cx, ay - cy, bx - ax, by - ay, 1.0, exact),
                   _closest(ax - dx, ay - dy, bx - ax, by - ay, 1.0, exact)))


#: What a run's far test keeps below its bound [m] (covers the rounding, ~1e-13 m).
FAR_MARGIN = 1e-9
#: :func:`_clear_of_a` decides on the quick norms (``exact=False``) where they are
#: farther than this from a decision's threshold [m], else on the exact ones: the two
#: differ by a few ulp (~1e-15 m at these distances), so the decisions are the exact ones.
SURE = 1e-10

_SIDE = (0.0, 1.0, -1.0)


@nb.njit(cache=True, nogil=True)
def _run_limits(i, a_start, a_end, ok, centre_ok, runs, stop, stop_c, width):
    """Per run of A's (row ``i``) candidates: the first length blocked for the outline
    (``stop``) and for the centre discs (``stop_c``) by A's own masks, and the half width
    of a capsule about the segment from A's start to the run's last end that holds every
    sweep of the run (``width`` [m]: the greatest distance of an end from that segment;
    the distance is convex, the sweeps lie in the ends' hull)."""
    for c in range(stop.shape[0]):
        stop[c] = stop_c[c] = runs
        sx, sy = a_start[i, 0], a_start[i, 1]
        lx, ly = a_end[i, c * runs + runs - 1, 0], a_end[i, c * runs + runs - 1, 1]
        width[c] = 0.0
        for l in range(runs):
            e = _closest(sx - a_end[i, c * runs + l, 0], sy - a_end[i, c * runs + l, 1],
                         lx - sx, ly - sy, 1.0)
            width[c] = max(width[c], e)
        for l in range(runs):
            if not ok[i, c * runs + l]:
                stop[c] = l
                break
        for l in range(runs):
            if not centre_ok[i, c * runs + l]:
                stop_c[c] = l
                break


@nb.njit(cache=True, nogil=True)
def _discs_of_b(p, b_now, b_yaw_now, b_end, b_yaw_end, b_remaining, sb, bx, by, bvx, bvy):
    """Fill B's (row ``p``) three disc centres now and their velocities (3,) [m, m/s];
    return its remaining step time [s] (0 when done) and its turn's sagitta widening [m]."""
    tb = b_remaining[p]
    if tb <= 1e-9:
        tb = 0.0
    yb0, yb1 = b_yaw_now[p], b_yaw_end[p]
    c0, s0, c1, s1 = np.cos(yb0), np.sin(yb0), np.cos(yb1), np.sin(yb1)
    bend_b = sb * (1.0 - np.cos(0.5 * (yb1 - yb0))) + 1e-12
    for v in range(3):
        k = _SIDE[v]
        bx[v] = b_now[p, 0] - k * sb * s0
        by[v] = b_now[p, 1] + k * sb * c0
        bvx[v] = bvy[v] = 0.0
        if tb > 0.0:
            bvx[v] = (b_end[p, 0] - k * sb * s1 - bx[v]) / tb
            bvy[v] = (b_end[p, 1] + k * sb * c1 - by[v]) / tb
    return tb, bend_b


@nb.njit(cache=True, nogil=True)
def _centre_motion(i, j, a_start, a_end, a_dur, a_elapsed):
    """A's (row ``i``) centre on candidate ``j``: remaining time ``ta`` [s], the share
    ``f`` of the step gone, the end, the position now and the velocity [m, m/s]."""
    sx, sy = a_start[i, 0], a_start[i, 1]
    dur = a_dur[i, j]
    gone = min(a_elapsed[i], dur)
    ta = dur - gone
    f = gone / dur if dur > 0.0 else 1.0
    ex, ey = a_end[i, j, 0], a_end[i, j, 1]
    ax0, ay0 = sx + f * (ex - sx), sy + f * (ey - sy)
    avx = avy = 0.0
    if ta > 1e-9:
        avx, avy = (ex - ax0) / ta, (ey - ay0) / ta
    else:
        ta = 0.0
    return ta, f, ex, ey, ax0, ay0, avx, avy


@nb.njit(cache=True, nogil=True)
def _gaps(pa, a_start, a_yaw0, a_end, a_yaw1, a_dur, a_elapsed, a_shape, b_now, b_yaw_now,
          b_end, b_yaw_end, b_remaining, b_shape, runs, a_ok, a_centre_ok, out, out_centre):
    npairs, nj = out.shape
    bx = np.empty(3)
    by = np.empty(3)
    bvx = np.empty(3)
    bvy = np.empty(3)
    # with runs: per run of A's candidates, the first length blocked for the outline and
    # for the centre discs (by A's own mask or an earlier neighbour of the same A)
    n_runs = nj // runs if runs > 0 else 0
    stop = np.empty(n_runs, np.int64)
    stop_c = np.empty(n_runs, np.int64)
    # and per run the half width of a capsule holding the run's sweeps (_run_limits)
    width = np.empty(n_runs)
    far = 0.0
    for p in range(npairs):
        i = pa[p]
        if runs > 0 and (p == 0 or i != pa[p - 1]):
            _run_limits(i, a_start, a_end, a_ok, a_centre_ok, runs, stop, stop_c, width)
        ra, ras, sa = a_shape[i, 0], a_shape[i, 1], a_shape[i, 2]
        rb, rbs, sb = b_shape[p, 0], b_shape[p, 1], b_shape[p, 2]
        bound = max(ra, sa + ras) + max(rb, sb + rbs)
        # B's three discs now and their velocities (the same for every candidate of A)
        tb, bend_b = _discs_of_b(p, b_now, b_yaw_now, b_end, b_yaw_end, b_remaining, sb, bx, by,
                                 bvx, bvy)
        for j in range(nj):
            c = l = 0
            if runs > 0:
                c = j // runs
                l = j - c * runs
                if l >= stop_c[c]:  # a shorter step of the run is blocked: so is this one
                    out[p, j] = out_centre[p, j] = -np.inf
                    continue
                if l == 0:  # the run's capsule against B's whole remaining sweep
                    far = _segment_distance(
                        a_start[i, 0], a_start[i, 1], a_end[i, j + runs - 1, 0],
                        a_end[i, j + runs - 1, 1], b_now[p, 0], b_now[p, 1], b_end[p, 0],
                        b_end[p, 1]) - width[c]
                if far - bound >= FAR_MARGIN:  # the holding discs stay clear: a bound
                    out_centre[p, j] = far - ra - rb
                    out[p, j] = far - bound if l < stop[c] else -np.inf
                    continue
            ta, f, ex, ey, ax0, ay0, avx, avy = _centre_motion(i, j, a_start, a_end, a_dur,
                                                               a_elapsed)
            # the centres: their approach bounds the holding discs' (clear: done) and is
            # the centre discs' (overlapping: done)
            d = _approach(ax0, ay0, avx, avy, ta, bx[0], by[0], bvx[0], bvy[0], tb)
            out_centre[p, j] = d - ra - rb
            if runs > 0:
                if d - ra - rb < 0.0:
                    stop_c[c] = l
                if l >= stop[c]:
                    out[p, j] = -np.inf
                    continue
            if d >= bound:
                out[p, j] = d - bound
                continue
            best = d - ra - rb
            if best < 0.0 or (sa == 0.0 and sb == 0.0):
                out[p, j] = best
                if runs > 0 and best < 0.0:
                    stop[c] = l
                continue
            ya0 = a_yaw0[i] + f * (a_yaw1[i, j] - a_yaw0[i])
            ya1 = a_yaw1[i, j]
            bend_a = sa * (1.0 - np.cos(0.5 * (ya1 - ya0))) + 1e-12
            cs0, sn0, cs1, sn1 = np.cos(ya0), np.sin(ya0), np.cos(ya1), np.sin(ya1)
            for u in range(3):
                ku = _SIDE[u]
                rad_a = ra if u == 0 else ras + bend_a
                # disc u of A: now and at its step's end
                cx0, cy0 = ax0 - ku * sa * sn0, ay0 + ku * sa * cs0
                cvx = cvy = 0.0
                if ta > 0.0:
                    cvx = (ex - ku * sa * sn1 - cx0) / ta
                    cvy = (ey + ku * sa * cs1 - cy0) / ta
                for v in range(3):
                    if u == 0 and v == 0:
                        continue
                    rad_b = rb if v == 0 else rbs + bend_b
                    g = _approach(cx0, cy0, cvx, cvy, ta, bx[v], by[v], bvx[v], bvy[v],
                                  tb) - rad_a - rad_b
                    best = min(best, g)
                if best < 0.0:  # overlapping: how deep does not matter
                    break
            out[p, j] = best
            if runs > 0 and best < 0.0:
                stop[c] = l


@nb.njit(cache=True, nogil=True)
def _clear_of_a(i, pairs, a_start, a_yaw0, a_end, a_yaw1, a_dur, a_elapsed, a_shape, b_now,
                b_yaw_now, b_end, b_yaw_end, b_remaining, b_shape, runs, ok, centre_ok):
    """:func:`_gaps` with runs for one A (row ``i`` of the ``a_*`` arrays) against its
    neighbours ``pairs`` (rows of the ``b_*`` arrays, in order), keeping the signs only:
    A's rows of ``ok`` and ``centre_ok`` (m, J) become "shorter than the run's first
    blocked length" (the reduction over A's neighbours of ``_gaps``' negative entries).
    A clear entry's disc pairs are skipped where a disc of one body keeps clear of the
    other's holding disc about its centre (every disc of a body, widened for its turn,
    lies within its shoulder offset of the centre's track): the same signs, fewer disc
    pairs. Distances are decided on the quick norms unless within :data:`SURE` of a
    threshold (then on the exact ones): the same signs, about half the time."""
    nj = ok.shape[1]
    bx = np.empty(3)
    by = np.empty(3)
    bvx = np.empty(3)
    bvy = np.empty(3)
    n_runs = nj // runs
    stop = np.empty(n_runs, np.int64)
    stop_c = np.empty(n_runs, np.int64)
    width = np.empty(n_runs)
    far = 0.0
    _run_limits(i, a_start, a_end, ok, centre_ok, runs, stop, stop_c, width)
    ra, ras, sa = a_shape[i, 0], a_shape[i, 1], a_shape[i, 2]
    for p in pairs:
        rb, rbs, sb = b_shape[p, 0], b_shape[p, 1], b_shape[p, 2]
        bound = max(ra, sa + ras) + max(rb, sb + rbs)
        tb, bend_b = _discs_of_b(p, b_now, b_yaw_now, b_end, b_yaw_end, b_remaining, sb, bx, by,
                                 bvx, bvy)
        hold_b = max(rb, sb + rbs + bend_b)  # B's discs lie within this of its centre
        for j in range(nj):
            c = j // runs
            l = j - c * runs
            if l >= stop_c[c]:
                continue
            if l == 0:
                sx, sy = a_start[i, 0], a_start[i, 1]
                lx, ly = a_end[i, j + runs - 1, 0], a_end[i, j + runs - 1, 1]
                far = _segment_distance(sx, sy, lx, ly, b_now[p, 0], b_now[p, 1],
                                        b_end[p, 0], b_end[p, 1], False) - width[c]
                if abs(far - bound - FAR_MARGIN) < SURE:
                    far = _segment_distance(sx, sy, lx, ly, b_now[p, 0], b_now[p, 1],
                                            b_end[p, 0], b_end[p, 1]) - width[c]
            if far - bound >= FAR_MARGIN:
                continue
            ta, f, ex, ey, ax0, ay0, avx, avy = _centre_motion(i, j, a_start, a_end, a_dur,
                                                               a_elapsed)
            d = _approach(ax0, ay0, avx, avy, ta, bx[0], by[0], bvx[0], bvy[0], tb, False)
            if abs(d - ra - rb) < SURE or abs(d - bound) < SURE:
                d = _approach(ax0, ay0, avx, avy, ta, bx[0], by[0], bvx[0], bvy[0], tb)
            if d - ra - rb < 0.0:
                stop_c[c] = l
            if l >= stop[c]:
                continue
            if d >= bound:
                continue
            best = d - ra - rb  # only its sign counts from here
            if best < 0.0:
                stop[c] = l
                continue
            if sa == 0.0 and sb == 0.0:
                continue
            ya0 = a_yaw0[i] + f * (a_yaw1[i, j] - a_yaw0[i])
            ya1 = a_yaw1[i, j]
            bend_a = sa * (1.0 - np.cos(0.5 * (ya1 - ya0))) + 1e-12
            cs0, sn0, cs1, sn1 = np.cos(ya0), np.sin(ya0), np.cos(ya1), np.sin(ya1)
            for u in range(3):
                ku = _SIDE[u]
                rad_a = ra if u == 0 else ras + bend_a
                cx0, cy0 = ax0 - ku * sa * sn0, ay0 + ku * sa * cs0
                cvx = cvy = 0.0
                if ta > 0.0:
                    cvx = (ex - ku * sa * sn1 - cx0) / ta
                    cvy = (ey + ku * sa * cs1 - cy0) / ta
                # disc u against B's holding disc: clear of all of B's discs
                if u == 0:
                    e = d
                    if abs(e - rad_a - hold_b - FAR_MARGIN) < SURE:
                        e = _approach(ax0, ay0, avx, avy, ta, bx[0], by[0], bvx[0], bvy[0],
                                      tb)
                else:
                    e = _approach(cx0, cy0, cvx, cvy, ta, bx[0], by[0], bvx[0], bvy[0], tb,
                                  False)
                    if abs(e - rad_a - hold_b - FAR_MARGIN) < SURE:
                        e = _approach(cx0, cy0, cvx, cvy, ta, bx[0], by[0], bvx[0], bvy[0],
                                      tb)
                if e - rad_a - hold_b >= FAR_MARGIN:
                    continue
                for v in range(3):
                    if u == 0 and v == 0:
                        continue
                    rad_b = rb if v == 0 else rbs + bend_b
                    g = _approach(cx0, cy0, cvx, cvy, ta, bx[v], by[v], bvx[v], bvy[v],
                                  tb, False) - rad_a - rad_b
                    if abs(g) < SURE:
                        g = _approach(cx0, cy0, cvx, cvy, ta, bx[v], by[v], bvx[v], bvy[v],
                                      tb) - rad_a - rad_b
                    best = min(best, g)
                if best < 0.0:
                    break
            if best < 0.0:
                stop[c] = l
    for c in range(n_runs):
        for l in range(runs):
            ok[i, c * runs + l] = l < stop[c]
            centre_ok[i, c * runs + l] = l < stop_c[c]


@nb.njit(cache=True, nogil=True)
def _clear_runs(pa, a_start, a_yaw0, a_end, a_yaw1, a_dur, a_elapsed, a_shape, b_now,
                b_yaw_now, b_end, b_yaw_end, b_remaining, b_shape, runs, ok, centre_ok):
    """:func:`_clear_of_a` for each A of ``pa`` (P,) (each A's neighbours together)."""
    first = 0
    for p in range(pa.shape[0]):
        if p == pa.shape[0] - 1 or pa[p + 1] != pa[p]:  # A's last neighbour
            _clear_of_a(pa[p], np.arange(first, p + 1), a_start, a_yaw0, a_end, a_yaw1,
                        a_dur, a_elapsed, a_shape, b_now, b_yaw_now, b_end, b_yaw_end,
                        b_remaining, b_shape, runs, ok, centre_ok)
            first = p + 1


def body_gaps(pa: np.ndarray, *, a_start: np.ndarray, a_yaw0: np.ndarray, a_end: np.ndarray,
              a_yaw1: np.ndarray, a_duration: np.ndarray, a_elapsed: np.ndarray,
              a_shape: np.ndarray, b_now: np.ndarray, b_yaw_now: np.ndarray,
              b_end: np.ndarray, b_yaw_end: np.ndarray, b_remaining: np.ndarray,
              b_shape: np.ndarray, runs: int = 0, a_ok: np.ndarray | None = None,
              a_centre_ok: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Least clearance [m] from now on between the outlines of m stepping bodies A and
    P neighbours B, for J candidate steps of each A: (P, J); negative where they would
    overlap (then not necessarily the least). A lower bound (a shoulder disc turning is
    widened by its chord's sagitta; when the discs holding the two bodies stay clear,
    their clearance is returned), exact for discs. Also returned: (P, J) the clearance
    of the centre discs alone [m] (exact), which no facing of the outlines can exceed.

    Parameters
    ----------
    pa : (P,) int
        The body A (row of the ``a_*`` arrays) of each neighbour.
    a_start, a_yaw0 : (m, 2), (m,)
        A's position [m] and yaw [rad] at its heel strike.
    a_end, a_yaw1, a_duration : (m, J, 2), (m, J), (m, J)
        Each candidate step's end position [m], end yaw [rad] and duration [s].
    a_elapsed : (m,)
        Time since the heel strike [s] (that much of the step has gone).
    a_shape, b_shape : (m, 3), (P, 3)
        :meth:`BodyShape.packed` rows.
    b_now, b_yaw_now, b_end, b_yaw_end, b_remaining : (P, 2), (P,), (P, 2), (P,), (P,)
        The neighbour now, at the end of its committed step, and the time until then [s]
        (0: standing).
    runs : int, optional
        Only whether a step is clear up to its first blocked length matters (the caller's
        candidates are ``J / runs`` runs of ``runs`` increasing lengths, and ``pa`` lists
        each A's neighbours together, as ``np.nonzero`` gives them): after the first
        negative entry of a run for one A (over its neighbours so far, and ``a_ok`` /
        ``a_centre_ok``) the run's longer entries are only set to -inf, not evaluated;
        and where B's remaining sweep keeps clear of a capsule holding all of a run's
        sweeps, the run's clearances are that lower bound (both outputs), not evaluated.
        0 (default): every entry evaluated.
    a_ok, a_centre_ok : (m, J) bool, optional
        With ``runs``: A's candidates already blocked for the outline / the centre discs
        (e.g. by the walls) where False (default: none).
    """
    f = np.ascontiguousarray
    out = np.empty((pa.shape[0], a_end.shape[1]))
    centre = np.empty_like(out)
    if runs and a_end.shape[1] % runs:
        raise ValueError(f"body_gaps: runs {runs} does not divide {a_end.shape[1]} candidates")
    no = np.ones((0, 0), bool)
    a_ok = no if a_ok is None or not runs else f(a_ok, bool)
    a_centre_ok = no if a_centre_ok is None or not runs else f(a_centre_ok, bool)
    if runs:
        full = np.ones((a_end.shape[0], a_end.shape[1]), bool)
        a_centre_ok = full if a_centre_ok.size == 0 else a_centre_ok
        a_ok = a_centre_ok if a_ok.size == 0 else a_ok & a_centre_ok
    _gaps(f(pa, dtype=np.int64), f(a_start, float), f(a_yaw0, float), f(a_end, float),
          f(a_yaw1, float), f(a_duration, float), f(a_elapsed, float), f(a_shape, float),
          f(b_now, float), f(b_yaw_now, float), f(b_end, float), f(b_yaw_end, float),
          f(b_remaining, float), f(b_shape, float), int(runs), a_ok, a_centre_ok, out, centre)
    return out, centre


def clear_runs(pa: np.ndarray, *, a_start: np.ndarray, a_yaw0: np.ndarray, a_end: np.ndarray,
               a_yaw1: np.ndarray, a_duration: np.ndarray, a_elapsed: np.ndarray,
               a_shape: np.ndarray, b_now: np.ndarray, b_yaw_now: np.ndarray,
               b_end: np.ndarray, b_yaw_end: np.ndarray, b_remaining: np.ndarray,
               b_shape: np.ndarray, runs: int, ok: np.ndarray,
               centre_ok: np.ndarray) -> None:
    """:func:`body_gaps` with ``runs``, reduced over each A's neighbours to what its
    caller keeps: in place, the rows of ``ok`` / ``centre_ok`` (m, J) bool (A's
    candidates not blocked by the walls, for the outline / the centre discs) of every A
    in ``pa`` become False from the first length of each run blocked by the walls or a
    neighbour, as ``ok & ~(gaps < 0).any()`` over its neighbours would (same signs; the
    clearances themselves are not computed). ``ok`` must imply ``centre_ok``."""
    if a_end.shape[1] % runs:
        raise ValueError(f"clear_runs: runs {runs} does not divide {a_end.shape[1]} candidates")
    if not (ok.dtype == np.bool_ and centre_ok.dtype == np.bool_ and ok.flags.c_contiguous
            and centre_ok.flags.c_contiguous):
        raise ValueError("clear_runs: ok and centre_ok must be C-contiguous bool arrays")
    ok &= centre_ok
    f = np.ascontiguousarray
    _clear_runs(f(pa, dtype=np.int64), f(a_start, float), f(a_yaw0, float), f(a_end, float),
                f(a_yaw1, float), f(a_duration, float), f(a_elapsed, float),
                f(a_shape, float), f(b_now, float), f(b_yaw_now, float), f(b_end, float),
                f(b_yaw_end, float), f(b_remaining, float), f(b_shape, float), int(runs),
                ok, centre_ok)


def shape_overlap(xy_a: np.ndarray, yaw_a: np.ndarray, shape_a: np.ndarray,
                  xy_b: np.ndarray, yaw_b: np.ndarray, shape_b: np.ndarray) -> np.ndarray:
    """(P,) overlap [m] of two standing outlines (positive where they overlap): the
    deepest interpenetration of any two of their discs; positions (P, 2) [m], yaws (P,)
    [rad], :meth:`BodyShape.packed` rows (P, 3)."""
    ca = disc_centres(xy_a, yaw_a, shape_a[:, 2])  # (P, 3, 2)
    cb = disc_centres(xy_b, yaw_b, shape_b[:, 2])
    ra = shape_a[:, [0, 1, 1]]
    rb = shape_b[:, [0, 1, 1]]
    d = np.linalg.norm(ca[:, :, None, :] - cb[:, None, :, :], axis=-1)  # (P, 3, 3)
    return (ra[:, :, None] + rb[:, None, :] - d).max(axis=(1, 2))
