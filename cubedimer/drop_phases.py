"""The phases of a field-drop recording: the dimer at rest, its free fall with the field off, the field back on.

A lab records a field drop from before the drive stops: the dimer levitates at rest (its height there is the
origin of y), the drive stops and the dimer falls freely (``yddot = -g``: with the field off nothing holds it),
then the drive is back and the dimer oscillates in the trap.  Only the last phase is the motion the suite's
models describe; the rest and the fall must be cut off before a fit, and the field's return is the natural
t = 0.  :func:`find_drop_phases` finds the phases in a series of heights.

Method (``y`` up, or down: a fall is then a rise at ``+g``).

1. **Rest.**  The first frames are at rest when their spread is within 3 noise (``noise``, else the robust
   scale of their successive differences) and below 2 % of the run's half range, and the trend and curvature of a
   parabola through the first :data:`MIN_REST_FRAMES` (at least :data:`MIN_REST_S`) are below 6 of their standard errors at the scatter about it
   (a smooth motion has them, noise-free or not, at a turning point too).  The rest ends at the first of
   three frames in a row that lie more than :data:`DEPARTURE_SIGMA` noise on the same side of the rest level
   (the fall has then lasted about ``sqrt(12 noise / g)``: one frame at 2000 frames/s and 0.2 um of noise).
2. **Where the field comes back, roughly.**  The fall from the rest level, ``y_r -+ g D(t - t_d, tau)`` (``t_d``
   and the transducer's ring time ``tau`` fitted on a grid of a fiftieth and a half of a frame; :func:`fall_depth`
   D: ``(t - t_d)^2 / 2`` for a field that switches off at once, a slower start while it rings down), is extended
   frame by frame until the next three frames lie beyond 5 noise (the rest frames' scatter; with a ring time also 1 %
   of the fall's depth) on the side the field pushes (a fall decelerated, within :data:`MAX_FALL_S`).
3. **Both switching times and the ring time.**  On the frames from before the departure to :data:`AFTER_S` after that
   rough return the model ``y = y_r - a D(t - t_d, tau) + b U(t - t_on, tau) + (c/6) (t - t_on)_+^3`` (continuous in
   height and velocity; :func:`return_depth` U the field's force ringing back up, ``(t - t_on)_+^2 / 2`` for an instant
   switch; the field-on motion a cubic over those few milliseconds, to 0.1 um of a 230 um oscillation at 22 Hz) gives
   the switching times and the ring time by least squares with the fall at g (with the field off nothing but gravity
   acts; a free ``a`` would let the field-on cubic take up a short fall): a grid of a tenth of a frame (the ring time
   half a frame, up to :data:`MAX_RING_S`), refined (Nelder-Mead), the other parameters linear; a ring time is kept only
   where it lowers the residual sum by more than 10 noise variances (else ``t_d`` and ``tau`` trade off within the
   noise, and the instant switch is taken).  At those times every
   parameter is fitted freely, ``a`` included (a free fall: ``g`` within :data:`FALL_TOLERANCE` and the residuals' RMS
   within 3 noise and 1 % of the fall's depth); ``a``'s error comes from the covariance of all seven (the Jacobian in
   the switching and ring times by central differences), ``t_on``'s from the half width of the grid's times whose
   residual sum lies within one noise variance of the least.  A fall whose fitted acceleration is not ``g`` within
   :data:`FALL_TOLERANCE` (relative) is not a free fall (:attr:`DropPhases.free_fall` False).  With a ring time the
   field's return ``t_on`` is when the drive restarts; its force rises as ``(1 - exp(-t / tau))^2``, so at a noise of
   1 um the restart is seen up to about one ring time late (tests/cubedimer/test_drop_phases.py).

A series that does not start at rest has no drop phases (None): it is the field-on motion already.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import logging

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import DatasetError

__all__ = ["DropPhases", "find_drop_phases", "starts_at_rest", "field_on_start", "STANDARD_GRAVITY", "DEPARTURE_SIGMA", "MAX_FALL_S",
           "AFTER_S", "FALL_TOLERANCE", "MIN_REST_FRAMES", "MIN_REST_S", "rest_head_frames", "MAX_RING_S", "fall_depth", "return_depth"]

#: Standard gravity [m/s^2] (docs/conventions.md).
STANDARD_GRAVITY = 9.80665
#: Noise standard deviations beyond the rest level at which the fall has begun.
DEPARTURE_SIGMA = 6.0
#: Longest field-off phase searched [s] (the drops of the source paper last 2-5 ms).
MAX_FALL_S = 0.03
#: Field-on time fitted after the rough return [s]: the motion is a cubic to 0.01 px over it at 22 Hz.
AFTER_S = 0.002
#: Relative tolerance of the fall's fitted acceleration about g for a free fall.
FALL_TOLERANCE = 0.25
#: Frames at rest a recording must begin with for its drop to be found.
MIN_REST_FRAMES = 16
#: ... and the time they must span [s] (16 frames at 2000 frames/s): a trap oscillation (about 22 Hz) curves by the
#: square of the time a head of frames spans, so over a shorter head its turning point cannot be told from rest
#: however many frames the head holds (at 50,000 frames/s 16 frames span 0.32 ms).
MIN_REST_S = 0.008
#: Longest ring time of the transducer searched [s]: the field's amplitude decays as exp(-t / tau) when the drive
#: stops and rises as 1 - exp(-t / tau) when it is back (tau = Q / (pi f): 1.74 ms at Q = 250 and 45.65 kHz).
MAX_RING_S = 0.004
logger = logging.getLogger("cubedimer.dataset")
_GRID = 0.1  # grid step of t_d and t_on [frames] (then refined)
_RING_GRID = 0.5  # grid step of the ring time [frames] (then refined)
_RETURN_BEFORE = 4.0  # the field's return searched from this many frames before the rough one (step 2)
_RIDGE = 1e-12 * np.eye(3)  # keeps the field-on normal equations solvable where a column vanishes


def fall_depth(s: ArrayLike, tau: ArrayLike) -> NDArray:
    """The fall per unit g after the drive stops, s >= 0 [any unit of time, tau in the same; 0 before]: the double
    integral of ``1 - exp(-2 s / tau)`` (the field's force, as the square of its amplitude, decays over tau / 2 while
    it held the dimer against g), ``s^2 / 2`` for an instant switch (tau = 0).  Late in the fall it is the free fall
    of a drop delayed by tau / 2 and deeper by tau^2 / 8.  ``s`` and ``tau`` broadcast."""
    s = np.maximum(np.asarray(s, float), 0.0)
    tau = np.asarray(tau, float)
    ring = tau > 0
    t = np.where(ring, tau, 1.0)
    return np.where(ring, 0.5 * s ** 2 - 0.5 * t * s - 0.25 * t ** 2 * np.expm1(-2.0 * s / t), 0.5 * s ** 2)


def return_depth(u: ArrayLike, tau: ArrayLike) -> NDArray:
    """The rise per unit acceleration after the drive is back, u >= 0: the double integral of the field's force as it
    rings up, ``(1 - exp(-u / tau))^2``; ``u^2 / 2`` for tau = 0.  ``u`` and ``tau`` broadcast."""
    u = np.maximum(np.asarray(u, float), 0.0)
    tau = np.asarray(tau, float)
    ring = tau > 0
    t = np.where(ring, tau, 1.0)
    return np.where(ring, 0.5 * u ** 2 - 1.5 * t * u - 2.0 * t ** 2 * np.expm1(-u / t)
                    + 0.25 * t ** 2 * np.expm1(-2.0 * u / t), 0.5 * u ** 2)


@dataclass(frozen=True)
class DropPhases:
    """The phases of one field-drop recording (frame indices from 0 at the first frame; fractional where a
    switching time lies between frames).

    Attributes
    ----------
    rest_frames : int
        Frames ``[0, rest_frames)`` show the dimer at rest.
    drop_frame : float
        When the drive stops [frames].
    field_on_frame, field_on_frame_error : float
        When the field is back [frames], and its standard error.
    first_field_on_frame : int
        The run's first frame: after the field's return by twice its error, and not before the first of the frames
        that leave the free fall (step 2).
    fall_acceleration, fall_acceleration_error : float
        The fitted acceleration of the fall [m/s^2] (negative: down in the series' sense of y) and its standard
        error.
    fit_scatter : float
        The RMS of the fit's residuals over its frames [the series' unit].
    rest_level : float
        The height at rest [the series' unit].
    noise : float
        The noise of one frame used [the series' unit].
    frame_interval : float
        [s].
    ring_frames : float
        The transducer's ring time fitted [frames] (0: the field switched at once).
    """

    rest_frames: int
    drop_frame: float
    field_on_frame: float
    field_on_frame_error: float
    first_field_on_frame: int
    fall_acceleration: float
    fall_acceleration_error: float
    rest_level: float
    noise: float
    frame_interval: float
    fit_scatter: float = 0.0
    ring_frames: float = 0.0

    @property
    def free_fall(self) -> bool:
        """The fall's acceleration is g (either sign) within :data:`FALL_TOLERANCE` and the model fits the frames to
        within 3 noise RMS and 1 % of the fall's depth (a jump from rest does not)."""
        depth = 0.5 * STANDARD_GRAVITY * self.field_off_s ** 2  # the fall's depth: 1 % of it for the model's error
        return (abs(abs(self.fall_acceleration) / STANDARD_GRAVITY - 1.0) <= FALL_TOLERANCE
                and self.fit_scatter <= 3.0 * self.noise + 0.01 * depth)

    @property
    def field_off_s(self) -> float:
        """How long the field was off [s]."""
        return (self.field_on_frame - self.drop_frame) * self.frame_interval

    def to_dict(self) -> dict:
        """JSON-ready (frames, seconds and SI units; times from the first frame)."""
        dt = self.frame_interval
        return {"rest_frames": [0, int(self.rest_frames)],
                "field_off_frames": [int(math.floor(self.drop_frame)) + 1, int(self.first_field_on_frame)],
                "field_on_first_frame": int(self.first_field_on_frame),
                "drop_time_s": self.drop_frame * dt, "field_on_time_s": self.field_on_frame * dt,
                "field_on_time_error_s": self.field_on_frame_error * dt, "field_off_s": self.field_off_s,
                "fall_acceleration_m_s2": self.fall_acceleration,
                "fall_acceleration_error_m_s2": self.fall_acceleration_error, "free_fall": self.free_fall,
                "ring_time_s": self.ring_frames * dt,
                "method": "rest: the first frames within the noise of their level; field off: the free fall "
                          "y_r - a D(t - t_drop, tau), the field ringing down over the ring time tau; field on: "
                          "continuous in height and velocity, the field ringing up, a cubic over 2 ms; both times "
                          "and tau fitted (cubedimer.drop_phases)"}


def _robust_noise(y: NDArray) -> float:
    d = np.diff(y[np.isfinite(y)])
    return 1.4826 * float(np.median(np.abs(d))) / math.sqrt(2.0) if d.size >= 4 else 0.0


def rest_head_frames(dt: float | None = None) -> int:
    """The frames a rest is judged on at frame interval ``dt`` [s]: :data:`MIN_REST_FRAMES`, or more where they span
    less than :data:`MIN_REST_S` (None: the frames alone)."""
    if dt is None or not dt > 0:
        return MIN_REST_FRAMES
    return max(MIN_REST_FRAMES, int(math.ceil(MIN_REST_S / dt - 1e-9)))


def starts_at_rest(y: ArrayLike, noise: float | None = None, dt: float | None = None) -> tuple[int, float, float] | None:
    """``(departure frame, rest level, noise)`` of a series that begins at rest (step 1 of the module docstring),
    or None.  The departure frame is the first of the three frames in a row beyond the rest.  ``dt``: the frame
    interval [s], so that the rest is judged over at least :data:`MIN_REST_S` (:func:`rest_head_frames`)."""
    y = np.asarray(y, float)
    fin = np.flatnonzero(np.isfinite(y))
    n_head = rest_head_frames(dt)
    if fin.size < 4 * n_head:
        return None
    head_at = fin[:n_head]
    head = y[head_at]
    sigma = max(float(noise or 0.0), _robust_noise(y[: fin[2 * n_head]]))
    half_range = 0.5 * float(np.subtract(*np.percentile(y[fin], [99, 1])))
    x = (head_at - head_at.mean()) / max(float(np.ptp(head_at)), 1.0)
    V = np.vander(x, 3)
    coef, *_ = np.linalg.lstsq(V, head, rcond=None)
    resid = float(np.std(head - V @ coef))
    # at rest: no trend or curvature beyond 6 of their standard errors at the noise (a smooth motion has them, even at
    # a turning point or noise-free: a 100 um oscillation at 22 Hz curves by 80 standard errors at 0.2 um of noise over
    # 16 frames at 2000 frames/s), a spread within the noise.  The curvature's standard error is 3.4 times the noise's
    # (the slope's 0.8 times): a bound of 6 noise on it would call 7 % of runs at rest moving.  The spread within 3
    # noise: the robust noise of 31 differences is uncertain by about 20 %, and 2 noise called 1 in 300 at rest moving.
    se = max(resid * math.sqrt(x.size / (x.size - 3)), float(noise or 0.0)) * np.sqrt(np.diag(np.linalg.inv(V.T @ V)))
    trend = bool(np.any(np.abs(coef[:2]) > 6.0 * se[:2]))
    if not half_range > 0 or trend or np.std(head) > max(3.0 * sigma, 1e-300) or np.std(head) > 0.02 * half_range:
        return None
    level = float(np.median(head))
    for _ in range(2):
        out = np.abs(np.nan_to_num(y - level, nan=0.0)) > DEPARTURE_SIGMA * max(sigma, 1e-300)
        side = np.sign(np.nan_to_num(y - level))
        run = out[:-2] & out[1:-1] & out[2:] & (side[:-2] == side[1:-1]) & (side[1:-1] == side[2:])
        if not run.any():
            return None
        k = int(np.argmax(run))
        if k < n_head:
            return None
        rest = y[:k][np.isfinite(y[:k])]
        level = float(np.median(rest))
        # the rest frames' scatter is the noise; below 1e-6 of the run's half range it is round-off (noise-free data)
        sigma = max(float(noise or 0.0), float(np.std(rest)), 1e-6 * half_range)
    return k, level, sigma


def _fall_only_fit(y: NDArray, k: int, level: float, g: float, e: int, taus: NDArray) -> tuple[float, float]:
    """(t_d, tau) [frames] of the fall ``level + g fall_depth(t - t_d, tau)`` (g signed) best fitting frames
    ``k - 1 .. e``."""
    idx = np.arange(max(0, k - 1), e + 1)
    idx = idx[np.isfinite(y[idx])]
    td = np.arange(k - 3.0 - 0.5 * taus.max(), k + 0.005, 0.02)
    pd, pt = (v.ravel() for v in np.meshgrid(td, taus, indexing="ij"))
    model = level + g * fall_depth(idx[None, :] - pd[:, None], pt[:, None])
    best = int(np.argmin(np.sum((y[idx][None, :] - model) ** 2, axis=1)))
    return float(pd[best]), float(pt[best])


def _rough_return(y: NDArray, k: int, level: float, g_frames: float, sigma: float, max_frames: int,
                  taus: NDArray) -> int | None:
    """The last frame of the fall, roughly (step 2), or None when the fall never ends within the search."""
    n = y.size
    for e in range(k + 1, min(n - 4, k + max_frames)):
        td, tau = _fall_only_fit(y, k, level, g_frames, e, taus)
        nxt = np.arange(e + 1, e + 4)
        depth = g_frames * fall_depth(nxt - td, tau)
        push = -np.sign(g_frames) * (y[nxt] - level - depth)  # the field decelerates the fall
        # beyond the noise, and with a ring time 1 % of the fall's depth (the model leaves out the trap's force
        # while the field rings down)
        if np.all(np.isfinite(push)) and np.all(push > 5.0 * sigma + (0.01 * np.abs(depth) if tau > 0 else 0.0)):
            return e
    return None


def _columns(t: NDArray, td: ArrayLike, ton: ArrayLike, tau: ArrayLike) -> NDArray:
    """The model's columns at the switching times ``td``, ``ton`` and ring time ``tau`` [frames]: y_r, a (the fall),
    b, c (field on)."""
    s, u, tau = np.broadcast_arrays(np.asarray(t, float) - td, np.asarray(t, float) - ton, tau)
    u = np.maximum(u, 0.0)
    return np.stack([np.ones_like(s), -fall_depth(s, tau), return_depth(u, tau), u ** 3 / 6.0], axis=-1)


def _fixed_fall_rss(y: NDArray, t: NDArray, td: ArrayLike, ton: ArrayLike, tau: ArrayLike, g_frames: float) -> NDArray:
    """Residual sums of the model with the fall at ``g_frames`` (signed, per frame squared), over triples of times."""
    td, ton, tau = np.broadcast_arrays(np.atleast_1d(td), np.atleast_1d(ton), np.atleast_1d(tau))
    X = _columns(t[None, :], td[:, None], ton[:, None], tau[:, None])
    return _linear_rss(y[None, :] + g_frames * X[..., 1], X[..., [0, 2, 3]], g_frames)


def _linear_rss(rhs: NDArray, X: NDArray, g_frames: float, gram: NDArray | None = None) -> NDArray:
    """The residual sums of ``rhs`` (p, r: the heights with the fall at g taken out) over the least squares in the
    field-on columns ``X`` (p, r, 3: y_r, b, c; laid out as a transposed (3, p, r) array, as indexing the columns
    out of :func:`_columns` leaves them, which sets the sums' order), one per triple of times; inf where the
    return is no return.  ``gram``: the columns' normal matrices, when known."""
    if gram is None:
        gram = _normal_matrices(X)
    beta = np.linalg.solve(gram, np.einsum("prk,pr->pk", X, rhs)[..., None])[..., 0]
    rss = np.sum((rhs - np.einsum("prk,pk->pr", X, beta)) ** 2, axis=1)
    # the field's return decelerates the fall by at least g (the trap holds the dimer against g at its equilibrium,
    # and more below it; half of it here): a return that the field-on cubic fits without it (a return inside the
    # fall, b about 0, when few frames follow the true one) is no return
    return np.where(-np.sign(g_frames) * beta[:, 1] >= 0.5 * abs(g_frames), rss, np.inf)


def _normal_matrices(X: NDArray) -> NDArray:
    """``X^T X`` (p, 3, 3) of the field-on columns ``X`` (p, r, 3), with the ridge that keeps them solvable."""
    return np.einsum("prk,prl->pkl", X, X) + _RIDGE


def _grid_rss(y: NDArray, t: NDArray, td: NDArray, ton: NDArray, tau: float, g_frames: float) -> NDArray:
    """:func:`_fixed_fall_rss` over pairs of times (``td``, ``ton``) of a grid at one ring time ``tau``: the fall's
    column is computed once per distinct ``td``, and the return's columns and their normal matrices once per
    distinct ``ton`` (the same numbers)."""
    tds, at_d = np.unique(td, return_inverse=True)
    tons, at_on = np.unique(ton, return_inverse=True)
    tau_d = np.full((tds.size, 1), tau)
    tau_on = np.full((tons.size, 1), tau)
    fall = -fall_depth(t[None, :] - tds[:, None], tau_d)
    u = np.maximum(t[None, :] - tons[:, None], 0.0)
    field_on = np.stack([np.ones_like(u), return_depth(u, tau_on), u ** 3 / 6.0])
    gram = _normal_matrices(field_on.transpose(1, 2, 0))[at_on]
    return _linear_rss(y[None, :] + g_frames * fall[at_d], field_on[:, at_on].transpose(1, 2, 0), g_frames, gram)


def _point_rss(y: NDArray, t: NDArray, td: float, ton: float, tau: float, g_frames: float) -> float:
    """:func:`_fixed_fall_rss` at one triple of times (the refinement's objective): the same numbers, without the
    broadcasting over triples."""
    s = np.maximum(t - td, 0.0)
    u = np.maximum(t - ton, 0.0)
    if tau > 0:  # fall_depth and return_depth, term by term
        fall = 0.5 * s ** 2 - 0.5 * tau * s - 0.25 * (tau * tau) * np.expm1(-2.0 * s / tau)
        rise = (0.5 * u ** 2 - 1.5 * tau * u - 2.0 * (tau * tau) * np.expm1(-u / tau)
                + 0.25 * (tau * tau) * np.expm1(-2.0 * u / tau))
    else:
        fall, rise = 0.5 * s ** 2, 0.5 * u ** 2
    X = np.stack([np.ones_like(u), rise, u ** 3 / 6.0])[:, None, :].transpose(1, 2, 0)
    return float(_linear_rss((y + g_frames * -fall)[None], X, g_frames)[0])


def _switching_fit(y: NDArray, k: int, e: int, after: int, g_frames: float, taus: NDArray, sigma: float
                   ) -> tuple[float, float, float, NDArray, NDArray]:
    """Step 3: the switching times and the ring time with the fall at g (a grid, then refined), then every parameter
    free at them: returns (t_d, t_on, tau, the linear parameters, the covariance of (y_r, a, b, c, t_d, t_on, tau),
    t_on's variance from the residual sum's profile)."""
    from scipy.optimize import minimize

    rows = np.arange(max(0, k - 20), min(y.size, e + 1 + after))
    rows = rows[np.isfinite(y[rows])]
    t, yr = rows.astype(float), y[rows]
    pd, po, pt = np.meshgrid(np.arange(k - 4.0 - 0.5 * taus.max(), k + _GRID / 2, _GRID),
                             np.arange(e - _RETURN_BEFORE, e + 1.5 + _GRID / 2, _GRID), taus, indexing="ij")
    keep = po > pd + 0.5
    pd, po, pt = pd[keep], po[keep], pt[keep]
    rss = np.concatenate([_grid_rss(yr, t, pd[pt == v], po[pt == v], float(v), g_frames) for v in taus])
    pd, po, pt = (np.concatenate([x[pt == v] for v in taus]) for x in (pd, po, pt))

    def refined(mask: NDArray, free_tau: bool) -> tuple[float, float, float, float, int]:
        """(t_d, t_on, tau, residual sum, grid index) of the best grid point among ``mask``, refined."""
        b = int(np.flatnonzero(mask)[np.argmin(rss[mask])])
        x0 = [pd[b], po[b], float(pt[b]) + 0.05] if free_tau else [pd[b], po[b]]
        known: dict[bytes, float] = {}  # the simplex revisits about half of its points once it has shrunk

        def objective(p: NDArray) -> float:
            key = p.tobytes()
            if key not in known:
                known[key] = _point_rss(yr, t, p[0], p[1], abs(p[2]) if free_tau else 0.0, g_frames)
            return known[key]

        res = minimize(objective, x0, method="Nelder-Mead", options={"xatol": 1e-3, "fatol": 1e-30, "maxiter": 600})
        inside = pd.min() <= res.x[0] <= pd.max() and po.min() <= res.x[1] <= po.max() and res.x[1] > res.x[0]
        if inside and res.fun <= rss[b]:
            return float(res.x[0]), float(res.x[1]), abs(float(res.x[2])) if free_tau else 0.0, float(res.fun), b
        return float(pd[b]), float(po[b]), float(pt[b]), float(rss[b]), b

    instant, ringing = refined(pt == 0, False), refined(np.ones(pt.size, bool), True)
    # a ring time only where it lowers the residual sum by more than chance does (10 noise variances: one parameter
    # more at a 0.2 % false-alarm rate); else the instant switch (t_d and tau otherwise trade off within the noise)
    ring = instant[3] - ringing[3] > 10.0 * sigma ** 2
    td, ton, tau, fun, best = ringing if ring else instant
    X = _columns(t, td, ton, tau)
    beta, *_ = np.linalg.lstsq(X, yr, rcond=None)
    var = float(np.sum((yr - X @ beta) ** 2)) / max(rows.size - 7, 1)
    # t_on's error: the half width of the times whose residual sum lies within one noise variance of the least
    near = po[(rss <= fun + var) & (ring | (pt == 0))]
    err_on = max(0.5 * float(near.max() - near.min()), abs(ton - po[best]), _GRID) if near.size else _GRID
    h = 1e-3  # a's error with the switching and ring times free: the Jacobian in them by central differences [frames]
    lo = max(tau - h, 0.0)
    jac = [(_columns(t, td + h, ton, tau) @ beta - _columns(t, td - h, ton, tau) @ beta) / (2 * h),
           (_columns(t, td, ton + h, tau) @ beta - _columns(t, td, ton - h, tau) @ beta) / (2 * h),
           (_columns(t, td, ton, tau + h) @ beta - _columns(t, td, ton, lo) @ beta) / (tau + h - lo)]
    J = np.column_stack([X, *jac])
    cov = var * np.linalg.pinv(J.T @ J)
    cov[5, 5] = err_on ** 2
    cov[0, 0] = var  # the residuals' variance in place of y_r's (not used): the fit's scatter
    return td, ton, tau, beta, cov


def find_drop_phases(t: ArrayLike, y: ArrayLike, noise: float | None = None,
                     g: float = STANDARD_GRAVITY) -> DropPhases | None:
    """The rest, the fall and the field's return in a recording's heights (module docstring).

    Parameters
    ----------
    t : array_like (n,)
        Frame times [s], uniform.
    y : array_like (n,)
        Heights [m] (NaN where a frame was not measured), up or down.
    noise : float, optional
        The noise of one frame [m]; default: the robust scale of the rest frames' successive differences.
    g : float
        The acceleration of free fall [m/s^2].

    Returns
    -------
    DropPhases or None
        None when the series does not begin at rest, or its departure from rest does not end within
        :data:`MAX_FALL_S` (a series at rest throughout, or one that never comes back under the field).
    """
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    if t.size < 4 * MIN_REST_FRAMES:
        return None
    dt = float((t[-1] - t[0]) / (t.size - 1))
    rest = starts_at_rest(y, noise, dt)
    if rest is None:
        return None
    k, level, sigma = rest
    g_frames = float(np.sign(y[k] - level)) * g * dt * dt  # the signed free fall per frame squared
    taus = np.arange(0.0, MAX_RING_S / dt + _RING_GRID / 2, _RING_GRID)  # ring times searched [frames]
    e = _rough_return(y, k, level, g_frames, sigma, int(math.ceil(MAX_FALL_S / dt)), taus)
    if e is None:
        return None
    after = max(4, int(round(AFTER_S / dt)))
    td, ton, tau, beta, cov = _switching_fit(y, k, e, after, g_frames, taus, sigma)
    err_on = math.sqrt(float(cov[5, 5]))
    a_err = math.sqrt(max(float(cov[1, 1]), 0.0)) / (dt * dt)
    first = max(int(math.ceil(ton + 2.0 * err_on)), e + 1)  # never before the frames that leave the fall
    return DropPhases(rest_frames=int(math.floor(td)) + 1 if td >= 0 else 0, drop_frame=td, field_on_frame=ton,
                      field_on_frame_error=err_on, first_field_on_frame=min(first, y.size - 1),
                      fall_acceleration=-float(beta[1]) / (dt * dt), fall_acceleration_error=a_err,
                      rest_level=float(beta[0]), noise=sigma, fit_scatter=math.sqrt(float(cov[0, 0])),
                      frame_interval=dt, ring_frames=tau)


def field_on_start(path, t: NDArray, y: NDArray) -> int:
    """The first frame of the field-on motion of a run that still holds its field drop (at rest, then the free fall
    with the field off; :mod:`cubedimer.drop_phases`): the run is cut there, with a warning; 0 for a run that does not
    start at rest.  A run that starts at rest and then moves without a free fall is refused in one line."""
    rest = starts_at_rest(y, dt=float((t[-1] - t[0]) / (t.size - 1)) if t.size > 1 else None)
    if rest is None:
        return 0
    ph = find_drop_phases(t, y)
    if ph is None or not ph.free_fall:
        how = ("does not come back under a field within {:g} ms".format(1e3 * MAX_FALL_S) if ph is None else
               f"moves, but not in a free fall (acceleration {ph.fall_acceleration:.3g} m/s^2 against g = 9.81, "
               f"residual RMS {ph.fit_scatter:.2g} m against a noise of {ph.noise:.2g} m)")
        raise DatasetError(f"{path}: starts with {rest[0]} frames at rest and then {how}: not the field-on motion "
                           "of a field drop; cut the file to the motion with the field on (python -m tracking track "
                           "writes it so; docs/formats.md)")
    k = ph.first_field_on_frame
    logger.warning("%s: the run still holds its field drop (at rest for %d frames, the field off for %.2f ms, a fall "
                   "of %.3g m/s^2): cut at the field's return, t = %.6g s; the first %d frames are left out", path.name,
                   ph.rest_frames, 1e3 * ph.field_off_s, ph.fall_acceleration, t[0] + ph.field_on_frame *
                   ph.frame_interval, k)
    return k
