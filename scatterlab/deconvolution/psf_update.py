r"""PSF models and updates for the blind deconvolution (Schulz; Eqs. 146-150; Sec. 5.3.2).

* :func:`initial_psf` -- the text's start: the PSF of one random Kolmogorov phase screen, piston and tilt removed;
* :func:`gerchberg_saxton` -- projection of a (non-parametric) PSF estimate onto the PSFs an aperture can form,
  :math:`|\mathcal F\{A e^{j\phi}\}|^2`, by alternating the image-plane modulus and the pupil amplitude;
* :func:`resample_psf` -- a centred PSF cropped or zero-padded onto another grid, unit sum;
* :func:`psf_distance` -- how far a PSF estimate is from the true PSF: L1 after the best integer shift.

PSFs are ``(H, W)`` arrays, centred at ``(H // 2, W // 2)``, non-negative with unit sum.
"""

from __future__ import annotations

import numpy as np

from scatterlab._checks import as_count, as_image_shape, as_rng

__all__ = ["initial_psf", "gerchberg_saxton", "psf_distance", "resample_psf"]


def initial_psf(pupil, shape, d_over_r0: float = 10.0, rng=None) -> np.ndarray:
    """The initial PSF of Sec. 5.3.2: the PSF of one random Kolmogorov phase screen (D/r0 = 10 by default)
    over ``pupil`` (n, n), piston and tilt removed, centred on the object grid ``shape`` (Hp, Wp), unit sum.
    A start as wide as the turbulence lets the multiplicative EM PSF update grow where the diffraction-limited
    PSF is nearly zero.

    Parameters
    ----------
    pupil : array_like, shape (n, n)
        Pupil amplitude on a square grid (> 0 inside the aperture; at least one sample).
    shape : tuple of int
        Object grid shape ``(Hp, Wp)`` [pixels].
    d_over_r0 : float
        Aperture diameter over Fried parameter, ``D / r0`` (> 0).
    rng : None, int or numpy.random.Generator, optional
        Seed or generator for the phase screen.

    Returns
    -------
    ndarray, shape (Hp, Wp)
        Centred PSF with unit sum.
    """
    from scatterlab.imaging import phase_screen, psf, remove_piston_tilt

    A = np.asarray(pupil, float)
    if A.ndim != 2 or A.shape[0] != A.shape[1]:
        raise ValueError(f"pupil must be a square 2-D array, got shape {A.shape}")
    if not d_over_r0 > 0:
        raise ValueError(f"d_over_r0 must be > 0, got {d_over_r0}")
    if not np.any(A > 0):
        raise ValueError(
            "pupil must have at least one sample > 0 (the aperture); it is empty (all <= 0 or NaN)"
        )
    n = A.shape[0]
    diameter = 2 * np.sqrt((A > 0).sum() / np.pi)  # pupil diameter [grid samples]
    phase = remove_piston_tilt(phase_screen(n, 1.0, diameter / d_over_r0, as_rng(rng)), A > 0)
    return resample_psf(psf(A, phase, pad=2), shape)


def resample_psf(h, shape) -> np.ndarray:
    """Centre-crop or zero-pad a centred PSF to ``shape``; unit sum.

    Parameters
    ----------
    h : array_like, shape (Hs, Ws)
        Centred PSF: finite and >= 0 (light is never negative; clip round-off with
        ``numpy.clip(h, 0, None)``).
    shape : tuple of int
        Target shape ``(H, W)`` [pixels], two integers >= 1.

    Returns
    -------
    ndarray, shape (H, W)
        The cropped or padded PSF, normalised to unit sum.

    Raises
    ------
    ValueError
        ``h`` not a finite non-negative 2-D array, ``shape`` not two integers >= 1, or no light left after
        the crop.
    """
    try:
        h = np.asarray(h, float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"h must be a numeric 2-D PSF, got {h!r}") from exc
    if h.ndim != 2:
        raise ValueError(f"h must be a 2-D PSF (Hs, Ws), got shape {h.shape}")
    if not np.all(np.isfinite(h)) or np.any(h < 0):
        raise ValueError(
            "h must be finite and >= 0 (a PSF: light is never negative; clip round-off with "
            "numpy.clip(h, 0, None))"
        )
    H, W = as_image_shape(shape, "shape")
    out = np.zeros((H, W))
    Hs, Ws = h.shape
    ch, cw = min(H, Hs), min(W, Ws)
    out[(H - ch) // 2 : (H - ch) // 2 + ch, (W - cw) // 2 : (W - cw) // 2 + cw] = h[
        (Hs - ch) // 2 : (Hs - ch) // 2 + ch, (Ws - cw) // 2 : (Ws - cw) // 2 + cw
    ]
    total = out.sum()
    if not total > 0:
        raise ValueError(
            f"h has no light inside the central {H} x {W} pixels it is cropped to (shape {h.shape})"
        )
    return out / total


