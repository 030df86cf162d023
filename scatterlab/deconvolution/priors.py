r"""Super-Gaussian DOLP priors and the MAP DOLP update (Eqs. 195-196, 198).

Prior (Eq. 195): :math:`\Pi(\mathcal P) = c_1\exp\{-[c_2(\mathcal P - c_3)]^m\}`, m even, c1 = 1: a smoothed
uniform density of half-width about :math:`1/c_2` around :math:`c_3`. The constants of the reference
(errata): Ch. V metal 7.2/0.15, dielectric 3.1/0.65; Ch. VI aluminium group 35/0.035, iron group 10.5/0.185,
dielectric 3.4/0.65; Ch. VII dielectric 4/0.7, metal 7/0.15; m = 10.

DOLP update (Eq. 196): with :math:`T = \sum_n\sum_y(\psi_{un} + \psi_{pn})` and :math:`Q = \sum_n\sum_y\psi_{pn}`
at a pixel, the M-step solves

.. math:: f(\mathcal P) = w\,m c_2^m\,\mathcal P(\mathcal P - 1)(\mathcal P - c_3)^{m-1} - \mathcal P T + Q = 0,

an (m+1)-order polynomial with :math:`f(0) = Q \ge 0` and :math:`f(1) = Q - T \le 0`, so a root lies in
[0, 1]. The coefficients reach :math:`c_2^m \approx 10^{15}` (aluminium group), so the polynomial is divided by
``T`` and solved for every pixel at once: the roots lie between q = Q/T and c3 (see :func:`dolp_update`), each
sign change on a grid over that interval is bracketed and refined by safeguarded Newton steps -- never the
companion matrix per pixel (:func:`dolp_update_companion` does that for testing). Where
several roots lie in [0, 1] the one with the largest complete-data objective
:math:`Q\ln\mathcal P + (T - Q)\ln(1 - \mathcal P) + w\ln\Pi` is taken.
"""

