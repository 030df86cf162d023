r"""Super-Gaussian DOLP priors and the MAP DOLP update (Eqs. 195-196, 198).

Prior (Eq. 195): :math:`\Pi(\mathcal P) = c_1\exp\{-[c_2(\mathcal P - c_3)]^m\}`, m even, c1 = 1: a smoothed
uniform density of half-width about :math:`1/c_2` around :math:`c_3`. The constants of the reference
(errata): Ch. V metal 7.2/0.15, dielectric 3.1/0.65; Ch. VI aluminium group 35/0.035, iron group 10.5/0.185,
dielectric 3.4/0.65; Ch. VII dielectric 4/0.7, metal 7/0.15; m = 10.

DOLP update (Eq. 196): with :math:`T = \sum_n\sum_y(\psi_{un} + \psi_{pn})` and :math:`Q = \sum_n\sum_y\psi_{pn}`
at a pixel, the M-step solves

.. math:: f(\mathcal P) = w\,m c_2^m\,\mathcal P(\mathcal P - 1)(\mathcal P - c_3)^{m-1} - \mathcal P T + Q = 0,

an (m+1)-order polynomial with :math:`f(0) = Q \ge 0` and :math:`f(1) = Q - T \le 0`, so a root lies in
[0, 1]. It is :math:`\mathcal P(1 - \mathcal P)` times the derivative of the complete-data objective
:math:`Q\ln\mathcal P + (T - Q)\ln(1 - \mathcal P) + w\ln\Pi`, a sum of concave terms (m even, w >= 0): the
objective has one maximum on [0, 1], the one root of f inside (0, 1) or an end (P = 0 at q = 0, P = 1 at
q = 1, where f vanishes for that factor's sake whether or not the objective peaks there). The coefficients
reach :math:`c_2^m \approx 10^{15}` (aluminium group) and, for priors the constructor accepts, 1e300 (and
more over a small T), so f is divided by ``T``, its prior term is evaluated in logs, and it is solved for
every pixel at once: the root lies between q = Q/T and c3 (see :func:`dolp_update`), the sign change on a
grid over that interval is bracketed and refined by safeguarded Newton steps -- never the companion matrix
per pixel (:func:`dolp_update_companion` does that for testing); without a sign change the maximum is at
an end of the interval, the one of larger objective.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass

import numpy as np

from scatterlab._checks import as_finite, as_positive

__all__ = [
    "SuperGaussianPrior",
    "PRIOR_SETS",
    "dolp_update",
    "dolp_update_companion",
    "adaptive_priors",
    "map_objective",
]


@dataclass(frozen=True)
class SuperGaussianPrior:
    """Eq. 195 with c1 = 1: ``exp(-[c2 (P - c3)]^m)``.

    Parameters
    ----------
    c2 : float
        Stiffness (a finite real number > 0, 1/DOLP): the half-width of the plateau is about 1 / c2;
        ``c2^m <= 1e300``.
    c3 : float
        Centre DOLP, a real number in [0, 1].
    m : int
        Even integer order >= 2 (the text's 10).
    name : str
        Material class label.

    Raises
    ------
    ValueError
        A constant of the wrong type (e.g. a string) or outside its range; the message names it.
    """

    c2: float
    c3: float
    m: int = 10
    name: str = ""

    def __post_init__(self):
        m = self.m
        if isinstance(m, (bool, np.bool_)) or not isinstance(m, numbers.Integral) or m < 2 or m % 2:
            raise ValueError(f"m must be an even integer >= 2, got {m!r}")
        for name in ("c2", "c3"):
            _check_real(getattr(self, name), name)
        if not (np.isfinite(self.c2) and self.c2 > 0):
            raise ValueError(f"c2 must be finite and > 0, got {self.c2!r}")
        if not (np.isfinite(self.c3) and 0 <= self.c3 <= 1):
            raise ValueError(f"c3 (the prior's centre DOLP) must be in [0, 1], got {self.c3!r}")
        if self.m * np.log10(self.c2) > 300:
            raise ValueError(f"c2^m = {self.c2:g}^{self.m} overflows (must be <= 1e300)")

    def log_pdf(self, P):
        """``-[c2 (P - c3)]^m`` (Eq. 195, c1 = 1), evaluated in logs so that huge c2^m never overflows: far
        from the centre it is a large finite negative number (floored at -1e300), never -inf or NaN for a
        finite P.

        Parameters
        ----------
        P : array_like
            DOLP (dimensionless), any shape.

        Returns
        -------
        ndarray
            The log prior (nats), shape of ``P``.
        """
        x = np.abs(self.c2 * (np.asarray(P, float) - self.c3))
        with np.errstate(divide="ignore"):
            logx = np.log(x)
        return -np.exp(np.minimum(self.m * logx, np.log(1e300)))


def _check_real(value, name: str) -> None:
    """ValueError naming ``name`` unless ``value`` is one real number (not a string, bool or array)."""
    ok = not isinstance(value, (str, bytes, bool, np.bool_)) and np.ndim(value) == 0
    if ok:
        try:
            float(value)
        except (TypeError, ValueError):
            ok = False
    if not ok:
        raise ValueError(f"{name} must be a real number, got {value!r}")


PRIOR_SETS = {
    "ch5": (
        SuperGaussianPrior(3.1, 0.65, name="dielectric"),
        SuperGaussianPrior(7.2, 0.15, name="metal"),
    ),
    "ch6": (
        SuperGaussianPrior(3.4, 0.65, name="dielectric"),
        SuperGaussianPrior(35.0, 0.035, name="aluminium"),
        SuperGaussianPrior(10.5, 0.185, name="iron"),
    ),
    "ch7": (
        SuperGaussianPrior(4.0, 0.7, name="dielectric"),
        SuperGaussianPrior(7.0, 0.15, name="metal"),
    ),
}


def _prior_set(priors, name: str = "priors") -> tuple:
    """A set of DOLP priors as a tuple: a key of :data:`PRIOR_SETS` (``"ch5"``, ``"ch6"``, ``"ch7"``: the names
    scene files and the command line use), one :class:`SuperGaussianPrior`, or a sequence of them.

    Parameters
    ----------
    priors : str, SuperGaussianPrior or sequence of SuperGaussianPrior
        The priors (an empty sequence gives an empty tuple).
    name : str
        The argument's name, for the error message.

    Returns
    -------
    tuple of SuperGaussianPrior

    Raises
    ------
    ValueError
        An unknown key (the message lists the valid ones), or an element that is not a SuperGaussianPrior.
    """
    if isinstance(priors, str):
        if priors not in PRIOR_SETS:
            raise ValueError(
                f"{name} must be one of the prior sets {sorted(PRIOR_SETS)} (PRIOR_SETS) or a "
                f"sequence of SuperGaussianPrior, got {priors!r}"
            )
        return PRIOR_SETS[priors]
    if isinstance(priors, SuperGaussianPrior):
        return (priors,)
    try:
        out = tuple(priors)
    except TypeError:
        out = None
    if out is None or not all(isinstance(p, SuperGaussianPrior) for p in out):
        raise ValueError(
            f"{name} must be a key of PRIOR_SETS {sorted(PRIOR_SETS)}, a SuperGaussianPrior or a "
            f"sequence of them, got {priors!r}"
        )
    return out


def map_objective(P, T, Q, prior: SuperGaussianPrior | None, weight: float = 1.0):
    """Complete-data objective of the DOLP at a pixel: Q ln P + (T - Q) ln(1 - P) + w ln Pi(P).

    Parameters
    ----------
    P : array_like
        DOLP (dimensionless, clipped to (0, 1) so the logs stay finite).
    T, Q : array_like
        Expected photon total and polarized total of the pixel (counts); broadcast with ``P``.
    prior : SuperGaussianPrior or None
        The prior (Eq. 195); None drops the prior term.
    weight : float or array_like
        Weight w of the log prior (dimensionless).

    Returns
    -------
    ndarray
        The objective (nats), shape of ``broadcast(P, T, Q)``.
    """
    P = np.clip(P, 1e-300, 1 - 1e-16)
    out = Q * np.log(P) + (T - Q) * np.log1p(-P)
    if prior is not None:
        with np.errstate(over="ignore", invalid="ignore"):
            lp = np.nan_to_num(weight * prior.log_pdf(P), nan=-np.inf)
        out = out + lp
    return out


# ln of the cap on each scaled term of f and f' (e^600 ~ 4e260): a capped term exceeds |P - q| <= 1 by far, so f
# keeps its sign, and (m - 1) times it stays finite for any order a prior can have
_LOG_CAP = 600.0


def _log_a(T, prior: SuperGaussianPrior, weight: float):
    """ln a with a = w m c2^m / T (-inf for w = 0): a itself reaches 1e600 and more (c2^m = 1e300, T = 1e-300)."""
    with np.errstate(divide="ignore"):
        return np.log(weight) + np.log(prior.m) + prior.m * np.log(prior.c2) - np.log(T)


def _f_and_slope(x, q, la, c3, m, slope=True):
    """f(P) / T = a P (P - 1) (P - c3)^(m-1) - P + q (q = Q/T, ln a = ``la``) and its slope at ``x`` (None
    without ``slope``).

    The prior's terms are evaluated in logs, each capped at e^600 (``_LOG_CAP``): no overflow for any ``a``,
    the sign of f is exact where a term is capped (the rest, q - P, is at most 1), and near a root, where
    the terms are of order 1, nothing is capped.
    """
    u = x - c3
    s = np.sign(u)  # u^(m-1) has the sign of u (m even); P (P - 1) <= 0
    with np.errstate(divide="ignore", invalid="ignore"):
        lu = np.log(np.abs(u))
        lxx = np.log(x) + np.log1p(-x)  # ln[P (1 - P)]
        # ln |u|^(m-2), 0 for m = 2 (also at u = 0)
        lum2 = (m - 2) * lu if m > 2 else np.zeros_like(lu)
        # |a P (P - 1) u^(m-1)|
        f = q - x - s * np.exp(np.minimum(la + lxx + lum2 + lu, _LOG_CAP))
        if not slope:
            return f, None
        # a |u|^(m-1) and a P (1 - P) |u|^(m-2)
        g1 = np.exp(np.minimum(la + lum2 + lu, _LOG_CAP))
        g2 = np.exp(np.minimum(la + lxx + lum2, _LOG_CAP))
    return f, s * (2 * x - 1) * g1 - (m - 1) * g2 - 1


def _inner_sign(f, df, lower):
    """The sign of f just inside a bracket end where f is ``f`` and its slope ``df``: f itself, or where f is 0
    (P = 0 at q = 0, P = 1 at q = 1, q = 0 exactly or a term too small to register) the slope's, negated at
    the upper end (f(x -+ e) ~ -+ e f'(x)). Returns a float whose sign bit is the sign."""
    inner = df if lower else -df
    return np.where(f == 0, inner, f)


def _scaled_objective(P, T, q, prior, weight):
    """The objective :func:`map_objective` divided by T + w (the same maximiser): T / (T + w) and w / (T + w)
    stay in [0, 1] where w / T would overflow (T down to 1e-300)."""
    big = T >= weight
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(big, weight / np.where(big, T, 1.0), T / np.where(big, 1.0, weight))
    alpha = np.where(big, 1.0, r) / (1.0 + r)
    beta = np.where(big, r, 1.0) / (1.0 + r)
    return map_objective(P, alpha, alpha * q, prior, beta)


def dolp_update(T, Q, prior: SuperGaussianPrior | None = None, weight: float = 1.0) -> np.ndarray:
    """MAP (or, without a prior, ML: Q/T) DOLP update for every pixel (Eq. 196).

    Pixels with T = 0 (no photons) keep P = 0 for the ML update and the prior's centre with a prior.
    The objective Q ln P + (T - Q) ln(1 - P) + w ln Pi(P) is strictly concave on (0, 1) (a sum of concave
    terms for w >= 0 and m even), so its maximum is unique: the one root of f (Eq. 196) inside (0, 1), or the
    end P = 0 (q = 0) or P = 1 (q = 1) where the objective falls away from it. Bracket: with
    g(P) = a P (P - 1) (P - c3)^(m-1), g >= 0 on [0, c3] and g <= 0 on [c3, 1], so the root (g = P - q) lies
    between q and c3 and nowhere else. f is evaluated on 9 points spanning [min(q, c3), max(q, c3)] in a
    scaled log form (no overflow for any c2^m <= 1e300, weight or T; :func:`_f_and_slope`), where f is 0 at
    an end its sign just inside is taken from the slope, the first sign change from + to - is solved by
    Newton steps safeguarded by bisection (:func:`_safeguarded_newton`, to 1e-13 relative in P and in
    1 - P, or a unit in the last place); without a sign change the maximum is at an end, and the end of
    larger objective is returned.

    Parameters
    ----------
    T : array_like
        Expected photon total of the pixel, sum over frames of psi_u + psi_p (counts, finite, >= 0).
    Q : array_like
        Expected polarized photon total, sum of psi_p (counts, finite, clipped to >= 0); broadcasts
        with ``T``.
    prior : SuperGaussianPrior or None
        The DOLP prior (Eq. 195); None gives the ML update Q / T.
    weight : float
        Weight w of the log prior in the objective: one number (dimensionless, finite, >= 0, default 1),
        not an array.

    Returns
    -------
    ndarray
        The updated DOLP, shape of ``broadcast(T, Q)``, in [0, 1].
    """
    T = as_positive(T, "T", allow_zero=True)
    Q = as_finite(Q, "Q")
    if np.ndim(weight) != 0:
        raise ValueError(
            f"weight must be a single number >= 0 (one weight for every pixel), got shape "
            f"{np.shape(weight)}"
        )
    weight = float(as_positive(weight, "weight", allow_zero=True))
    return _dolp_update(T, Q, prior, weight)


def _dolp_update(T, Q, prior: SuperGaussianPrior | None = None, weight: float = 1.0) -> np.ndarray:
    """:func:`dolp_update` without the argument checks, for the EM's M-step: ``T <= 0`` (also the FFT
    round-off of -1e-17 where no light falls) is no light, ``Q`` is clipped at 0."""
    T = np.asarray(T, float)
    Q = np.clip(np.asarray(Q, float), 0.0, None)
    T, Q = np.broadcast_arrays(T, Q)
    empty = T <= 0
    Ts = np.where(empty, 1.0, T)
    # Q >= T is q = 1; below it Q / T <= 1 cannot overflow (T down to 1e-300)
    q = np.divide(Q, Ts, out=np.ones_like(Ts), where=Q < Ts)
    if prior is None:
        return np.where(empty, 0.0, q)
    m, c3 = prior.m, float(np.clip(prior.c3, 0.0, 1.0))
    Tf, qf = Ts.ravel(), q.ravel()
    la = _log_a(Tf, prior, weight)  # a = w m c2^m / T, up to 1e600 and more: only ever used in logs
    lo_b, hi_b = np.minimum(qf, c3), np.maximum(qf, c3)
    t = np.linspace(0.0, 1.0, 9)[:, None]
    xs = lo_b + (hi_b - lo_b) * t  # (9, pixels)
    fg, _ = _f_and_slope(xs, qf, la, c3, m, slope=False)
    # f(min) >= 0 >= f(max); where f is 0 at an end (q = 0 or 1, or an underflow) its sign just inside counts
    fg[0] = _inner_sign(fg[0], _f_and_slope(lo_b, qf, la, c3, m)[1], lower=True)
    fg[-1] = _inner_sign(fg[-1], _f_and_slope(hi_b, qf, la, c3, m)[1], lower=False)
    neg = np.signbit(fg)
    # f from + (or +0) to -: concavity leaves one such cell, round-off may add some
    change = ~neg[:-1] & neg[1:]
    has = change.any(axis=0) & (hi_b > lo_b)
    (idx,) = np.nonzero(has)
    j = np.argmax(change[:, idx], axis=0)  # the first of them
    r_lo, r_hi = lo_b.copy(), lo_b.copy()
    r_lo[idx], r_hi[idx] = _safeguarded_newton(
        xs[j, idx], xs[j + 1, idx], fg[j, idx], qf[idx], la[idx], c3, m
    )
    # the candidates, of which the largest objective wins: the ends of the root's final bracket (adjacent
    # floats where a stiff prior peaks a few units from 1), or without a sign change (the maximum at an end)
    # the ends of the interval. Not both: the objective ties within its rounding over ~1e-8 of a flat
    # maximum, and an end would win such a tie against the root as often as not
    cand = np.stack([np.where(has, r_lo, lo_b), np.where(has, r_hi, hi_b)])
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        obj = _scaled_objective(cand, Tf, qf, prior, weight)
    obj = np.where(np.isnan(obj), -np.inf, obj)
    out = cand[np.argmax(obj, axis=0), np.arange(qf.size)].reshape(q.shape)
    return np.where(empty, c3, out)


def _wide(lo, hi):
    """Brackets spanning more than a factor 4 (P = 0 counts as 1e-300): bisected geometrically."""
    return hi > 4 * np.maximum(lo, 1e-300)


def _bisection_point(lo, hi):
    """Middle of [lo, hi] on the scale the objective sees (its ln P).

    Geometric while the bracket spans more than a factor 4, with the lower end taken as at least
    ``1e-20 hi`` (and 1e-300): an optimum at P ~ 1e-16 is reached in about ten halvings of ln P, not
    fifty of P, and one near ``hi`` in about five. Arithmetic otherwise.
    """
    lo_eff = np.maximum(np.maximum(lo, 1e-20 * hi), 1e-300)
    # sqrt of each: lo_eff * hi underflows to 0 below 5e-324 (an optimum at P ~ 1e-160)
    return np.where(_wide(lo, hi), np.sqrt(lo_eff) * np.sqrt(hi), 0.5 * (lo + hi))


def _safeguarded_newton(lo, hi, flo, q, loga, c3, m, rtol=1e-13, max_iter=200):
    """Roots of f (:func:`_f_and_slope`) in the brackets [lo, hi] (f(lo) has the sign of ``flo``).

    Vectorised Newton iteration safeguarded by bisection: where the bracket spans more than a
    factor 4, or a Newton step leaves it, is not finite or is not at most half the step before, the
    next point is :func:`_bisection_point` (geometric on wide brackets, so an optimum many decades below
    the bracket's top is approached in ln P). Each step keeps the sub-interval where f changes sign, so
    the bracket always holds a root; a Newton step below the tolerance is followed by a probe just
    across the root, which closes the bracket. Converged when the bracket is below ``rtol`` times
    min(P, 1 - P) (the objective's ln P and ln(1 - P) need relative accuracy in both: an optimum at
    P ~ 1e-16 is resolved, which an absolute tolerance would miss) or below a unit in the last place
    (where a stiff prior's optimum lies a few units from 1, each one counts); iterates only on the
    unconverged brackets.

    Parameters
    ----------
    lo, hi : ndarray, shape (k,)
        Bracket ends, 0 <= lo < hi <= 1 (DOLP, dimensionless).
    flo : ndarray, shape (k,)
        f at ``lo`` (or any value of its sign).
    q, loga : ndarray, shape (k,)
        q = Q / T and ln a, a = w m c2^m / T, of each bracket's pixel.
    c3 : float
        Prior centre (DOLP).
    m : int
        Prior order (even, >= 2).
    rtol : float
        Relative tolerance on P and on 1 - P.
    max_iter : int
        Iteration cap.

    Returns
    -------
    lo, hi : ndarray, shape (k,)
        The final brackets (DOLP, dimensionless), at most the tolerance wide (both ends at a root where f
        is 0 there): near 1 a stiff prior's objective changes much between adjacent floats, so the caller
        takes the end of larger objective.
    """
    lo, hi, flo = lo.copy(), hi.copy(), flo.copy()
    x = _bisection_point(lo, hi)
    step = np.full(x.size, np.inf)  # the last step taken
    active = np.arange(x.size)
    for _ in range(max_iter):
        if not active.size:
            break
        xa, la, ha = x[active], lo[active], hi[active]
        f, df = _f_and_slope(xa, q[active], loga[active], c3, m)
        up = np.signbit(f) == np.signbit(
            flo[active]
        )  # f at xa has the sign at lo: the root lies above
        la = np.where(up, xa, la)
        ha = np.where(up, ha, xa)
        flo[active] = np.where(up, f, flo[active])
        tol = np.maximum(rtol * np.minimum(xa, 1 - xa), np.spacing(xa))
        done = (ha - la <= tol) | (f == 0)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            xn = xa - f / df
        newton = np.abs(xn - xa)
        # a Newton step below the tolerance probes 0.9 tol beyond xa toward the root: across it, the bracket
        # closes; one that does not land inside the bracket, is not finite or does not halve the step before
        # (a root in the flat of a high power, e.g. (1 - P)^10 near c3 = 1, where Newton gains 10 % a step)
        # gives way to bisection, as a wide bracket does
        small = newton <= tol
        xn = np.where(small, xa + np.where(up, 0.9, -0.9) * tol, xn)
        slow = ~small & (newton > 0.5 * step[active])
        bad = _wide(la, ha) | slow | ~((xn > la) & (xn < ha))
        if np.any(bad):
            xn[bad] = _bisection_point(la[bad], ha[bad])
        xn = np.where(done, xa, xn)
        step[active] = np.abs(xn - xa)
        root = f == 0
        x[active], lo[active], hi[active] = xn, np.where(root, xa, la), np.where(root, xa, ha)
        active = active[~done]
    return lo, hi


def dolp_update_companion(T, Q, prior: SuperGaussianPrior, weight: float = 1.0) -> float:
    """Reference for one pixel: the real roots in [0, 1] of Eq. 196 by the companion matrix (numpy.roots),
    and the ends of the bracket (:func:`dolp_update`), the one with the largest objective. Slow and, for
    c2^m ~ 1e15, needs the scaling by T to stay accurate; below T ~ 1 (a = w m c2^m / T large) the cluster of
    roots near c3 is ill-conditioned and the result is off by up to ~1e-3 (:func:`dolp_update` is not).

    Parameters
    ----------
    T, Q : float
        Photon total (> 0) and polarized total (0 <= Q <= T) of the pixel (counts).
    prior : SuperGaussianPrior
        The prior (Eq. 195).
    weight : float
        Weight of the log prior (dimensionless).

    Returns
    -------
    float
        The MAP DOLP in [0, 1].
    """
    from numpy.polynomial import polynomial as Pn

    m, c3 = prior.m, prior.c3
    T, Q = float(np.squeeze(T)), float(np.squeeze(Q))
    if not (T > 0 and 0 <= Q <= T):
        raise ValueError(f"need T > 0 and 0 <= Q <= T (a DOLP q = Q/T in [0, 1]), got T={T}, Q={Q}")
    a = weight * m * prior.c2**m / T
    # a P (P - 1) (P - c3)^(m-1) - P + q, coefficients in increasing powers
    poly = Pn.polymul(Pn.polymul([0, 1], [-1, 1]), Pn.polypow([-c3, 1], m - 1)) * a
    poly = Pn.polyadd(poly, [Q / T, -1])
    roots = Pn.polyroots(poly)
    real = roots[
        (np.abs(roots.imag) < 1e-9) & (roots.real >= -1e-12) & (roots.real <= 1 + 1e-12)
    ].real
    # with the ends of the bracket [min(q, c3), max(q, c3)] (the objective's maximum on them or between):
    # where roots crowd (q = 1 and a root near 1) the companion matrix turns them complex and drops them
    q = Q / T
    real = np.r_[np.clip(real, 0, 1), min(q, c3), max(q, c3)]
    obj = map_objective(real, 1.0, q, prior, weight / T)
    return float(real[np.argmax(obj)])


# the narrowest prior adaptive_priors returns, and the least spread of DOLP values it separates
_MIN_SD = 0.01


def adaptive_priors(dolp, base=PRIOR_SETS["ch5"], *, m: int = 10, mask=None):
    """Priors re-centred from the DOLP histogram (Sec. 8.1.1): two-means on the DOLP values, each prior centred
    on a cluster mean with a half-width of two cluster standard deviations (c2 = 1 / (2 std)), names kept
    from ``base`` (dielectric = the higher cluster). Extends the classifier toward near-normal geometry.

    Parameters
    ----------
    dolp : array_like
        DOLP image (any shape, dimensionless); NaN pixels, and the masked ones of a numpy masked array (as
        :func:`scatterlab.imaging.dolp_aop_from_stokes` returns), are ignored. Every other value must be
        finite and in [0, 1] (clip a noisy estimate with ``numpy.clip(dolp, 0, 1)``).
    base : str or tuple of SuperGaussianPrior
        The set whose names are kept (default Ch. V's), or its key in :data:`PRIOR_SETS`.
    m : int
        Order of the new priors (even).
    mask : array_like of bool, optional
        Pixels to use, shape of ``dolp``.

    Returns
    -------
    tuple of SuperGaussianPrior
        One prior per class, dielectric (higher DOLP) first.

    Raises
    ------
    ValueError
        ``dolp`` not numeric, a used value infinite or outside [0, 1], or ``mask`` not of ``dolp``'s
        shape; fewer than 10 finite DOLP values, or values with no contrast to separate classes: all within
        0.01 of each other (the narrowest standard deviation of the priors it returns), e.g. a constant
        image. Priors re-centred there would be indistinguishable (scipy's two-means left a cluster
        empty and two identical priors came back); classify such an image with fixed priors
        (:data:`PRIOR_SETS`) instead.
    """
    from scipy.cluster.vq import kmeans2

    base = _prior_set(base, "base")
    try:  # masked pixels (imaging's DOLP images) are left out
        v = np.ma.filled(np.ma.asarray(dolp, float), np.nan)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"dolp must be a numeric DOLP image, got {dolp!r}") from exc
    if mask is not None:
        mask = np.asarray(mask)
        if mask.dtype != bool or mask.shape != v.shape:
            raise ValueError(
                f"mask must be a boolean array of dolp's shape {v.shape}, got {mask.dtype} {mask.shape}"
            )
        v = v[mask]
    v = v[~np.isnan(v)].ravel()  # NaN: a pixel without light
    if np.isinf(v).any():
        raise ValueError(
            "dolp must be finite where it is used: it holds inf (NaN and masked pixels are ignored)"
        )
    if np.any((v < 0) | (v > 1)):
        worst = float(v[np.argmax(np.maximum(-v, v - 1))])
        raise ValueError(
            f"dolp must be in [0, 1], got {worst:g} (a noisy estimate can be clipped with "
            "numpy.clip(dolp, 0, 1); NaN and masked pixels are ignored)"
        )
    if v.size < 10:
        raise ValueError("adaptive_priors needs at least 10 finite DOLP values")
    spread = float(np.ptp(v))
    if spread < _MIN_SD:
        raise ValueError(
            f"dolp has no contrast to separate classes: its finite values span {spread:.3g}, less than "
            f"{_MIN_SD} (the narrowest prior standard deviation); it must span at least {_MIN_SD}. "
            f"Classify it with fixed priors (PRIOR_SETS) instead"
        )
    lo, hi = np.quantile(v, [0.2, 0.8])
    if not hi > lo:  # most values equal: start from the extremes (equal starts empty a cluster)
        lo, hi = v.min(), v.max()
    cent, lab = kmeans2(v[:, None], np.array([[lo], [hi]]), minit="matrix", seed=0)
    out = []
    order = np.argsort(-cent[:, 0])  # dielectric first (higher DOLP), as in the base sets
    names = [p.name for p in base]
    for rank, k in enumerate(order[: len(base)]):
        sel = v[lab == k]
        sd = max(float(sel.std()) if sel.size > 1 else 0.05, _MIN_SD)
        out.append(
            SuperGaussianPrior(
                1 / (2 * sd),
                float(cent[k, 0]),
                m,
                name=names[rank] if rank < len(names) else f"class{rank}",
            )
        )
    return tuple(out)
