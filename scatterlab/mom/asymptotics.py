r"""Asymptotic limits the MoM must approach: first-order small perturbation theory (SPM1) and
physical optics (Kirchhoff), both polarizations.

* :func:`spm1_coefficient` -- incoherent scattering coefficient of a slightly rough 1-D surface
  (per radian, per incident power, as :meth:`~scatterlab.mom.Solution.scattering_coefficient`):

  .. math:: \sigma(\theta_s) = 4k^3\cos\theta_i\cos^2\theta_s\,|\alpha|^2\,W(k\sin\theta_s -
            k\sin\theta_i)

  with :math:`\alpha_s = (\epsilon-1)/[(\cos\theta_i + q_i)(\cos\theta_s + q_s)]`,
  :math:`\alpha_p = (\epsilon-1)(\epsilon\sin\theta_i\sin\theta_s - q_iq_s)/
  [(\epsilon\cos\theta_i + q_i)(\epsilon\cos\theta_s + q_s)]`,
  :math:`q = \sqrt{\epsilon - \sin^2\theta}`, :math:`\epsilon = \eta^2` (Tsang, Kong, Ding and Ao,
  2001; Thorsos 1989 for the PEC); the perfect-conductor limits are :math:`\alpha_s = 1` and
  :math:`\alpha_p = (\sin\theta_i\sin\theta_s - 1)/(\cos\theta_i\cos\theta_s)`. Valid for
  :math:`k\sigma_h \ll 1` and small slopes.
* :func:`periodogram` -- the complex amplitude
  :math:`a = \int f\,\psi_{inc}e^{jkx\sin\theta_s}dx / \sqrt{2\pi\int|\psi_{inc}|^2dx}` of one
  realization under a tapered wave, whose :math:`|a|^2` has the ensemble mean W (convolved with
  the taper's narrow spectrum). SPM1's first-order field is proportional to it, so the same
  incoherent estimator applied to a and to the MoM far field removes most of the Monte-Carlo
  scatter from their comparison (a control variate).
* :func:`physical_optics` -- the Kirchhoff solution on a PEC contour:
  :math:`U = 2\partial_n\psi_{inc}` (s) or :math:`\psi = 2\psi_{inc}` (p) on the lit side, zero in
  the shadow, as a :class:`~scatterlab.mom.Solution` (far field, echo width, coefficients).
"""

from __future__ import annotations

import numpy as np

from scatterlab._checks import as_angle, as_index, as_positive, as_rng
from scatterlab.fresnel import refraction_term
from scatterlab.mom.efie import Solution
from scatterlab.mom.surfaces import gaussian_spectrum

__all__ = [
    "compare_physical_optics",
    "compare_spm1",
    "periodogram",
    "physical_optics",
    "spm1_alpha",
    "spm1_coefficient",
]


def spm1_alpha(theta_i, theta_s, polarization: str, eta=None):
    """SPM1 polarization factor alpha (module docstring), broadcast over the angles [rad].

    Parameters
    ----------
    theta_i, theta_s : float or array [rad] -- incidence and scattering angles (theta_s > 0
        forward).
    polarization : "s" or "p"
    eta : complex, optional -- index ``n - 1j*kappa`` of the lower medium (checked as in
        :func:`~scatterlab.mom.solve`); None is a perfect conductor.

    Returns
    -------
    ndarray complex -- alpha. The square root ``q = sqrt(eta^2 - sin^2 theta)`` is the branch
    ``A - jB`` with ``A, B >= 0`` (docs/conventions.md), continuous as kappa -> 0+.
    """
    ci, cs, si, ss = np.cos(theta_i), np.cos(theta_s), np.sin(theta_i), np.sin(theta_s)
    if polarization not in ("s", "p"):
        raise ValueError(f"polarization must be 's' or 'p', got {polarization!r}")
    if eta is None:
        return np.asarray(
            1.0 + 0 * ss if polarization == "s" else (si * ss - 1) / (ci * cs), complex
        )
    eta = complex(as_index(eta, "eta"))
    e = eta**2
    # the package's stable u = sqrt(eta^2 - sin^2) = A - jB (sin^2 is even in the angle)
    qi, qs = refraction_term(eta, np.abs(theta_i)), refraction_term(eta, np.abs(theta_s))
    if polarization == "s":
        return (e - 1) / ((ci + qi) * (cs + qs))
    return (e - 1) * (e * si * ss - qi * qs) / ((e * ci + qi) * (e * cs + qs))