def psf_distance(h, truth, reach: int = 8) -> tuple:
    """The L1 distance of a PSF estimate from the true PSF, at the integer shift that brings them nearest.

    A blind estimate is found up to a translation (the object moves the other way), so the shift is
    minimised over. Both PSFs are put on the truth's grid (:func:`resample_psf`: centred, unit sum), so
    the distance runs from 0 (the same PSF) to 2 (disjoint supports).

    Parameters
    ----------
    h : array_like, shape (Hh, Wh)
        Centred PSF estimate (non-negative, positive sum).
    truth : array_like, shape (H, W)
        Centred true PSF (non-negative, positive sum).
    reach : int
        Largest shift tried along each axis [pixels] (>= 0).

    Returns
    -------
    distance : float
        ``sum |roll(h, shift) - truth|`` at the best shift, in [0, 2].
    shift : tuple of int
        That shift ``(dy, dx)`` [pixels] applied to ``h``.
    """
    truth = np.asarray(truth, float)
    h = np.asarray(h, float)
    for name, a in (("h", h), ("truth", truth)):
        if a.ndim != 2 or not np.all(np.isfinite(a)) or np.any(a < 0) or not a.sum() > 0:
            raise ValueError(f"{name} must be a finite non-negative 2-D PSF with a positive sum")
    as_count(reach, "reach", 0)
    truth = truth / truth.sum()
    try:
        h = resample_psf(h, truth.shape)
    except ValueError:  # all of the estimate's light lies outside the truth's grid: disjoint
        return 2.0, (0, 0)
    return min(
        (float(np.abs(np.roll(h, (a, b), (0, 1)) - truth).sum()), (a, b))
        for a in range(-reach, reach + 1)
        for b in range(-reach, reach + 1)
    )


def gerchberg_saxton(h_target, pupil, phase, shape, steps):
    """Project PSFs onto |F{A exp(j phi)}|^2 (Eqs. 146-150): impose sqrt(h_target) in the image plane and the
    aperture amplitude in the pupil, ``steps`` times.

    Parameters
    ----------
    h_target : array (K, Hp, Wp) -- PSF estimates (centred); pupil : array (n, n) -- aperture amplitude A;
    phase : array (K, n, n) [rad] -- starting pupil phases; shape : (Hp, Wp) of the returned PSFs;
    steps : int -- Gerchberg-Saxton iterations, >= 0 (0 returns the PSFs of the starting phases; the image
    plane is the 2n x 2n Nyquist grid of the pupil).

    Returns
    -------
    psfs (K, Hp, Wp) unit sum, phases (K, n, n) [rad]
    """
    as_count(steps, "steps", 0)
    A = np.asarray(pupil, float)
    n = A.shape[-1]
    m = 2 * n
    out_h, out_phase = [], []
    for k in range(h_target.shape[0]):
        target = np.sqrt(resample_psf(h_target[k], (m, m)))
        ph = phase[k]
        for _ in range(steps):
            F = np.fft.fftshift(np.fft.fft2(A * np.exp(1j * ph), s=(m, m)))
            F = target * np.exp(1j * np.angle(F)) * np.sqrt(np.sum(np.abs(F) ** 2))
            field = np.fft.ifft2(np.fft.ifftshift(F))[:n, :n]
            ph = np.where(A > 0, np.angle(field), 0.0)
        F = np.fft.fftshift(np.fft.fft2(A * np.exp(1j * ph), s=(m, m)))
        out_h.append(resample_psf(np.abs(F) ** 2, shape))
        out_phase.append(ph)
    return np.stack(out_h), np.stack(out_phase)


