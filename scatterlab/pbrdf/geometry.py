r"""Microfacet scattering geometry (Eqs. 110-112, 130-131, 167, 170).

Coordinates: the mean surface normal is :math:`\hat z`; the unit vector towards
the source is :math:`\hat s_i = (\sin\theta_i, 0, \cos\theta_i)` (incident
azimuth 0) and towards the observer
:math:`\hat s_r = (\sin\theta_r\cos\phi, \sin\theta_r\sin\phi, \cos\theta_r)`,
so that :math:`\phi = \pi` is the forward specular plane (the reference text's
:math:`\phi = |\phi_r - \phi_i|`).

The facet that reflects :math:`\hat s_i` into :math:`\hat s_r` has normal
:math:`\hat h = (\hat s_i + \hat s_r)/(2\cos\beta)`, tilt :math:`\alpha` from
:math:`\hat z` and local angle of incidence :math:`\beta` (Eq. 167):

.. math::

   \cos 2\beta = \cos\theta_i\cos\theta_r + \sin\theta_i\sin\theta_r\cos\phi,\qquad
   \cos\alpha = \frac{\cos\theta_i + \cos\theta_r}{2\cos\beta}.

Polarization bases. For a wave travelling along :math:`\hat k` reflected by a
surface with outward normal :math:`\hat n`, :math:`\hat s = (\hat n\times\hat k)/|\cdot|`
and :math:`\hat p = \hat k\times\hat s`, so that :math:`(\hat s, \hat p, \hat k)` is
right-handed; with this choice the Fresnel coefficients of Eq. 45 map incident
(s, p) components to reflected ones. The macroscopic bases use
:math:`\hat n = \hat z`; they are defined for :math:`\theta = 0` too, as the limit
along the stated azimuths. The facet basis uses :math:`\hat n = \hat h`, whose
s axis is :math:`(\hat s_i\times\hat s_r)/\sin 2\beta`. The rotations of Eq. 169,

.. math::

   J = \begin{bmatrix}\cos\gamma_r & -\sin\gamma_r\\ \sin\gamma_r & \cos\gamma_r\end{bmatrix}
       \begin{bmatrix} r_s & 0\\ 0 & r_p\end{bmatrix}
       \begin{bmatrix}\cos\gamma_i & \sin\gamma_i\\ -\sin\gamma_i & \cos\gamma_i\end{bmatrix},

carry the signed angles :math:`\gamma_i = \angle(\hat s^{M}_i \to \hat s^{m})`
and :math:`\gamma_r = \angle(\hat s^{M}_r \to \hat s^{m})`; their cosines are those
of Eq. 170 up to the sign convention (tested), and they vanish in the specular
plane. At exact backscatter (:math:`\beta = 0`) the facet plane is undefined, but
then :math:`r_p = -r_s` and :math:`J` does not depend on it; the macroscopic s
axis is used.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scatterlab._checks import as_angle, as_azimuth, broadcast

__all__ = [
    "FacetGeometry",
    "facet_geometry",
    "in_plane_geometry",
    "check_angles",
    "polar_cos",
    "polar_cos_sin",
    "azimuth_cos_sin",
]


@dataclass(frozen=True)
class FacetGeometry:
    """Per-geometry facet quantities (all arrays of the broadcast shape).

    Attributes
    ----------
    cos_theta_i, cos_theta_r : cosines of the incidence and observation angles.
    tan2_alpha : :math:`\\tan^2\\alpha`, squared facet slope (computed without cancellation).
    cos_alpha : facet tilt cosine.
    cos_beta : cosine of the local angle of incidence on the facet (``beta`` property [rad]).
    cos_gi, sin_gi, cos_gr, sin_gr : rotation cosines and sines of Eq. 169.
    sin2_beta : :math:`\\sin^2\\beta = |\\hat s_i - \\hat s_r|^2/4`, to full relative accuracy near
        backscatter (where ``1 - cos^2`` would lose it); None where not computed.
    in_plane : True for :func:`in_plane_geometry` (the rotations vanish identically).
    """

    cos_theta_i: np.ndarray
    cos_theta_r: np.ndarray
    tan2_alpha: np.ndarray
    cos_alpha: np.ndarray
    cos_beta: np.ndarray
    cos_gi: np.ndarray
    sin_gi: np.ndarray
    cos_gr: np.ndarray
    sin_gr: np.ndarray
    sin2_beta: np.ndarray | None = None
    in_plane: bool = False

    @property
    def beta(self) -> np.ndarray:
        """Local angle of incidence on the facet [rad]."""
        return np.arccos(self.cos_beta)

    @property
    def gamma_i(self) -> np.ndarray:
        """Signed rotation angle gamma_i [rad] (Eq. 170 gives its cosine)."""
        return np.arctan2(self.sin_gi, self.cos_gi)

    @property
    def gamma_r(self) -> np.ndarray:
        """Signed rotation angle gamma_r [rad]."""
        return np.arctan2(self.sin_gr, self.cos_gr)

    @property
    def alpha(self) -> np.ndarray:
        """Facet tilt alpha [rad]."""
        return np.arctan(np.sqrt(self.tan2_alpha))


def check_angles(theta_i, theta_r, phi):
    """Validate and broadcast ``theta_i, theta_r`` in [0, pi/2] and ``phi`` in [-2 pi, 2 pi] [rad].

    Parameters
    ----------
    theta_i, theta_r : array_like
        Incidence and observation angles [rad].
    phi : array_like
        Azimuth of observation relative to incidence [rad].

    Returns
    -------
    list of ndarray
        ``[theta_i, theta_r, phi]`` [rad], broadcast to one shape.
    """
    ti = as_angle(theta_i, "theta_i")
    tr = as_angle(theta_r, "theta_r")
    ph = as_azimuth(phi, "phi")
    return broadcast(theta_i=ti, theta_r=tr, phi=ph)


def polar_cos(theta):
    """``cos`` of polar angles in ``[0, pi/2]``; ``theta == pi/2`` (the float) is exactly grazing.

    ``np.cos(np.pi / 2)`` is 6.1e-17, not 0: without the snap a direction given as grazing would sit
    6e-17 rad above the horizon, where the pBRDF has singular peaks of 1e30 and more.

    Parameters
    ----------
    theta : array_like
        Polar angles [rad].

    Returns
    -------
    ndarray
        ``cos(theta)``, exactly 0 at ``theta == pi/2``, same shape.
    """
    theta = np.asarray(theta, float)
    c = np.cos(theta)
    if theta.ndim == 0:
        return np.float64(0.0) if theta == np.pi / 2 else c
    c[theta == np.pi / 2] = 0.0
    return c


def polar_cos_sin(theta):
    """``cos, sin`` of polar angles in ``[0, pi/2]``, with :func:`polar_cos`'s grazing snap.

    Parameters
    ----------
    theta : array_like
        Polar angles [rad].

    Returns
    -------
    cos, sin : ndarray
        Same shape as ``theta``.
    """
    return polar_cos(theta), np.sin(theta)


_QUARTER = (1.0, 0.0, -1.0, 0.0)


def azimuth_cos_sin(phi):
    """``cos, sin`` of azimuths; multiples of ``pi/2`` given as floats (``np.pi``) are exact.

    So ``phi = np.pi`` is exactly the specular plane on every path (``np.sin(np.pi)`` is 1.2e-16).

    Parameters
    ----------
    phi : array_like
        Azimuths [rad].

    Returns
    -------
    cos, sin : ndarray
        Same shape as ``phi``; exact at multiples of ``pi/2``.
    """
    phi = np.asarray(phi, float)
    q = np.round(phi / (np.pi / 2))
    exact = q * (np.pi / 2) == phi
    k = np.where(exact, q, 0).astype(np.intp) % 4
    table = np.array(_QUARTER)
    cp = np.where(exact, table[k], np.cos(phi))
    sp = np.where(exact, table[(k - 1) % 4], np.sin(phi))
    return cp, sp


def facet_geometry(
    theta_i, theta_r, phi, *, rotations: bool = True, checked: bool = False
) -> FacetGeometry:
    """Facet angles and polarization-frame rotations for any (theta_i, theta_r, phi).

    Parameters
    ----------
    theta_i, theta_r : array_like
        Incidence and observation angles [rad] in ``[0, pi/2]``; ``pi/2`` is exactly grazing.
    phi : array_like
        Azimuth of observation relative to incidence [rad]; ``pi`` is the specular plane.
    rotations : bool
        Compute the rotation angles (not needed for unpolarized, in-plane work).
    checked : bool
        Skip validation (inputs already validated and broadcast).

    Returns
    -------
    FacetGeometry
        Where both directions are grazing and opposite (``theta_i = theta_r = pi/2``, ``phi = pi``)
        no facet normal exists: ``tan2_alpha = inf`` there (no facet reflects).
    """
    if not checked:
        theta_i, theta_r, phi = check_angles(theta_i, theta_r, phi)
    ci, si = polar_cos_sin(theta_i)
    cr, sr = polar_cos_sin(theta_r)
    cp, sp = azimuth_cos_sin(phi)
    # h ~ s_i + s_r = (si + sr cp, sr sp, ci + cr)
    hx = si + sr * cp
    hy = sr * sp
    hz = ci + cr
    hxy2 = hx * hx + hy * hy
    norm2 = hxy2 + hz * hz  # = (2 cos beta)^2
    dx, dz = si - sr * cp, ci - cr  # s_i - s_r = (dx, -hy, dz)
    sin2_beta = np.minimum((dx * dx + hy * hy + dz * dz) / 4, 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        tan2_alpha = np.where(hz > 0, hxy2 / np.where(hz > 0, hz * hz, 1.0), np.inf)
    cos_beta = np.sqrt(norm2) / 2
    cos_beta = np.minimum(cos_beta, 1.0)
    cos_alpha = np.where(norm2 > 0, hz / np.sqrt(np.where(norm2 > 0, norm2, 1.0)), 0.0)
    if not rotations:
        z = np.zeros_like(cos_beta)
        return FacetGeometry(ci, cr, tan2_alpha, cos_alpha, cos_beta, z + 1, z, z + 1, z, sin2_beta)
    # facet s axis: (s_i x s_r)/|.|
    mx = -ci * sr * sp
    my = ci * sr * cp - si * cr
    mz = si * sr * sp
    mn = np.sqrt(mx * mx + my * my + mz * mz)
    degenerate = mn < 1e-14
    safe = np.where(degenerate, 1.0, mn)
    mx = np.where(degenerate, 0.0, mx / safe)
    my = np.where(degenerate, -1.0, my / safe)
    mz = np.where(degenerate, 0.0, mz / safe)
    # macro bases: s_i^M = (0, -1, 0), p_i^M = (-ci, 0, si);
    # s_r^M = (-sp, cp, 0), p_r^M = (-cr cp, -cr sp, sr)
    cos_gi = -my
    sin_gi = -ci * mx + si * mz
    cos_gr = -sp * mx + cp * my
    sin_gr = -cr * cp * mx - cr * sp * my + sr * mz
    return FacetGeometry(
        ci, cr, tan2_alpha, cos_alpha, cos_beta, cos_gi, sin_gi, cos_gr, sin_gr, sin2_beta
    )


def in_plane_geometry(theta_i, theta_r) -> FacetGeometry:
    """:class:`FacetGeometry` in the specular plane (``phi = pi``) from closed forms (Eq. 112).

    ``beta = (theta_i + theta_r)/2``, ``alpha = (theta_i - theta_r)/2``; the rotations vanish.
    Equal to :func:`facet_geometry` at ``phi = pi`` to rounding (tested). Inputs already validated.

    Parameters
    ----------
    theta_i, theta_r : ndarray
        Incidence and observation angles [rad] in ``[0, pi/2]``, validated and broadcast.

    Returns
    -------
    FacetGeometry
        Facet angles of the specular plane, rotations zero.
    """
    beta = (theta_i + theta_r) / 2
    half = (theta_i - theta_r) / 2
    ci, cr = polar_cos(theta_i), polar_cos(theta_r)
    cb, sb = polar_cos_sin(beta)
    t2 = np.where(ci + cr > 0, np.tan(half) ** 2, np.inf)
    one, zero = np.ones_like(cb), np.zeros_like(cb)
    return FacetGeometry(ci, cr, t2, np.cos(half), cb, one, zero, one, zero, sb * sb, True)