def spm1_coefficient(theta_i, theta_s, k, spectrum, polarization: str = "s", eta=None):
    """SPM1 incoherent scattering coefficient [1/rad] (module docstring).

    Parameters
    ----------
    theta_i, theta_s : float or array [rad]
    k : float [rad/m] -- wavenumber above the surface (finite, > 0).
    spectrum : callable K -> W(K) [m^3], or a tuple (sigma_h, corr_length) [m] of a Gaussian
        correlation (:func:`scatterlab.mom.surfaces.gaussian_spectrum`), exactly two entries. The
        callable receives the array K = k (sin theta_s - sin theta_i) [rad/m] and must return
        finite values >= 0 (a power spectrum) of K's shape or one that broadcasts to it.
    polarization : "s" or "p"
    eta : complex, optional -- index ``n - 1j*kappa``, checked as in :func:`~scatterlab.mom.solve`;
        None is a perfect conductor.

    Returns
    -------
    ndarray -- coefficient per radian of theta_s, per incident power.

    Raises
    ------
    ValueError
        If ``k`` is not finite and > 0, ``theta_i`` or ``theta_s`` is not finite within [-pi/2, pi/2], a
        Gaussian spectrum's ``sigma_h`` is negative or ``corr_length`` not > 0, the tuple does not hold
        exactly two entries, ``spectrum`` is neither a tuple nor callable or its values are not finite and
        >= 0 (or do not broadcast to K), or ``eta`` is not a passive index (see ``solve``).
    """
    theta_i = as_angle(theta_i, "theta_i", -np.pi / 2, np.pi / 2)
    theta_s = as_angle(theta_s, "theta_s", -np.pi / 2, np.pi / 2)
    if isinstance(spectrum, tuple):
        if len(spectrum) != 2:
            raise ValueError(
                "spectrum must be a callable K -> W(K) or a tuple (sigma_h, corr_length) of exactly "
                f"two entries, got a tuple of {len(spectrum)}"
            )
        sigma_h = float(as_positive(spectrum[0], "sigma_h", allow_zero=True))
        ell = float(as_positive(spectrum[1], "corr_length"))

        def spectrum(q):
            return gaussian_spectrum(q, sigma_h, ell)

    elif not callable(spectrum):
        raise ValueError(
            "spectrum must be a callable K -> W(K) or a tuple (sigma_h, corr_length), got "
            f"{type(spectrum).__name__}"
        )
    k = as_positive(k, "k")
    K = k * (np.sin(theta_s) - np.sin(theta_i))
    alpha = spm1_alpha(theta_i, theta_s, polarization, eta)
    W = _spectrum_values(spectrum, K)
    return 4 * k**3 * np.cos(theta_i) * np.cos(theta_s) ** 2 * np.abs(alpha) ** 2 * W


def _spectrum_values(spectrum, K):
    """``spectrum(K)`` checked: real, finite and >= 0, broadcast to K's shape."""
    values = spectrum(K)
    W = np.asarray(values)
    if W.dtype.kind not in "iuf":  # complex, strings, objects: not a power spectrum
        raise ValueError(
            f"spectrum(K) must return real numbers (a power spectrum W(K) [m^3]), got {values!r}"
        )
    W = W.astype(float)
    try:
        W = np.broadcast_to(W, np.shape(K))
    except ValueError as exc:
        raise ValueError(
            f"spectrum(K) must return an array of K's shape {np.shape(K)} (or one that broadcasts "
            f"to it), got shape {W.shape}"
        ) from exc
    if not np.all(np.isfinite(W)):
        raise ValueError(
            "spectrum(K) must return finite values (no NaN or inf), got a non-finite one"
        )
    if np.any(W < 0):
        raise ValueError(
            f"spectrum(K) must return values >= 0 (a power spectrum W(K) [m^3]), got "
            f"{float(W.min()):g}"
        )
    return W


