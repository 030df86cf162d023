r"""The facet's reflection and its DOLP: the Jones elements of Eq. 169 and the closed forms.

* :func:`facet_jones` -- the Jones elements of a facet seen in the macroscopic bases (Eq. 169),
  built on the reduced Fresnel kernel :func:`scatterlab.fresnel.reduced_coefficients`;
* :func:`facet_dolp` -- the DOLP of unpolarized light reflected by the facet at any
  (theta_i, theta_r, phi): the pBRDF's DOLP without the diffuse term;
* :func:`dolp_smooth_facet` -- :math:`(R_s - R_p)/(R_s + R_p)` at the facet angle
  :math:`\beta` (Eq. 114): the DOLP of light scattered by optically smooth facets,
  Thilak et al.'s forward model (Eq. 115 with the errata's A, B and facet angle);
* :func:`dolp_thilak` -- the same in the specular plane as a function of
  (theta_i, theta_r), :math:`\beta = (\theta_i + \theta_r)/2` (Eq. 112).

All are thin layers over :func:`scatterlab.fresnel.smooth_dolp` and
:func:`scatterlab.polarization.mueller.mueller_from_jones_elements`. The full pBRDF DOLP
(Eq. 203 and out of plane) is :meth:`scatterlab.pbrdf.Model.dolp`.
"""

from __future__ import annotations

import numpy as np

from scatterlab._checks import as_angle, as_index, broadcast
from scatterlab.fresnel import reduced_coefficients, smooth_dolp
from scatterlab.pbrdf.geometry import FacetGeometry, check_angles, facet_geometry, polar_cos_sin
from scatterlab.polarization.mueller import mueller_from_jones_elements
from scatterlab.polarization.stokes import dolp as stokes_dolp

__all__ = ["facet_jones", "facet_mueller", "facet_dolp", "dolp_smooth_facet", "dolp_thilak"]


def facet_jones(eta, geo: FacetGeometry, *, in_plane: bool = False):
    """Jones elements ``(T_ss, T_ps, T_sp, T_pp)`` of Eq. 169 in reduced form, and the scale.

    Parameters
    ----------
    eta : complex ndarray (validated) or ``"pec"``
    geo : FacetGeometry
    in_plane : bool
        The rotations vanish (specular plane): ``T_ps = T_sp = None`` (a diagonal Jones matrix).

    Returns
    -------
    a, b, c, d : complex ndarrays (``b, c`` None in plane), the reduced elements; the true ones
        are ``(1 - eta^2)`` times these.
    scale : ndarray, ``|1 - eta^2|^2`` times the normalization of
        :func:`~scatterlab.fresnel.reduced_coefficients` (elements bounded by 1); 0 at ``eta = 1``,
        where the reduced elements may be inf at exact grazing: the caller zeroes F there.
    """
    red = reduced_coefficients(eta, geo.cos_beta, geo.sin2_beta, normalize=True, checked=True)
    rs, rp, scale = red.rs, red.rp, red.scale
    if in_plane:
        return rs, None, None, rp, scale
    ci, si, cr, sr = geo.cos_gi, geo.sin_gi, geo.cos_gr, geo.sin_gr
    return (
        (cr * ci) * rs + (sr * si) * rp,
        (cr * si) * rs - (sr * ci) * rp,
        (sr * ci) * rs - (cr * si) * rp,
        (sr * si) * rs + (cr * ci) * rp,
        scale,
    )