from __future__ import annotations

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
        Stiffness (> 0, 1/DOLP): the half-width of the plateau is about 1 / c2.
    c3 : float
        Centre DOLP in [0, 1].
    m : int
        Even order >= 2 (the text's 10).
    name : str
        Material class label.
    """

    c2: float
    c3: float
    m: int = 10
    name: str = ""

    def __post_init__(self):
        if self.m < 2 or self.m % 2:
            raise ValueError(f"m must be an even integer >= 2, got {self.m}")
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


def _ipow(x, k: int):
    """x**k for a small positive integer k by repeated squaring (float ** int calls pow() per element)."""
    out, base = None, x
    while k:
        if k & 1:
            out = base if out is None else out * base
        k >>= 1
        if k:
            base = base * base
    return out


def _f_scaled(P, q, a, c3, m):
    """f(P) / T with q = Q/T and a = w m c2^m / T."""
    return a * P * (P - 1) * _ipow(P - c3, m - 1) - P + q


def dolp_update(T, Q, prior: SuperGaussianPrior | None = None, weight: float = 1.0) -> np.ndarray:
    """MAP (or, without a prior, ML: Q/T) DOLP update for every pixel (Eq. 196).

    Pixels with T = 0 (no photons) keep P = 0 for the ML update and the prior's centre with a prior.
    Bracket: with g(P) = a P (P - 1) (P - c3)^(m-1), g >= 0 on [0, c3] and g <= 0 on [c3, 1], so a root
    (g = P - q) lies between q and c3 and nowhere else (P = 0 too when q = 0), and f(min) >= 0 >= f(max).
    Every sign change of f on 9 points spanning [min(q, c3), max(q, c3)] is bracketed, all brackets of all
    pixels are solved together by Newton steps safeguarded by bisection (:func:`_safeguarded_newton`, to
    1e-13 relative in P and in 1 - P), and where a pixel has several roots the one of largest objective is
    kept.

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
        Weight w of the log prior in the objective (dimensionless, finite, >= 0, default 1).

    Returns
    -------
    ndarray
        The updated DOLP, shape of ``broadcast(T, Q)``, in [0, 1].
    """
    T = as_positive(T, "T", allow_zero=True)
    Q = as_finite(Q, "Q")
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
    q = np.clip(Q / Ts, 0.0, 1.0)
    if prior is None:
        return np.where(empty, 0.0, q)
    m, c3 = prior.m, float(np.clip(prior.c3, 0.0, 1.0))
    # a few photons against c2^m ~ 1e15: the prior dominates; the cap keeps f finite (a P (P-1) (P-c3)^9 <= 1e200)
    a = np.minimum(weight * m * prior.c2**m / np.maximum(Ts, 1e-150), 1e200).ravel()
    qf = q.ravel()
    lo_b, hi_b = np.minimum(qf, c3), np.maximum(qf, c3)
    t = np.linspace(0.0, 1.0, 9)[:, None]
    xs = lo_b + (hi_b - lo_b) * t  # (17, pixels)
    fg = _f_scaled(xs, qf, a, c3, m)
    ends = np.flatnonzero(
        (fg[0] == 0) | (hi_b == lo_b)
    )  # q = 0 (or q = c3): the end point itself is a root
    # at q = 0 f leaves the root P = 0 with the sign of f'(0) = a c3^(m-1) - 1: bracket from there
    fg[0] = np.where(fg[0] == 0, a * c3 ** (m - 1) - 1, fg[0])
    neg = np.signbit(fg)
    j, idx = np.nonzero(neg[:-1] != neg[1:])  # bracket j of pixel idx (f = +0 counts as positive)
    P = _safeguarded_newton(xs[j, idx], xs[j + 1, idx], fg[j, idx], qf[idx], a[idx], c3, m)
    idx, P = np.r_[idx, ends], np.r_[P, lo_b[ends]]
    out = np.full(qf.size, np.nan)
    counts = np.bincount(idx, minlength=qf.size)
    single = counts[idx] == 1
    out[idx[single]] = P[single]
    multi = ~single
    if np.any(multi):
        im, Pm = idx[multi], P[multi]
        obj = map_objective(
            Pm, 1.0, qf[im], prior, np.minimum(weight / np.maximum(Ts.ravel()[im], 1e-200), 1e200)
        )
        order = np.lexsort((obj, im))  # per pixel, the root of largest objective comes last
        last = np.r_[im[order][1:] != im[order][:-1], True]
        out[im[order][last]] = Pm[order][last]
    out = np.where(np.isnan(out), qf, out).reshape(
        q.shape
    )  # no bracket: cannot happen (f(min) >= 0 >= f(max))
    return np.where(empty, c3, out)


def _f_and_slope(x, q, a, c3, m):
    """f (:func:`_f_scaled`) and df/dP at ``x``."""
    u = x - c3
    um2 = _ipow(u, m - 2) if m > 2 else np.ones_like(u)
    um1 = um2 * u
    f = a * x * (x - 1) * um1 - x + q
    df = a * ((2 * x - 1) * um1 + (m - 1) * x * (x - 1) * um2) - 1
    return f, df


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
    return np.where(_wide(lo, hi), np.sqrt(lo_eff * hi), 0.5 * (lo + hi))


def _safeguarded_newton(lo, hi, flo, q, a, c3, m, rtol=1e-13, max_iter=200):
    """Roots of f (:func:`_f_scaled`) in the brackets [lo, hi] (f(lo) has the sign of ``flo``).

    Vectorised Newton iteration safeguarded by bisection: where the bracket spans more than a
    factor 4, or a Newton step leaves it or is not finite, the next point is
    :func:`_bisection_point` (geometric on wide brackets, so an optimum many decades below the
    bracket's top is approached in ln P). Each step keeps the sub-interval where f changes sign, so
    the bracket always holds a root. Converged when the step or the bracket is below ``rtol`` times
    min(P, 1 - P) (the objective's ln P and ln(1 - P) need relative accuracy in both: an optimum at
    P ~ 1e-16 is resolved, which an absolute tolerance would miss) or below a few units in the last
    place; iterates only on the unconverged brackets.

    Parameters
    ----------
    lo, hi : ndarray, shape (k,)
        Bracket ends, 0 <= lo < hi <= 1 (DOLP, dimensionless).
    flo : ndarray, shape (k,)
        f at ``lo`` (or any value of its sign).
    q, a : ndarray, shape (k,)
        q = Q / T and a = w m c2^m / T of each bracket's pixel.
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
    ndarray, shape (k,)
        The roots (DOLP, dimensionless).
    """
    eps = np.finfo(float).eps
    lo, hi, flo = lo.copy(), hi.copy(), flo.copy()
    x = _bisection_point(lo, hi)
    active = np.arange(x.size)
    for _ in range(max_iter):
        if not active.size:
            break
        xa, la, ha = x[active], lo[active], hi[active]
        f, df = _f_and_slope(xa, q[active], a[active], c3, m)
        same = np.signbit(f) == np.signbit(flo[active])
        la = np.where(same, xa, la)
        ha = np.where(same, ha, xa)
        flo[active] = np.where(same, f, flo[active])
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            xn = xa - f / df
        bad = ~np.isfinite(xn) | (xn <= la) | (xn >= ha) | _wide(la, ha)
        if np.any(bad):
            xn[bad] = _bisection_point(la[bad], ha[bad])
        tol = np.maximum(rtol * np.minimum(xa, 1 - xa), 4 * eps * xa)
        done = (np.abs(xn - xa) <= tol) | (ha - la <= tol) | (f == 0)
        x[active], lo[active], hi[active] = np.where(f == 0, xa, xn), la, ha
        active = active[~done]
    return x


def dolp_update_companion(T, Q, prior: SuperGaussianPrior, weight: float = 1.0) -> float:
    """Reference for one pixel: the real roots in [0, 1] of Eq. 196 by the companion matrix (numpy.roots),
    the one with the largest objective. Slow and, for c2^m ~ 1e15, needs the scaling by T to stay accurate.

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
    real = np.clip(real, 0, 1)
    obj = map_objective(real, 1.0, Q / T, prior, weight / T)
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
        DOLP image (any shape, dimensionless); NaN pixels are ignored.
    base : tuple of SuperGaussianPrior
        The sets whose names are kept (default Ch. V's).
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
        Fewer than 10 finite DOLP values, or values with no contrast to separate classes: all within
        0.01 of each other (the narrowest standard deviation of the priors it returns), e.g. a constant
        image. Priors re-centred there would be indistinguishable (scipy's two-means left a cluster
        empty and two identical priors came back); classify such an image with fixed priors
        (:data:`PRIOR_SETS`) instead.
    """
    from scipy.cluster.vq import kmeans2

    v = np.asarray(dolp, float)
    v = v[np.isfinite(v) & (mask if mask is not None else True)].ravel()
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