def periodogram(x, y, incidence, k, theta_s):
    """The spectrum of one profile seen by a tapered wave at K = k (sin theta_s - sin theta_i).

    Parameters
    ----------
    x, y : arrays (N,) [m] -- the profile on a uniform grid.
    incidence : TaperedWave
    k : float [rad/m]
    theta_s : array (S,) [rad]

    Returns
    -------
    ndarray (S,) complex [m^1.5] -- int f psi_inc e^{jk x sin theta_s} dx / sqrt(2 pi int
    |psi_inc|^2 dx); |a|^2 estimates W.
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    dx = float(np.mean(np.diff(x)))
    psi = incidence.field(x, 0 * x, k)
    f = y - np.mean(y)
    phase = np.exp(1j * k * np.sin(np.asarray(theta_s, float))[:, None] * x[None, :])
    amp = phase @ (f * psi) * dx
    return amp / np.sqrt(2 * np.pi * np.sum(np.abs(psi) ** 2) * dx)


def physical_optics(sol: Solution, incidence, polarization: str = "s") -> Solution:
    """The Kirchhoff solution on the contour of ``sol`` (a PEC solve) for ``incidence``.

    Parameters
    ----------
    sol : Solution -- gives the contour and k.
    incidence : PlaneWave or TaperedWave
    polarization : "s" (U = 2 d psi_inc/dn) or "p" (psi = 2 psi_inc), lit side only.

    Returns
    -------
    Solution -- with the physical-optics unknowns (residual 0).

    Raises
    ------
    ValueError
        ``polarization`` not "s" or "p".
    """
    if polarization not in ("s", "p"):
        raise ValueError(
            f"polarization must be 's' (E along z) or 'p' (H along z), got {polarization!r}"
        )
    c, k = sol.contour, sol.k
    d = np.array([np.sin(incidence.theta), -np.cos(incidence.theta)])
    lit = d[0] * c.nx + d[1] * c.ny < 0
    common = {"contour": c, "k": k, "incidences": [incidence], "residual": np.zeros(1)}
    if polarization == "s":
        U = np.where(lit, 2 * incidence.normal_derivative(c.x, c.y, c.nx, c.ny, k), 0)
        return Solution(current=U, quadrature=sol.quadrature, **common)
    psi = np.where(lit, 2 * incidence.field(c.x, c.y, k), 0)
    return Solution(
        current=np.zeros_like(psi),
        surface_field=psi,
        polarization="p",
        quadrature=sol.quadrature,
        **common,
    )


def compare_spm1(polarization, eta, count, length, rng, k_sigma=0.1, corr_length=1.0):
    """Incoherent MoM coefficient of ``count`` realizations against SPM1 (wavelength 1).

    Gaussian surfaces of k sigma_h = ``k_sigma`` and correlation length ``corr_length``
    [wavelengths], ``length`` [wavelengths] each, 10 points per wavelength in the denser medium,
    Thorsos taper g = length / 4 at theta_i = 30 deg.

    Parameters
    ----------
    polarization : "s" or "p"
    eta : complex or None
    count : int -- realizations (>= 2).
    length : float [wavelengths]
    rng : anything ``np.random.default_rng`` accepts.
    k_sigma, corr_length : float -- roughness.

    Returns
    -------
    dict -- theta_s (S,) [rad]; mom, spm1 (the realizations' periodograms through the same
    incoherent estimator), spm1_ensemble (Gaussian W, times the estimator's 1 - 1/count), all
    (S,) [1/rad]; ratio, the incoherent power of ``mom`` over that of ``spm1`` (integrated over
    theta_s), and ratio_se, its delete-one jackknife standard error over the realizations (the
    Monte-Carlo scatter the control variate leaves: with 8 realizations of 20 wavelengths the
    p-polarized PEC ratio varies by about 0.06 from seed to seed).
    """
    from scatterlab.mom.formulations import solve
    from scatterlab.mom.incidence import TaperedWave
    from scatterlab.mom.surfaces import rough_surface

    rng = as_rng(rng)
    k, ti = 2 * np.pi, np.radians(30)
    sigma_h = k_sigma / k
    ppw = 10 * max(1.0, abs(eta) if eta is not None else 1.0)
    th = np.radians(np.linspace(-89, 89, 357))
    F, A = [], []
    for _ in range(count):
        x, y = rough_surface(length, 1 / ppw, sigma_h, corr_length, rng)
        inc = TaperedWave(ti, length / 4, x0=0.5 * (x[0] + x[-1]))
        F.append(solve(x, y, 1.0, inc, polarization=polarization, eta=eta).far_field(th))
        A.append(periodogram(x, y, inc, k, th))
    F, A = np.array(F), np.array(A)
    norm = 8 * np.pi * k * inc.incident_power(k)
    q = k * (np.sin(th) - np.sin(ti))

    def incoherent(X):  # (N, S) -> (S,): mean power less the coherent part's
        return np.mean(np.abs(X) ** 2, 0) - np.abs(np.mean(X, 0)) ** 2

    def spm1_of(W):
        return spm1_coefficient(ti, th, k, lambda qq: np.interp(qq, q, W), polarization, eta)

    def ratio(idx):
        return np.trapezoid(incoherent(F[idx]) / norm, th) / np.trapezoid(
            spm1_of(incoherent(A[idx])), th
        )

    mom, spm1 = incoherent(F) / norm, spm1_of(incoherent(A))
    # delete-one jackknife of the integrated ratio (both sides lose the same realization)
    loo = np.array([ratio(np.delete(np.arange(count), i)) for i in range(count)])
    se = float(np.sqrt((count - 1) / count * np.sum((loo - loo.mean()) ** 2)))
    return {
        "theta_s": th,
        "mom": mom,
        "spm1": spm1,
        "spm1_ensemble": spm1_coefficient(ti, th, k, (sigma_h, corr_length), polarization, eta)
        * (1 - 1 / count),
        "ratio": float(np.trapezoid(mom, th) / np.trapezoid(spm1, th)),
        "ratio_se": se,
    }


def compare_physical_optics(polarization, ka, ppw=10.0):
    """A PEC circular cylinder of electrical radius ``ka`` (wavelength 1) against Kirchhoff.

    Parameters
    ----------
    polarization : "s" or "p"
    ka : float
    ppw : float -- points per wavelength.

    Returns
    -------
    (float, float) -- relative L2 difference of the echo widths over 120-180 deg from the
    incident direction (the reflection zone), and the MoM back-scatter over pi a.
    """
    from scatterlab.mom.formulations import solve
    from scatterlab.mom.incidence import PlaneWave

    k = 2 * np.pi
    phi = np.radians(np.arange(120, 181))
    a = ka / k
    n = int(np.ceil(2 * np.pi * a * ppw))
    t = 2 * np.pi * (np.arange(n) + 0.5) / n
    inc = PlaneWave(np.pi / 2)
    sol = solve(a * np.cos(t), a * np.sin(t), 1.0, inc, closed=True, polarization=polarization)
    ew = sol.echo_width(np.pi / 2 - phi)
    ew_po = physical_optics(sol, inc, polarization).echo_width(np.pi / 2 - phi)
    return float(np.linalg.norm(ew - ew_po) / np.linalg.norm(ew_po)), float(ew[-1] / (np.pi * a))