def facet_mueller(
    eta,
    geo: FacetGeometry,
    *,
    shape=(4, 4),
    weight=None,
    depolarized=None,
    out=None,
    facet_frame: bool = False,
):
    r"""``weight`` times the Mueller matrix (Eq. 133) of the facet's Jones matrix (Eq. 169).

    Eq. 169 is a product of two rotations and ``diag(r_s, r_p)``, and so is its Mueller matrix
    (Eq. 133 is multiplicative): the smooth facet's matrix

    .. math::

       M_\beta = \begin{bmatrix} A & B & 0 & 0\\ B & A & 0 & 0\\ 0 & 0 & C & S\\ 0 & 0 & -S & C
       \end{bmatrix},\quad A, B = \tfrac12(|r_s|^2 \pm |r_p|^2),\quad C + jS = r_s r_p^*,

    between the rotations' matrices, which turn :math:`(S_1, S_2)` by :math:`2\gamma_r` (rows)
    and :math:`-2\gamma_i` (columns). Four real products of the Fresnel coefficients instead of the
    four complex elements of :func:`facet_jones` and their six products in
    :func:`~scatterlab.polarization.mueller.mueller_from_jones_elements`, with which it agrees to
    rounding (tested); ``m03``, ``m30`` and, in the specular plane, the elements with a
    :math:`\sin 2\gamma` are exactly 0.

    Parameters
    ----------
    eta : complex ndarray (validated; 0-d for one index everywhere) or ``"pec"``
    geo : FacetGeometry
    shape : (int, int)
        The leading block of rows and columns, e.g. ``(3, 1)`` for unpolarized illumination.
    weight : ndarray, optional
        A factor of the whole matrix (the pBRDF's Gamma [1/sr]).
    depolarized : ndarray, optional
        Adds ``depolarized * m00`` to the (0, 0) element (the pBRDF's diffuse factor [1/sr]).
    out : ndarray, optional
        The result's storage, shape ``(..., rows, cols)``.
    facet_frame : bool
        Leave the reflected Stokes vectors in the facet's frame (no :math:`R(2\gamma_r)`): the same
        intensity and DOLP, ``S2 = 0`` for unpolarized illumination.

    Returns
    -------
    ndarray, shape ``(..., rows, cols)``: the true matrix (the reduced coefficients' scale
    applied), 0 where ``eta = 1`` (no interface).
    """
    red = reduced_coefficients(eta, geo.cos_beta, geo.sin2_beta, normalize=True, checked=True)
    rs, rp, scale = red.rs, red.rp, red.scale
    rows, cols = shape
    w = scale if weight is None else weight * scale
    qs = rs.real * rs.real + rs.imag * rs.imag
    qp = rp.real * rp.real + rp.imag * rp.imag
    m00 = 0.5 * (qs + qp)
    A = m00 * w
    if out is None:
        out = np.empty(np.broadcast_shapes(np.shape(A), np.shape(depolarized)) + (rows, cols))
    B = 0.5 * (qs - qp) * w if rows > 1 or cols > 1 else None
    if rows > 2 or cols > 2:
        rsp = rs * np.conj(rp)
        C, S = rsp.real * w, rsp.imag * w
    # cos and sin of 2 gamma_i (columns 1-2) and 2 gamma_r (rows 1-2); 1 and 0 in the plane
    ci, si = (1.0, 0.0) if geo.in_plane or cols == 1 else _double(geo.cos_gi, geo.sin_gi)
    no_rows = geo.in_plane or rows == 1 or facet_frame
    cr, sr = (1.0, 0.0) if no_rows else _double(geo.cos_gr, geo.sin_gr)
    if rows > 1 and cols > 1:
        cc, ss, cs, sc = cr * ci, sr * si, cr * si, sr * ci
    elements = {
        (0, 0): lambda: A,
        (0, 1): lambda: B * ci,
        (0, 2): lambda: B * si,
        (0, 3): lambda: 0.0,
        (1, 0): lambda: B * cr,
        (1, 1): lambda: A * cc + C * ss,
        (1, 2): lambda: A * cs - C * sc,
        (1, 3): lambda: -S * sr,
        (2, 0): lambda: B * sr,
        (2, 1): lambda: A * sc - C * cs,
        (2, 2): lambda: A * ss + C * cc,
        (2, 3): lambda: S * cr,
        (3, 0): lambda: 0.0,
        (3, 1): lambda: S * si,
        (3, 2): lambda: -S * ci,
        (3, 3): lambda: C,
    }
    for i in range(rows):
        for j in range(cols):
            out[..., i, j] = elements[i, j]()
    if depolarized is not None:
        out[..., 0, 0] += m00 * (depolarized * scale)
    none = scale == 0  # eta = 1: no interface, no light (the reduced factors may be NaN)
    if np.any(none):
        out[np.broadcast_to(none, out.shape[:-2])] = 0.0
    return out


