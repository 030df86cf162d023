r"""Division-of-focal-plane (DoFP) polarization cameras: raw mosaic frames <-> channel images.

A DoFP sensor carries a micro-polarizer over every pixel, repeating in 2x2 superpixels of four
orientations. The pattern is given as a 2x2 array of polarizer angles in degrees, ``pattern[row %
2][col % 2]``; the default is that of the Sony IMX250MZR/IMX253MZR sensors (FLIR Blackfly S, LUCID
Phoenix/Triton polarization models)::

    90  45
    135  0

Demosaicing here is by superpixel: each 2x2 block gives one pixel of each channel, so channels are
half the raw size and every channel pixel is one detector reading. Interpolating demosaicers
(bilinear, Newton) give full-size channels but correlate the noise of neighbouring pixels and mix
photons of different pixels, which breaks the Poisson likelihood of the deconvolution; the channels'
half-pixel offsets are left to the registration and the PSF. Angles are measured from the s axis of
the observation (the camera's horizontal when the plane of incidence is horizontal), in the same
sense as :mod:`scatterlab.imaging.polarimeter`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["SONY_POLARSENS", "check_pattern", "demosaic", "mosaic"]

SONY_POLARSENS = ((90.0, 45.0), (135.0, 0.0))


def check_pattern(pattern, where: str = "pattern") -> np.ndarray:
    """Validate a 2x2 DoFP pattern of polarizer angles [deg]: finite, four distinct orientations mod
    180.

    Parameters
    ----------
    pattern : array_like (2, 2) [deg]
    where : str
        Name used in error messages (argument or file key).

    Returns
    -------
    ndarray (2, 2) of float, in [0, 180).
    """
    try:
        p = np.asarray(pattern, float)
    except (TypeError, ValueError):
        raise ValueError(
            f"{where} must be a 2x2 array of polarizer angles in degrees, got {pattern!r}"
        ) from None
    if p.shape != (2, 2) or not np.all(np.isfinite(p)):
        raise ValueError(
            f"{where} must be a finite 2x2 array of polarizer angles in degrees, got {p.tolist()}"
        )
    p = np.mod(p, 180.0)
    if np.unique(np.round(p, 9)).size != 4:
        raise ValueError(
            f"{where} must hold four different polarizer orientations (mod 180 deg), got "
            f"{p.tolist()}"
        )
    return p


def demosaic(raw, pattern=SONY_POLARSENS, *, where: str = "raw"):
    """Superpixel demosaic of DoFP raw frames into channel images.

    Parameters
    ----------
    raw : array_like (..., 2H, 2W)
        Raw frames (counts); both sizes must be even.
    pattern : array_like (2, 2) [deg]
        Polarizer angle of each position in the 2x2 superpixel (default: Sony Polarsens).
    where : str
        Name used in error messages (e.g. the file).

    Returns
    -------
    channels : ndarray (..., 4, H, W)
        One image per polarizer orientation, in ascending angle order.
    angles : ndarray (4,) [rad]
        The channels' polarizer angles.
    """
    p = check_pattern(pattern)
    r = np.asarray(raw, float)
    if r.ndim < 2 or r.shape[-1] % 2 or r.shape[-2] % 2 or min(r.shape[-2:]) < 2:
        raise ValueError(
            f"{where}: DoFP raw frames need even sizes (2x2 superpixels), got shape {r.shape}"
        )
    if not np.all(np.isfinite(r)):
        raise ValueError(f"{where}: raw frames must be finite (no NaN or inf)")
    order = np.argsort(p.ravel())
    blocks = [r[..., i::2, j::2] for i in range(2) for j in range(2)]
    return np.stack([blocks[k] for k in order], axis=-3), np.radians(p.ravel()[order])


def mosaic(channels, angles, pattern=SONY_POLARSENS) -> np.ndarray:
    """Inverse of :func:`demosaic`: channel images ``(..., 4, H, W)`` at ``angles`` [rad] -> raw
    ``(..., 2H, 2W)``.

    Parameters
    ----------
    channels : array_like (..., 4, H, W)
    angles : array_like (4,) [rad]
        Must be the four orientations of ``pattern`` (in any order).
    pattern : array_like (2, 2) [deg]

    Returns
    -------
    ndarray (..., 2H, 2W)
    """
    p = check_pattern(pattern)
    c = np.asarray(channels, float)
    a = np.mod(np.degrees(np.asarray(angles, float).ravel()), 180.0)
    if c.ndim < 3 or c.shape[-3] != 4 or a.size != 4:
        raise ValueError(
            f"channels must have shape (..., 4, H, W) with 4 angles, got {c.shape} and {a.size}"
        )
    out = np.empty(c.shape[:-3] + (2 * c.shape[-2], 2 * c.shape[-1]))
    for i in range(2):
        for j in range(2):
            k = np.flatnonzero(np.isclose(a, p[i, j], atol=1e-6))
            if k.size != 1:
                raise ValueError(
                    f"the channels' angles {np.round(a, 6).tolist()} deg do not match the pattern "
                    f"{p.tolist()}"
                )
            out[..., i::2, j::2] = c[..., k[0], :, :]
    return out