class PupilPhasePSF:
    r"""The PSF of a pupil phase on the object grid, and its gradient with respect to that phase.

    :math:`h(\phi) = m\,|\mathcal F\{A e^{j\phi}\}|^2 / \sum m\,|\mathcal F\{A e^{j\phi}\}|^2` (Eq. 186), the
    transform on the 2n x 2n Nyquist grid of the n x n pupil, centred on the object grid, ``m`` the support.
    :meth:`gradient` is the chain rule from :math:`\partial L/\partial h` to :math:`\partial L/\partial\phi`
    (Schulz's multi-frame gradient): with :math:`E = \mathcal F\{p\}`, :math:`p = A e^{j\phi}`,
    :math:`\partial L/\partial\phi(u) = -2\,\mathrm{Im}[p(u)\,\mathcal F\{g\,\bar E\}(u)]`, g the gradient
    with respect to :math:`|E|^2`.

    Parameters
    ----------
    pupil : ndarray, shape (n, n)
        Aperture amplitude A.
    shape : tuple of int
        Object grid ``(Hp, Wp)`` [pixels].
    support : ndarray of bool, shape (Hp, Wp)
        Where the PSF may be non-zero.
    """

    def __init__(self, pupil, shape, support):
        self.A = np.asarray(pupil, float)
        self.n = self.A.shape[-1]
        m = 2 * self.n
        self.m = m
        Hp, Wp = shape
        ch, cw = min(Hp, m), min(Wp, m)
        self.dst = (
            slice((Hp - ch) // 2, (Hp - ch) // 2 + ch),
            slice((Wp - cw) // 2, (Wp - cw) // 2 + cw),
        )
        self.src = (
            slice((m - ch) // 2, (m - ch) // 2 + ch),
            slice((m - cw) // 2, (m - cw) // 2 + cw),
        )
        self.shape = tuple(shape)
        self.support = np.asarray(support, bool)
        self.inside = self.A > 0

    def _field(self, phase):
        p = self.A * np.exp(1j * phase)
        return p, np.fft.fft2(p, s=(self.m, self.m))

    def _on_support(self, E):
        """|E|^2, centred on the object grid and cut to the support (not normalised)."""
        big = np.zeros(self.shape)
        big[self.dst] = np.fft.fftshift(E.real**2 + E.imag**2)[self.src]
        return big * self.support

    def psf(self, phase):
        """The PSF ``(Hp, Wp)`` (centred, unit sum over the support) of the pupil phase ``(n, n)`` [rad].

        Parameters
        ----------
        phase : ndarray, shape (n, n)

        Returns
        -------
        ndarray, shape (Hp, Wp)
        """
        _, E = self._field(phase)
        big = self._on_support(E)
        return big / big.sum()

    def gradient(self, phase, G):
        """:math:`\\partial L/\\partial\\phi` ``(n, n)`` [1/rad] from :math:`\\partial L/\\partial h` ``G``.

        Parameters
        ----------
        phase : ndarray, shape (n, n)
            Pupil phase [rad].
        G : ndarray, shape (Hp, Wp)
            Gradient of the objective with respect to the (centred, normalised) PSF.

        Returns
        -------
        ndarray, shape (n, n)
            Zero outside the aperture.
        """
        p, E = self._field(phase)
        big = self._on_support(E)
        S = big.sum()
        h = big / S
        g_h = np.where(self.support, (G - np.sum(G * h)) / S, 0.0)
        gc = np.zeros((self.m, self.m))
        gc[self.src] = g_h[self.dst]
        W = np.fft.fft2(np.fft.ifftshift(gc) * np.conj(E))[: self.n, : self.n]
        return np.where(self.inside, -2.0 * np.imag(p * W), 0.0)