def _double(cos, sin):
    """``cos 2 gamma, sin 2 gamma`` from ``cos gamma, sin gamma``."""
    return (cos - sin) * (cos + sin), 2 * sin * cos


def facet_dolp(eta, theta_i, theta_r, phi=np.pi) -> np.ndarray:
    """DOLP of unpolarized light reflected by the facet joining ``theta_i`` to ``(theta_r, phi)``.

    In the specular plane this is :func:`dolp_smooth_facet` at ``beta = (theta_i + theta_r)/2``;
    elsewhere :math:`\\sqrt{M_{10}^2 + M_{20}^2}/M_{00}` of the facet's Mueller matrix (Eqs. 169,
    133): the smooth-facet DOLP seen in the rotated macroscopic bases. It is the continuous
    extension at ``eta = 1`` (a function of eta, used by the inversion), and the pBRDF's DOLP
    without a diffuse term wherever the specular term is non-zero.

    Parameters
    ----------
    eta : complex array_like or ``"pec"``
    theta_i, theta_r : array_like [rad] in ``[0, pi/2]``
    phi : array_like [rad], default ``pi``.

    Returns
    -------
    ndarray in ``[0, 1]``, broadcast shape.
    """
    ti, tr, ph = check_angles(theta_i, theta_r, phi)
    if not isinstance(eta, str):
        eta = as_index(eta)
        eta, ti, tr, ph = broadcast(eta=eta, theta_i=ti, theta_r=tr, phi=ph)
    geo = facet_geometry(ti, tr, ph, checked=True)
    a, b, c, d, _ = facet_jones(eta, geo)
    m = mueller_from_jones_elements(a, b, c, d, shape=(3, 1))[..., 0]
    # beta = 90 deg: R_s = R_p = 1 (the limit at eta = 1 too)
    return np.where(geo.cos_beta == 0, 0.0, np.clip(stokes_dolp(m), 0.0, 1.0))


def dolp_smooth_facet(eta, beta) -> np.ndarray:
    """DOLP ``(Rs - Rp)/(Rs + Rp)`` of unpolarized light reflected at facet angle ``beta`` [rad].

    Eqs. 57, 114.

    :func:`scatterlab.fresnel.smooth_dolp` with validated arguments: continuous at ``eta -> 1``.

    Parameters
    ----------
    eta : complex array_like or ``"pec"``
    beta : array_like [rad] in ``[0, pi/2]``

    Returns
    -------
    ndarray in ``[0, 1]``, broadcast shape.
    """
    beta = as_angle(beta, "beta")
    if not isinstance(eta, str):
        eta = as_index(eta)
        eta, beta = broadcast(eta=eta, beta=beta)
    cb, sb = polar_cos_sin(beta)
    return np.clip(smooth_dolp(eta, cb, sb * sb, checked=True)[0], 0.0, 1.0)


def dolp_thilak(eta, theta_i, theta_r) -> np.ndarray:
    """Thilak et al.'s DOLP (Eq. 115) in the specular plane.

    The smooth-facet DOLP at ``beta = (theta_i + theta_r)/2``.

    Parameters
    ----------
    eta : complex array_like or ``"pec"``
    theta_i, theta_r : array_like [rad] in ``[0, pi/2]``

    Returns
    -------
    ndarray in ``[0, 1]``, broadcast shape.
    """
    ti = as_angle(theta_i, "theta_i")
    tr = as_angle(theta_r, "theta_r")
    return dolp_smooth_facet(eta, (ti + tr) / 2)
