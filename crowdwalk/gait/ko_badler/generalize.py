"""Ko & Badler (1992) generalisations of walk data: φ_ρ (§2), ψ (§4) and both (§5).

Every function broadcasts over walkers: per-walker scalars (step lengths, body fields)
have a batch shape, sequence values (..., n) or (..., n, 2). Lengths [m], angles [rad].
Equation numbers are the paper's; where the text is read or corrected it says so here
and in docs/architecture.md ("Ko & Badler").
"""

from __future__ import annotations

import numpy as np

from crowdwalk.gait.ko_badler.walkdata import BodyCondition, GaitLaw, StepStart, WalkData

__all__ = [
    "mu",
    "hip_height_at_heel_strike",
    "ankle_at_toe_off",
    "ankle_at_heel_strike",
    "achieved_step_length",
    "step_length_generalization",
    "body_generalization",
    "generalization",
]


def mu(law: GaitLaw, body: BodyCondition, step_length) -> np.ndarray:
    """μ1…μ4(S, sl), shape (4, *batch) [rad].

    Eq. 5  μ1 = −α1 (sl/ll(S) − sl*) + μ1*   knee angle at heel strike (interior);
    Eq. 6  μ2 =  α2 (sl/ll(S) − sl*) + μ2*   foot angle at heel strike (toe up);
    Eq. 21 μ3 =  α3 (sl/ll(S) − sl*) + μ3*   foot angle at toe-off (heel up);
    Eq. 24 μ4 =  α4 (sl/ll(S) − sl*) + μ4*   meta angle at toe-off;
    with sl* read as the prototype's sl*/ll(S*) (``law.step_ratio``).
    """
    x = np.asarray(step_length, dtype=float) / body.leg_length - law.step_ratio
    sign = np.array([-1.0, 1.0, 1.0, 1.0]).reshape((4,) + (1,) * np.ndim(x))
    a = law.alpha.reshape(sign.shape)
    m = law.mu_star.reshape(sign.shape)
    return sign * a * x + m


def ankle_at_heel_strike(law: GaitLaw, body: BodyCondition, step_length) -> np.ndarray:
    """(b2x, b2y), shape (*batch, 2) [m]: the landing ankle at HSM⁺ (Eqs. 34–35).

    b2x = sl − (ah cos θh − ah cos(θh + μ2)),  b2y = ah sin(θh + μ2): the foot of step
    length sl, rotated toe-up by μ2 about its heel, in the stance foot's N frame (also
    Eqs. 8–9: ``A`` of Fig. 3).
    """
    sl = np.asarray(step_length, dtype=float)
    mu2 = mu(law, body, sl)[1]
    ah, th = body.ankle_heel, body.heel_angle
    return np.stack([sl - (ah * np.cos(th) - ah * np.cos(th + mu2)),
                     ah * np.sin(th + mu2)], axis=-1)  # fmt: skip


def ankle_at_toe_off(law: GaitLaw, body: BodyCondition, step_length, previous) -> np.ndarray:
    """(b1x, b1y), shape (*batch, 2) [m]: the swing ankle at TOM (Eqs. 32–33, corrected).

    The swing foot pivots on the tip of its toes at its own footprint, one previous step
    (``previous`` [m]) behind the stance foot's N: the toes at the meta angle μ4 put the
    ball at (bN + bt − bt cos μ4, bt sin μ4), the foot at μ3 heel up puts the ankle at
    ab (−cos(θb + μ3), sin(θb + μ3)) from the ball. Eqs. 32–33 as printed drop θb (at
    μ3 = μ4 = 0 they give the ankle (bN − ab, 0) instead of (0, aN)); the measured
    prototype fits the corrected form (scripts/derive_ko_badler_prototype.py prints both).
    """
    m = mu(law, body, step_length)
    mu3, mu4 = m[2], m[3]
    bt, ab, tb = body.toes, body.ankle_ball, body.ball_angle
    x = body.ball + bt - bt * np.cos(mu4) - ab * np.cos(tb + mu3)
    y = bt * np.sin(mu4) + ab * np.sin(tb + mu3)
    return np.stack([x - np.asarray(previous, dtype=float), y], axis=-1)


def hip_height_at_heel_strike(law: GaitLaw, body: BodyCondition, step_length) -> np.ndarray:
    """ỹn: hip height above the floor at HSM⁺ after a step of length sl [m] (§2.1).

    Eq. 7  a1² = thigh² + shin² − 2 thigh shin cos μ1;
    Eqs. 8–9 the landing ankle ``A`` = (x'a, y'a) (:func:`ankle_at_heel_strike`, xa = 0);
    Eq. 10 a3 = sqrt(a1² − (x'a − xa − sl/2)²);  Eq. 11 HIP = (xa + sl/2, a3 + y'a).
    """
    sl = np.asarray(step_length, dtype=float)
    mu1 = mu(law, body, sl)[0]
    a1_sq = body.thigh**2 + body.shin**2 - 2.0 * body.thigh * body.shin * np.cos(mu1)
    landing = ankle_at_heel_strike(law, body, sl)
    a3 = np.sqrt(np.maximum(a1_sq - (landing[..., 0] - 0.5 * sl) ** 2, 0.0))
    return a3 + landing[..., 1]


def achieved_step_length(w: WalkData) -> np.ndarray:
    """The step length the walk data realise [m] (Lemma 2, Eqs. 36–37).

    The swing ankle lands at A(HSM⁺) with the foot at F3(HSM⁺) toe up; the foot then
    rolls on its heel to flat, so the next N lies hN ahead of that heel.
    """
    ankle = w.ankle.v[..., -1, :]
    foot = w.foot3.v[..., -1]
    ah, th = w.body.ankle_heel, w.body.heel_angle
    heel_x = ankle[..., 0] - ah * np.cos(th + foot)
    return heel_x + ah * np.cos(th)


def _ankle_remap(ankle, tom, b1, b2, b3, b4, scale=1.0) -> np.ndarray:
    """Eqs. 29–30 (and 127–128 with ``scale`` α): map the swing ankle from (b1, b2) to (b3, b4).

    x' = b3x + (b4x − b3x)/(b2x − b1x) (x − b1x);  y' = s y + (1 − t') d1 + t' d2,
    d1 = b3y − s y1, d2 = b4y − s y_na, t' = (t − TOM)/(HSM⁺ − TOM).
    """
    x, y = ankle.x, ankle.y
    tp = (ankle.t - tom) / (1.0 - tom)
    gain = ((b4[..., 0] - b3[..., 0]) / (b2[..., 0] - b1[..., 0]))[..., None]
    xn = b3[..., 0][..., None] + gain * (x - b1[..., 0][..., None])
    d1 = b3[..., 1][..., None] - scale * y[..., :1]
    d2 = b4[..., 1][..., None] - scale * y[..., -1:]
    yn = scale * y + (1.0 - tp) * d1 + tp * d2
    return ankle.with_values(np.stack(np.broadcast_arrays(xn, yn), axis=-1))


def step_length_generalization(w: WalkData, rho, *, start: StepStart | None = None) -> WalkData:
    """φ_ρ: W(S, sl) → W(S, ρ sl) (§2, Eqs. 12–30).

    Parameters
    ----------
    w : WalkData
        W(S, sl).
    rho : float | numpy.ndarray
        Step-length ratio ρ > 0 (batch shape).
    start : StepStart, optional
        sl_before and the hip height ỹ1 at HSM⁻ ("given by the current posture");
        default ``w.start`` (the walk's own).
    """
    start = w.start if start is None else start
    law, body = w.law, w.body
    sl = w.step_length
    new_sl = np.asarray(rho, dtype=float) * sl
    before = np.asarray(start.step_length, dtype=float)
    m_new = mu(law, body, new_sl)
    col = np.expand_dims  # per-walker scalar → (..., 1) against (..., n)

    # (i) hip, Eqs. 13–15.
    rho_x = (before + new_sl) / (before + sl)  # Eq. 15
    y_start = np.asarray(start.hip_height, dtype=float)  # ỹ1
    y_end = hip_height_at_heel_strike(law, body, new_sl)  # ỹn, §2.1
    t = w.hip.t
    hx = col(rho_x, -1) * w.hip.x  # Eq. 13
    hy = (w.hip.y + (1.0 - t) * (col(y_start, -1) - w.hip.y[..., :1])
          + t * (col(y_end, -1) - w.hip.y[..., -1:]))  # Eq. 14  # fmt: skip
    hip = w.hip.with_values(np.stack(np.broadcast_arrays(hx, hy), axis=-1))

    # (ii) F1, Eq. 20: scaled to the heel-strike angle of the previous step.
    f1 = w.foot1.v
    foot1 = w.foot1.with_values(f1 * col(mu(law, body, before)[1], -1) / f1[..., :1])
    # (iii) F2, Eq. 22 (signed: the toe-off foot angle is −μ3).
    f2 = w.foot2.v
    foot2 = w.foot2.with_values(f2 * col(-m_new[2], -1) / f2[..., -1:])
    # (iv) F3, Eq. 23 with t' = (t − TOM)/(HSM⁺ − TOM) as in Eq. 30 (the printed
    # t/(HSM⁺ − TOM) does not make F3 start at the toe-off angle, which Eq. 70 needs).
    f3 = w.foot3.v
    tp = (w.foot3.t - w.tom) / (1.0 - w.tom)
    d1 = col(-m_new[2], -1) - f3[..., :1]
    d2 = col(m_new[1], -1) - f3[..., -1:]
    foot3 = w.foot3.with_values(f3 + (1.0 - tp) * d1 + tp * d2)
    # (v) M, Eq. 26.
    mv = w.meta.v
    meta = w.meta.with_values(mv * col(m_new[3], -1) / mv[..., -1:])
    # (vi) A, Eqs. 27–30 with the ankle positions of Lemma 1 (Eqs. 32–35).
    b1 = ankle_at_toe_off(law, body, sl, w.previous_step_length)
    b2 = ankle_at_heel_strike(law, body, sl)
    b3 = ankle_at_toe_off(law, body, new_sl, before)
    b4 = ankle_at_heel_strike(law, body, new_sl)
    ankle = _ankle_remap(w.ankle, w.tom, b1, b2, b3, b4)
    return w.replace(step_length=new_sl, previous_step_length=before, hip=hip, foot1=foot1,
                     foot2=foot2, foot3=foot3, meta=meta, ankle=ankle)  # fmt: skip


def body_generalization(w: WalkData, body: BodyCondition) -> WalkData:
    """ψ_{S1}^{S2}: W(S1, sl) → W(S2, ll(S2)/ll(S1) sl) (§4, Eqs. 120–129).

    α = ll(S2)/ll(S1). Hip: x' = α x (Eq. 122), y' = α y + ΔaN (Eq. 123), ΔaN = aN(S2) −
    α aN(S1). Foot and meta angles are unchanged (μ_i is invariant, Eq. 124). Ankle:
    Eqs. 127–128 from S1's (b1, b2) at sl to S2's (b3, b4) at α sl (Lemma 1). The
    previous step scales with the body too (proof of Theorem 4, (i)).
    """
    s1 = w.body
    alpha = body.leg_length / s1.leg_length
    d_an = body.ankle_height - alpha * s1.ankle_height
    col = np.expand_dims
    hx = col(alpha, -1) * w.hip.x
    hy = col(alpha, -1) * w.hip.y + col(d_an, -1)
    hip = w.hip.with_values(np.stack(np.broadcast_arrays(hx, hy), axis=-1))
    sl, before = w.step_length, w.previous_step_length
    b1 = ankle_at_toe_off(w.law, s1, sl, before)
    b2 = ankle_at_heel_strike(w.law, s1, sl)
    b3 = ankle_at_toe_off(w.law, body, alpha * sl, alpha * before)
    b4 = ankle_at_heel_strike(w.law, body, alpha * sl)
    ankle = _ankle_remap(w.ankle, w.tom, b1, b2, b3, b4, scale=col(alpha, -1))
    angles = {k: getattr(w, k).with_values(np.broadcast_to(
        getattr(w, k).v, (*np.shape(alpha), getattr(w, k).t.size)))
        for k in ("foot1", "foot2", "foot3", "meta")}  # fmt: skip
    return w.replace(body=body, step_length=alpha * sl, previous_step_length=alpha * before,
                     hip=hip, ankle=ankle, **angles)  # fmt: skip


def generalization(w: WalkData, body: BodyCondition, step_length, *,
                   start: StepStart | None = None) -> WalkData:  # fmt: skip
    """W(S1, sl1) → W(S2, sl2): ψ_{S1}^{S2} then φ (Eqs. 150–151).

    ``start`` is the S2 walker's previous step and hip height (default: ψ's image of the
    walk's own). By Theorem 4 the order does not matter.
    """
    w2 = body_generalization(w, body)
    return step_length_generalization(w2, np.asarray(step_length) / w2.step_length,
                                      start=start)  # fmt: skip
