r"""Polarimetric image datasets: channel images of one scene at several specular geometries.

:class:`PolarimetricDataset` is what ``scatterlab analyze`` and the characterization pipeline take
from measured (or simulated) data:

* ``counts`` (G, K, H, W) [e-]: channel images of G geometries and K polarizer channels, H, W >= 8,
  in dark-subtracted photo-electrons (divide ADU by the gain first). Small negative values from read
  noise are fine; strongly negative ones are refused: more pixels of a channel image below -5 sigma
  than Gaussian noise leaves there (its expectation, under one pixel for sensors below 3.5 Mpx,
  rounded up) plus 4 (hot pixels of the dark frame), where sigma = sqrt(2) x ``read_noise_e`` (the
  read noise of the exposure and of a dark frame subtracted from it) or, without ``read_noise_e``,
  the robust scatter of neighbouring pixels, which shot noise raises (a looser check: give the read
  noise). Pixels in ``bad_pixels`` are not counted. Nor may a geometry's negative counts add up to
  more than 10 % of its light;
* ``polarizer_angles`` (K,) [rad]: analyser angle of each channel from the s axis;
* ``theta`` (G,) [rad]: specular geometry of each acquisition, theta_i = theta_r and phi = pi
  (observation in the specular plane);
* ``wavelength`` [m];
* ``optics`` (:class:`Optics`): sampling of the PSF, pixels per lambda/D, or the aperture diameter,
  pixel pitch and focal length;
* ``read_noise`` [e- rms] or None when unknown;
* ``bad_pixels`` (G, H, W) bool or None: pixels to leave out (dead, hot, defective). They do not
  enter the likelihood of the restoration, and the analysis leaves them unclassified;
* ``full_well`` [e-] or None: the dark-subtracted count at which a pixel saturates. Values at or above
  it are censored: they tell the restoration "at least this many" (a saturated area still holds its
  light, and its halo is taken off the pixels around), and a pixel with a saturated channel has no
  measured DOLP, so the analysis leaves it unclassified. Saturated pixels are better given this way
  than listed in ``bad_pixels``: dropped, their light is left to guesswork and its halo stays on the
  pixels around (``docs/characterization_accuracy.md``);
* ``truth`` (:class:`Truth`) or None: what a simulation knows (labels, indices, roughness, the
  object's S0 and DOLP, the PSFs); None for measurements;
* ``title``, ``description`` (str) and ``simulated`` (bool, True for simulated data, always said so
  in reports).

The PSF sampling ``Q`` (pixels per lambda/D; 2 is Nyquist) fixes the support of the optical transfer
function: the pupil's radius in the Fourier grid of an ``n``-pixel image is ``n / (2 Q)`` pixels
(:meth:`Optics.pupil_radius`), the ``psf_radius`` of
:func:`scatterlab.deconvolution.blind_deconvolve`.

Files (all hold the same keys; degrees and micrometres in files, radians and metres in memory):

* HDF5 (:func:`write_dataset_hdf5`, :func:`read_dataset_hdf5`) and NPZ (:func:`write_dataset_npz`,
  :func:`read_dataset_npz`);
* a multi-page TIFF with a sidecar TOML of the same name (:func:`write_dataset_tiff`,
  :func:`read_dataset_tiff`), the form most cameras give;
* any of them may hold DoFP raw frames ``raw`` (G, 2H, 2W) with ``dofp_pattern_deg`` instead of
  ``counts`` and ``polarizer_deg``: they are demosaiced on reading (:mod:`scatterlab.io.dofp`).

:func:`read_dataset` picks the reader from the file name. Keys: ``counts`` or ``raw``;
``polarizer_deg`` (K,); ``dofp_pattern_deg`` (2, 2); ``theta_deg`` (G,); ``wavelength_um``;
``pixels_per_lambda_over_d``, ``aperture_diameter_mm``, ``pixel_pitch_um``, ``focal_length_mm``
(optics; give the first or the other three); ``read_noise_e``; ``bad_pixels`` ((H, W) for the
sensor, or (G, H, W) per geometry, non-zero = bad; for DoFP data (2H, 2W) or (G, 2H, 2W) on the raw
frame, a superpixel being bad when any of its four pixels is); ``full_well_e`` (give the camera's
full well less the dark level, or a little below: pixels at or above it in a channel are
saturated); ``title``; ``description``;
``simulated``; ``truth_labels`` (H, W), ``truth_names`` (L,), ``truth_n``, ``truth_kappa``,
``truth_sigma`` (L,), ``truth_s0``, ``truth_dolp``, ``truth_psf`` (G, H, W).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from scatterlab.io.dofp import check_pattern, demosaic, mosaic
from scatterlab.io.table import LENGTH_UNITS, likely_wavelength_unit, wavelength_range_problem

__all__ = [
    "Optics",
    "Truth",
    "PolarimetricDataset",
    "to_flat",
    "from_flat",
    "read_dataset",
    "write_dataset",
    "with_pixel_mask",
    "DATASET_SUFFIXES",
    "FORMAT_NAME",
]

FORMAT_NAME = "scatterlab polarimetric dataset"
FORMAT_VERSION = 1
DATASET_SUFFIXES = (".h5", ".hdf5", ".npz", ".tif", ".tiff", ".toml")
# the largest share of a geometry's light its negative counts may carry (read noise, not signal)
NEGATIVE_SHARE = 0.1
# the smallest image (H, W) a dataset may have: the restoration's pupil grid is half the image, and a
# PSF needs at least 4 samples across it
MIN_IMAGE_SIZE = 8
# a dark-subtracted count more than this many noise sigmas below 0 is not read noise (Gaussian read
# noise puts one pixel in 3.5 million there) ...
NEGATIVE_SIGMAS = 5.0
# ... and a channel image may have this many such pixels beyond the Gaussian expectation (hot pixels
# of a subtracted dark frame, a cosmic ray in it); more are refused (_strongly_negative)
NEGATIVE_OUTLIERS = 4
# the smallest share of a geometry's pixels that bad_pixels may leave to measure
MIN_VALID_SHARE = 0.1
LEFT_OUT_NOTE = "pixels left out of the likelihood per geometry"
# pixels crowding a channel's highest count that mark it as clipped (saturated): a 3 x 3 plateau
PLATEAU_PIXELS = 9
DEAD_PIXEL_NOTE = "pixels read <= 0 in every channel at every geometry"
SATURATED_NOTE = "pixels with a channel at the full well"
PLATEAU_NOTE = "crowd the highest count"
_OPTICS_KEYS = {
    "pixels_per_lambda_over_d": 1.0,
    "aperture_diameter_mm": 1e-3,
    "pixel_pitch_um": 1e-6,
    "focal_length_mm": 1e-3,
}


@dataclass(frozen=True)
class Optics:
    """Imaging optics: give ``pixels_per_lambda_over_d`` or all of ``aperture_diameter``,
    ``pixel_pitch`` and ``focal_length`` [m] (then
    ``Q = wavelength * focal_length / (aperture_diameter * pixel_pitch)``)."""

    pixels_per_lambda_over_d: float | None = None
    aperture_diameter: float | None = None
    pixel_pitch: float | None = None
    focal_length: float | None = None

    def __post_init__(self):
        for name in (
            "pixels_per_lambda_over_d",
            "aperture_diameter",
            "pixel_pitch",
            "focal_length",
        ):
            v = getattr(self, name)
            if v is not None and not (np.isfinite(v) and v > 0):
                raise ValueError(f"optics {name} must be > 0, got {v}")
        physical = (self.aperture_diameter, self.pixel_pitch, self.focal_length)
        if self.pixels_per_lambda_over_d is None and any(v is None for v in physical):
            raise ValueError(
                "optics need pixels_per_lambda_over_d, or aperture_diameter, pixel_pitch and "
                "focal_length together"
            )

    def sampling(self, wavelength: float) -> float:
        """Pixels per lambda/D (2 is Nyquist sampling of the PSF).

        Parameters
        ----------
        wavelength : float [m]

        Returns
        -------
        float
        """
        if self.pixels_per_lambda_over_d is not None:
            return float(self.pixels_per_lambda_over_d)
        return float(wavelength * self.focal_length / (self.aperture_diameter * self.pixel_pitch))

    def pupil_radius(self, n: int, wavelength: float) -> float:
        """Radius of the pupil (half the OTF support) in the Fourier grid of an image.

        Parameters
        ----------
        n : int
            Image size [pixels].
        wavelength : float [m]

        Returns
        -------
        float
            ``n / (2 Q)`` [pixels], the ``psf_radius`` of the blind deconvolution.
        """
        return n / (2 * self.sampling(wavelength))


@dataclass
class Truth:
    """What a simulation knows, in object coordinates (the plate as seen face-on; the camera sees it
    foreshortened by cos theta).

    Attributes
    ----------
    labels : ndarray (H, W) int
        Material label of each pixel, indexing ``names``, ``n``, ``kappa``, ``sigma``.
    names : list of str
    n, kappa, sigma : ndarray (L,)
        Complex index ``n - 1j*kappa`` and rms facet slope per label.
    s0, dolp : ndarray (G, H, W) or None
        The object's S0 [1/sr] and DOLP at each geometry.
    psf : ndarray (G, H, W) or None
        The PSF each acquisition was blurred with (centred, unit sum).
    """

    labels: np.ndarray
    names: list
    n: np.ndarray
    kappa: np.ndarray
    sigma: np.ndarray
    s0: np.ndarray | None = None
    dolp: np.ndarray | None = None
    psf: np.ndarray | None = None


@dataclass
class PolarimetricDataset:
    """Channel images at several specular geometries (module docstring for the shapes and units)."""

    counts: np.ndarray
    polarizer_angles: np.ndarray
    theta: np.ndarray
    wavelength: float
    optics: Optics
    read_noise: float | None = None
    truth: Truth | None = None
    title: str = ""
    description: str = ""
    simulated: bool = False
    source: str = ""
    notes: list = field(default_factory=list)
    bad_pixels: np.ndarray | None = None
    full_well: float | None = None

    def __post_init__(self):
        flat = to_flat(self)
        checked = from_flat(flat, self.source or "dataset")
        self.counts, self.polarizer_angles, self.theta = (
            checked.counts,
            checked.polarizer_angles,
            checked.theta,
        )
        self.wavelength = checked.wavelength
        self.bad_pixels, self.full_well = checked.bad_pixels, checked.full_well
        self.notes = list(self.notes) + [n for n in checked.notes if n not in self.notes]

    def valid_pixels(self) -> np.ndarray | None:
        """The pixels to measure with at each geometry: those not in ``bad_pixels`` (saturated ones
        are measured, censored: :attr:`full_well`).

        Returns
        -------
        ndarray (G, H, W) of bool, or None
            None when every pixel is valid.
        """
        return _valid(self.bad_pixels)

    @property
    def shape(self) -> tuple:
        """``(G, K, H, W)``."""
        return self.counts.shape

    def stokes(self) -> np.ndarray:
        """Least-squares linear Stokes images of the (blurred, noisy) data (G, H, W, 3) [e-]."""
        from scatterlab.imaging import stokes_from_channels

        return np.stack([stokes_from_channels(c, self.polarizer_angles) for c in self.counts])


# ------------------------------------------------------------------------------------------- flat
# form
def to_flat(ds: PolarimetricDataset, *, dofp_pattern=None) -> dict:
    """The dataset as the flat dict of file keys (module docstring).

    Parameters
    ----------
    ds : PolarimetricDataset
    dofp_pattern : array_like (2, 2) [deg], optional
        Store DoFP raw frames (the four channels mosaicked) instead of channel images.

    Returns
    -------
    dict
        Arrays, numbers and strings keyed as in files (degrees, micrometres).
    """
    flat = {
        "format": FORMAT_NAME,
        "format_version": FORMAT_VERSION,
        "title": ds.title,
        "description": ds.description,
        "simulated": bool(ds.simulated),
        "theta_deg": np.degrees(np.asarray(ds.theta, float)),
        "wavelength_um": float(ds.wavelength) * 1e6,
    }
    if dofp_pattern is not None:
        flat["raw"] = mosaic(ds.counts, ds.polarizer_angles, dofp_pattern)
        flat["dofp_pattern_deg"] = check_pattern(dofp_pattern, "dofp_pattern")
    else:
        flat["counts"] = np.asarray(ds.counts, float)
        flat["polarizer_deg"] = np.degrees(np.asarray(ds.polarizer_angles, float))
    o = ds.optics
    for key, value in (
        ("pixels_per_lambda_over_d", o.pixels_per_lambda_over_d),
        ("aperture_diameter_mm", o.aperture_diameter),
        ("pixel_pitch_um", o.pixel_pitch),
        ("focal_length_mm", o.focal_length),
    ):
        if value is not None:
            flat[key] = float(value) / _OPTICS_KEYS[key]
    if ds.read_noise is not None:
        flat["read_noise_e"] = float(ds.read_noise)
    bad = ds.bad_pixels
    if bad is not None and np.any(bad):
        bad = np.asarray(bad, bool)
        if dofp_pattern is not None:  # on the raw frame: each superpixel's four pixels
            bad = np.repeat(np.repeat(bad, 2, axis=-2), 2, axis=-1)
        flat["bad_pixels"] = bad.astype(np.uint8)
    if ds.full_well is not None:
        flat["full_well_e"] = float(ds.full_well)
    t = ds.truth
    if t is not None:
        flat.update(
            truth_labels=np.asarray(t.labels),
            truth_names=np.asarray(list(t.names), dtype=str),
            truth_n=np.asarray(t.n, float),
            truth_kappa=np.asarray(t.kappa, float),
            truth_sigma=np.asarray(t.sigma, float),
        )
        for name in ("s0", "dolp", "psf"):
            if getattr(t, name) is not None:
                flat[f"truth_{name}"] = np.asarray(getattr(t, name), float)
    return flat


def _array(flat, key, where, ndim):
    if key not in flat:
        raise ValueError(f"{where}: missing {key!r}")
    try:
        a = np.asarray(flat[key], float)
    except (TypeError, ValueError):
        raise ValueError(f"{where}: {key!r} must be numeric") from None
    if a.ndim != ndim:
        raise ValueError(f"{where}: {key!r} must have {ndim} dimensions, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{where}: {key!r} contains NaN or inf")
    return a


def _scalar(flat, key, where, required=True):
    if key not in flat or flat[key] is None:
        if required:
            raise ValueError(f"{where}: missing {key!r}")
        return None
    try:
        v = float(np.asarray(flat[key]).reshape(()))
    except (TypeError, ValueError):
        raise ValueError(f"{where}: {key!r} must be one number, got {flat[key]!r}") from None
    if not (np.isfinite(v) and v > 0):
        raise ValueError(f"{where}: {key!r} must be > 0, got {v}")
    return v


def _checked_counts(counts, where, raw=False):
    """Not empty, images of at least :data:`MIN_IMAGE_SIZE` pixels a side, and light at every
    geometry (``raw``: demosaiced from DoFP raw frames, named so)."""
    if counts.size == 0:
        raise ValueError(
            f"{where}: 'counts' is empty: shape (G, K, H, W) = {counts.shape}, each must be >= 1"
        )
    H, W = counts.shape[-2:]
    if min(H, W) < MIN_IMAGE_SIZE:
        what = (
            f"'raw' frames {2 * H} x {2 * W} demosaic into {H} x {W} channel images"
            if raw
            else f"'counts' images are {H} x {W} pixels (H x W)"
        )
        raise ValueError(
            f"{where}: {what}; a dataset needs H, W >= {MIN_IMAGE_SIZE} (the restoration's pupil grid "
            "is half the image, and a PSF needs at least 4 samples across it)"
        )
    G = counts.shape[0]
    dark = [g for g in range(G) if not np.any(counts[g] > 0)]
    if dark:
        raise ValueError(
            f"{where}: 'counts' hold no photons (every count <= 0) at geometr"
            f"{'y' if len(dark) == 1 else 'ies'} {dark}: nothing to measure there"
        )
    # dark-subtracted photo-electrons go below 0 only by read noise: over a geometry the negative
    # part is a small fraction of the light (under 1 % for a 10 e- camera and a plate filling a
    # tenth of the field); a large one means too much was subtracted, or the data are not counts
    negative = np.sum(np.clip(-counts, 0, None), axis=(1, 2, 3))
    share = negative / np.sum(np.clip(counts, 0, None), axis=(1, 2, 3))
    if np.any(share > NEGATIVE_SHARE):
        g = int(np.argmax(share))
        raise ValueError(
            f"{where}: 'counts' at geometry {g} are negative by {share[g]:.0%} of their light "
            f"(at most {NEGATIVE_SHARE:.0%}: dark-subtracted photo-electrons go below 0 only by "
            "the read noise): was too much dark subtracted, or are these not photo-electrons "
            "(ADU divided by the gain)?"
        )
    return counts


def _channels(flat, where):
    """``(counts (G, K, H, W), angles [rad], notes)`` from channel images or DoFP raw frames."""
    if "raw" in flat and "counts" in flat:
        raise ValueError(f"{where}: holds both 'counts' and 'raw'; keep one")
    if "raw" in flat:
        raw = _array(flat, "raw", where, 3)
        if "dofp_pattern_deg" not in flat:
            raise ValueError(
                f"{where}: DoFP raw frames need 'dofp_pattern_deg' (2x2 polarizer angles)"
            )
        counts, angles = demosaic(
            raw,
            check_pattern(flat["dofp_pattern_deg"], f"{where}: 'dofp_pattern_deg'"),
            where=where,
        )
        return (
            _checked_counts(counts, where, raw=True),
            angles,
            [f"DoFP raw frames {raw.shape[1:]} demosaiced by superpixel into 4 channels"],
        )
    counts = _checked_counts(_array(flat, "counts", where, 4), where)
    deg = _array(flat, "polarizer_deg", where, 1)
    if deg.size != counts.shape[1]:
        raise ValueError(
            f"{where}: 'polarizer_deg' has {deg.size} angles for {counts.shape[1]} channels"
        )
    if np.unique(np.round(np.mod(deg, 180), 9)).size < 3:
        raise ValueError(
            f"{where}: 'polarizer_deg' {deg.tolist()} needs at least three different orientations "
            f"(mod 180 deg) to measure linear polarization"
        )
    orient = np.sort(np.mod(deg, 180.0))
    spread = 180.0 - np.max(np.diff(np.r_[orient, orient[0] + 180.0]))  # the arc the channels cover
    if spread < 10.0:
        raise ValueError(
            f"{where}: 'polarizer_deg' {deg.tolist()} span only {spread:.3g} deg of orientation: the "
            "channels cannot tell S1 from S2 (radians given as degrees?)"
        )
    return counts, np.radians(deg), []


def _noise_sigma(counts, read_noise):
    """``(sigma (G, K) [e-], how)``: the noise of a dark-subtracted count at 0 e-.

    With the read noise known: sqrt(2) x it, the read noise of the exposure and of a dark frame
    subtracted from it (the worst case, a single dark frame). Without: the robust scatter of
    horizontally neighbouring pixels of each image (median absolute deviation of their differences /
    sqrt(2)), which shot noise in bright parts can only raise; at least 1 e- (noise-free simulations).
    """
    if read_noise is not None:
        sigma = max(np.sqrt(2.0) * read_noise, 1.0)
        how = (
            f"sigma = sqrt(2) x read_noise_e {read_noise:g} e- = {sigma:.3g} e-: the read noise of "
            "the exposure and of the dark frame subtracted"
        )
        return np.full(counts.shape[:2], sigma), how
    d = np.diff(counts, axis=-1).reshape(counts.shape[:2] + (-1,))
    mad = np.median(np.abs(d - np.median(d, axis=-1, keepdims=True)), axis=-1)
    sigma = np.maximum(1.4826 * mad / np.sqrt(2.0), 1.0)
    return sigma, "read_noise_e not given: sigma from the scatter of neighbouring pixels"


def _strongly_negative(counts, read_noise, valid, where) -> None:
    """Refuse a channel image with more pixels below -:data:`NEGATIVE_SIGMAS` noise sigmas than read
    noise explains (its Gaussian expectation, rounded up, plus :data:`NEGATIVE_OUTLIERS`), pixels listed
    in ``bad_pixels`` (``valid`` False) aside.

    Slightly negative dark-subtracted counts are read noise; a patch far below it is a wrong dark or
    bias frame, or defective pixels, which the restoration would take for a dark, unpolarized object
    (the light-weighted share check of :func:`_checked_counts` misses a small patch in a bright image).
    """
    from math import ceil

    from scipy.stats import norm

    G, K, H, W = counts.shape
    sigma, how = _noise_sigma(counts, read_noise)
    limit = -NEGATIVE_SIGMAS * sigma  # (G, K)
    below = counts < limit[..., None, None]
    if valid is not None:
        below &= valid[:, None]
    found = below.sum(axis=(-2, -1))
    allowed = NEGATIVE_OUTLIERS + ceil(norm.sf(NEGATIVE_SIGMAS) * H * W)
    if not np.any(found > allowed):
        return
    g, k = (int(v) for v in np.unravel_index(np.argmax(found), found.shape))
    lowest = np.where(below[g, k], counts[g, k], np.inf)
    r, c = (int(v) for v in np.unravel_index(np.argmin(lowest), lowest.shape))
    images = int(np.sum(found > allowed))
    raise ValueError(
        f"{where}: 'counts' at geometry {g}, channel {k}: {int(found[g, k])} of {H * W} pixels are "
        f"below {limit[g, k]:.4g} e-, {NEGATIVE_SIGMAS:g} noise sigmas below 0 ({how}); the lowest "
        f"{counts[g, k, r, c]:.6g} e- at row {r}, column {c}"
        + (f"; {images} of {G * K} channel images have such pixels" if images > 1 else "")
        + f". Noise leaves at most {allowed} per image there: was too much dark or bias subtracted "
        "there, or are these pixels defective? List defective pixels in 'bad_pixels' (analyze "
        "--bad-pixels MASK); give read_noise_e if it is missing or wrong"
    )


def _truth(flat, counts_shape, where):
    if "truth_labels" not in flat:
        return None
    G, _, H, W = counts_shape
    labels = np.asarray(flat["truth_labels"])
    names = [str(x) for x in np.asarray(flat.get("truth_names", [])).ravel()]
    props = [_array(flat, f"truth_{k}", where, 1) for k in ("n", "kappa", "sigma")]
    L = len(names)
    if labels.shape != (H, W) or not np.issubdtype(labels.dtype, np.integer):
        raise ValueError(
            f"{where}: 'truth_labels' must be an integer map of shape {(H, W)}, got "
            f"{labels.dtype} {labels.shape}"
        )
    if any(p.size != L for p in props) or labels.min() < 0 or labels.max() >= L:
        raise ValueError(
            f"{where}: truth_names, truth_n, truth_kappa, truth_sigma need one entry per label "
            f"(labels 0..{labels.max()})"
        )
    maps = {}
    for k in ("s0", "dolp", "psf"):
        if f"truth_{k}" in flat:
            maps[k] = _array(flat, f"truth_{k}", where, 3)
            if maps[k].shape != (G, H, W):
                raise ValueError(
                    f"{where}: 'truth_{k}' must have shape {(G, H, W)}, got {maps[k].shape}"
                )
    return Truth(labels.astype(int), names, *props, **maps)


def _bad_pixels(flat, counts_shape, where, raw_frame=None):
    """``bad_pixels`` as a (G, H, W) bool array (None without the key): (H, W) or (G, H, W), or the
    same on the DoFP raw frame (2H, 2W), where a superpixel is bad when any of its pixels is
    (``raw_frame``: accept that shape; default: when the file holds raw frames)."""
    if "bad_pixels" not in flat:
        return None
    G, _, H, W = counts_shape
    raw_frame = "raw" in flat if raw_frame is None else raw_frame
    a = _array(flat, "bad_pixels", where, np.ndim(flat["bad_pixels"]))
    given = a.shape
    if raw_frame and a.shape[-2:] == (2 * H, 2 * W) and a.ndim in (2, 3):
        a = a.reshape(a.shape[:-2] + (H, 2, W, 2)).any(axis=(-3, -1))
    if a.shape not in ((H, W), (G, H, W)):
        raw = f" (or {(2 * H, 2 * W)} on the raw frame)" if raw_frame else ""
        raise ValueError(
            f"{where}: 'bad_pixels' must have shape (H, W) = {(H, W)} or (G, H, W) = "
            f"{(G, H, W)}{raw}, got {given}"
        )
    return np.broadcast_to(a != 0, (G, H, W))


def _valid(bad):
    """(G, H, W) bool of the pixels to measure with (``bad`` (G, H, W) negated), or None when all
    are."""
    if bad is None or not np.any(bad):
        return None
    return ~np.asarray(bad, bool)


def _dead_pixel_note(counts, valid, read_noise, where):
    """A note (and a warning) for pixels that read <= 0 in every channel at every geometry inside lit
    parts of the image: dead pixels that ``bad_pixels`` should list, or the analysis takes them for
    black spots. A real dark-subtracted pixel under light is never <= 0 in all of several reads."""
    from scipy import ndimage

    G, K = counts.shape[:2]
    if G * K < 6:  # too few reads to tell a dead pixel from a dim one
        return None
    dead = np.all(counts <= 0, axis=(0, 1))
    if valid is not None:
        dead &= np.any(valid, axis=0)  # already listed
    if not dead.any():
        return None
    # the light around them: each dead pixel takes its nearest live neighbour's mean count
    mean = np.mean(counts, axis=(0, 1))
    nearest = ndimage.distance_transform_edt(dead, return_distances=False, return_indices=True)
    level = ndimage.median_filter(mean[tuple(nearest)], size=7, mode="nearest")
    lit = level > 20.0 * max(read_noise or 0.0, 1.0)
    suspects = dead & lit
    if not suspects.any():
        return None
    r, c = (int(v[0]) for v in np.nonzero(suspects))
    note = (
        f"{int(suspects.sum())} {DEAD_PIXEL_NOTE} inside lit "
        f"parts of the image (the first at row {r}, column {c}): dead pixels? List them in "
        "'bad_pixels', or the analysis takes them for black, non-reflecting spots"
    )
    warnings.warn(f"{where}: {note}", UserWarning, stacklevel=3)
    return note


def _saturation_note(counts, read_noise, where):
    """A note (and a warning) when at least :data:`PLATEAU_PIXELS` pixels of a channel lie within six
    read-noise sigma of its brightest value, three times as many as in the band just below: clipped at
    the camera's full well (and spread by the dark frame subtracted). Light with shot noise never
    crowds its highest counts so closely."""
    G, K = counts.shape[:2]
    top = counts.reshape(G, K, -1).max(axis=-1)
    # clipped raw values, less a dark frame, spread by the dark's scatter (about the read noise)
    tol = 6.0 * max(read_noise or 0.0, 1.0)
    t = top[..., None, None]
    at_top = np.sum(counts >= t - tol, axis=(-2, -1))
    # a clip piles the light up in a spike; smooth light (noise-free synthetic data) fills the band
    # below its top as densely as the top itself
    below = np.sum((counts >= t - 2 * tol) & (counts < t - tol), axis=(-2, -1))
    flat = (
        (at_top >= PLATEAU_PIXELS)
        & (at_top >= 3 * below)
        & (top > 20.0 * max(read_noise or 0.0, 1.0))
    )
    if not flat.any():
        return None
    g, k = (int(v[0]) for v in np.nonzero(flat))
    note = (
        f"{int(at_top[g, k])} pixels of geometry {g}, channel {k} {PLATEAU_NOTE} "
        f"{top[g, k]:.6g} e- (within {tol:g} e-; {int(flat.sum())} of {G * K} images have such a "
        "plateau): saturated? "
        "Clipped channels make a pixel's DOLP wrong (a saturated area reads as unpolarized, like a "
        "metal). Give the full well (full_well_e, or analyze --full-well), which censors them; "
        "listing them in bad_pixels is worse (docs/characterization_accuracy.md)"
    )
    warnings.warn(f"{where}: {note}", UserWarning, stacklevel=3)
    return note


def _saturated_note(counts, full_well):
    """What the full well censors: the saturated pixels per geometry."""
    per = np.any(counts >= full_well, axis=1).sum(axis=(1, 2)).tolist()
    if not any(per):
        return None
    return (
        f"{SATURATED_NOTE} (full_well_e = {full_well:g} e-) per geometry: {per} of "
        f"{counts[0, 0].size}; censored in the restoration, unclassified"
    )


def from_flat(flat: dict, where: str) -> PolarimetricDataset:
    """Validate the flat dict of file keys and build the dataset.

    Parameters
    ----------
    flat : dict
        Keys of the module docstring (``counts`` or ``raw``, ``theta_deg``, ...).
    where : str
        The file, named in every error.

    Returns
    -------
    PolarimetricDataset

    Raises
    ------
    ValueError
        A missing key, a wrong shape, NaN, images smaller than 8 x 8, strongly negative counts (module
        docstring), angles or wavelength out of range (the wavelength in [0.01, 100] um,
        :func:`scatterlab.io.table.wavelength_range_problem`), too few polarizer orientations, bad
        optics or truth, naming ``where`` and the key.
    """
    _check_keys(flat, where)
    counts, angles, notes = _channels(flat, where)
    G = counts.shape[0]
    theta_deg = _array(flat, "theta_deg", where, 1)
    if theta_deg.size != G:
        raise ValueError(f"{where}: 'theta_deg' has {theta_deg.size} angles for {G} geometries")
    if np.any(theta_deg <= 0) or np.any(theta_deg >= 90):
        raise ValueError(f"{where}: 'theta_deg' must be in (0, 90) deg, got {theta_deg.tolist()}")
    if np.all(theta_deg < np.pi / 2):  # the largest a polar angle in radians can be
        raise ValueError(
            f"{where}: 'theta_deg' {theta_deg.tolist()} are all below {np.pi / 2:.4f} deg, where "
            "the DOLP is below 1e-3 and determines nothing: radians given as degrees?"
        )
    wavelength = _scalar(flat, "wavelength_um", where) * 1e-6
    problem = wavelength_range_problem(wavelength * 1e6, "um")
    if problem:
        likely = likely_wavelength_unit(wavelength * 1e6, "um")
        raise ValueError(
            f"{where}: 'wavelength_um' = {wavelength * 1e6:g}: {problem}"
            + (
                f"; 'wavelength_um' is in micrometres: write {wavelength * 1e6 * LENGTH_UNITS[likely] / 1e-6:g}"
                if likely
                else ""
            )
        )
    kw = {
        k.replace("_mm", "").replace("_um", ""): None if v is None else v * _OPTICS_KEYS[k]
        for k in _OPTICS_KEYS
        for v in [_scalar(flat, k, where, required=False)]
    }
    try:
        optics = Optics(**kw)
    except ValueError as exc:
        raise ValueError(
            f"{where}: {exc} (in a file: pixels_per_lambda_over_d, or aperture_diameter_mm, "
            "pixel_pitch_um and focal_length_mm)"
        ) from None
    read_noise = flat.get("read_noise_e")
    if read_noise is not None and not (np.isfinite(float(read_noise)) and float(read_noise) >= 0):
        raise ValueError(f"{where}: 'read_noise_e' must be >= 0, got {read_noise}")
    bad = _bad_pixels(flat, counts.shape, where)
    valid = _valid(bad)
    _strongly_negative(counts, None if read_noise is None else float(read_noise), valid, where)
    full_well = _scalar(flat, "full_well_e", where, required=False)
    if valid is not None:
        share = valid.mean(axis=(1, 2))
        if np.any(share < MIN_VALID_SHARE):
            g = int(np.argmin(share))
            raise ValueError(
                f"{where}: 'bad_pixels' leaves {share[g]:.1%} of the pixels at geometry {g} to "
                f"measure with (at least {MIN_VALID_SHARE:.0%}): is it non-zero only where a pixel "
                "is bad?"
            )
        per = (~valid).sum(axis=(1, 2)).tolist()
        notes.append(f"{LEFT_OUT_NOTE}: {per} of {valid[0].size} (listed in bad_pixels)")
    for note in (
        _dead_pixel_note(counts, valid, read_noise and float(read_noise), where),
        _saturation_note(counts, read_noise and float(read_noise), where)
        if full_well is None
        else _saturated_note(counts, full_well),
    ):
        if note:
            notes.append(note)
    ds = object.__new__(PolarimetricDataset)  # validated here: skip __post_init__'s round trip
    ds.__dict__.update(
        bad_pixels=bad,
        full_well=full_well,
        counts=counts,
        polarizer_angles=angles,
        theta=np.radians(theta_deg),
        wavelength=wavelength,
        optics=optics,
        read_noise=None if read_noise is None else float(read_noise),
        truth=_truth(flat, counts.shape, where),
        title=str(flat.get("title", "")),
        description=str(flat.get("description", "")),
        simulated=_bool(flat.get("simulated", False)),
        source=str(where),
        notes=notes,
    )
    return ds


_TRUTH_KEYS = {
    f"truth_{k}" for k in ("labels", "names", "n", "kappa", "sigma", "s0", "dolp", "psf")
}
_KEYS = {
    "format",
    "format_version",
    "title",
    "description",
    "simulated",
    "counts",
    "polarizer_deg",
    "raw",
    "dofp_pattern_deg",
    "theta_deg",
    "wavelength_um",
    "read_noise_e",
    "bad_pixels",
    "full_well_e",
    *_OPTICS_KEYS,
    *_TRUTH_KEYS,
}


def _check_keys(flat, where, extra=()) -> None:
    """Refuse keys a dataset does not have (a misspelt ``read_noise`` would otherwise be ignored) and
    files of another format or a newer version; ``extra`` are further keys the file may hold (a TIFF
    sidecar's ``tiff``, ``layout``, ``truth``)."""
    import difflib

    allowed = _KEYS | set(extra)
    unknown = sorted(set(flat) - allowed)
    if unknown:
        hints = [
            f"{k!r} (did you mean {close[0]!r}?)" if close else repr(k)
            for k in unknown
            for close in [difflib.get_close_matches(k, sorted(allowed), n=1, cutoff=0.6)]
        ]
        raise ValueError(
            f"{where}: unknown key{'s' if len(unknown) > 1 else ''} {', '.join(hints)}; a dataset "
            f"has {', '.join(sorted(allowed - _TRUTH_KEYS))} and truth_* keys"
        )
    name = flat.get("format")
    if name is not None and str(np.asarray(name).reshape(()).item()) != FORMAT_NAME:
        raise ValueError(f"{where}: 'format' is {name!r}, not {FORMAT_NAME!r}")
    version = flat.get("format_version")
    if version is not None:
        try:
            v = float(np.asarray(version).reshape(()))
        except (TypeError, ValueError):
            raise ValueError(
                f"{where}: 'format_version' must be a number, got {version!r}"
            ) from None
        if not (np.isfinite(v) and 1 <= v <= FORMAT_VERSION and v == int(v)):
            raise ValueError(
                f"{where}: 'format_version' {version!r}: this scatterlab reads version 1 to "
                f"{FORMAT_VERSION} (a newer file needs a newer scatterlab)"
            )


def _bool(v) -> bool:
    v = np.asarray(v).reshape(()).item()
    return v.lower() == "true" if isinstance(v, str) else bool(v)


# -------------------------------------------------------------------------------------------
# dispatch
def read_dataset(path) -> PolarimetricDataset:
    """Read a dataset, choosing the reader from the file name.

    Parameters
    ----------
    path : str or Path
        ``.h5``/``.hdf5``, ``.npz``, ``.tif``/``.tiff`` (with its sidecar ``.toml``) or the sidecar
        ``.toml``.

    Returns
    -------
    PolarimetricDataset

    Raises
    ------
    ValueError
        "expected a dataset" for other kinds of file; the readers' errors, naming the file and key.
    FileNotFoundError
        A missing file.
    """
    from scatterlab.io import stacks

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in DATASET_SUFFIXES:
        raise ValueError(
            f"{path}: expected a dataset (HDF5 .h5, NPZ .npz, or a TIFF stack with a sidecar "
            f".toml), got a {suffix or 'suffix-less'} file"
        )
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    if suffix in (".h5", ".hdf5"):
        return stacks.read_dataset_hdf5(path)
    if suffix == ".npz":
        return stacks.read_dataset_npz(path)
    return stacks.read_dataset_tiff(path)


def write_dataset(
    path, ds: PolarimetricDataset, *, dofp_pattern=None, overwrite: bool = False
) -> Path:
    """Write ``ds`` in the format named by the file's suffix.

    Parameters
    ----------
    path : str or Path
        Ending in ``.h5``/``.hdf5`` (HDF5, images gzip-compressed), ``.npz`` (compressed NPZ) or
        ``.tif``/``.tiff`` (a multi-page TIFF, every other key in its sidecar TOML and the truth in
        ``NAME-truth.npz``); images are stored as float32.
    ds, dofp_pattern, overwrite
        As :func:`~scatterlab.io.write_dataset_hdf5`.

    Returns
    -------
    Path
        The file written.
    """
    from scatterlab.io import stacks

    check_write_arguments(path, ds, "write_dataset")
    suffix = Path(path).suffix.lower()
    writers = {
        ".h5": stacks.write_dataset_hdf5,
        ".hdf5": stacks.write_dataset_hdf5,
        ".npz": stacks.write_dataset_npz,
        ".tif": stacks.write_dataset_tiff,
        ".tiff": stacks.write_dataset_tiff,
    }
    if suffix not in writers:
        raise ValueError(f"{path}: dataset files end in {sorted(writers)}")
    return writers[suffix](path, ds, dofp_pattern=dofp_pattern, overwrite=overwrite)


def check_write_arguments(path, ds, function: str) -> None:
    """Refuse a dataset writer's arguments in the wrong order or of the wrong kind.

    Parameters
    ----------
    path : object
        What was given as the file path (a str or os.PathLike is expected).
    ds : object
        What was given as the dataset (a :class:`PolarimetricDataset` is expected).
    function : str
        The writer's name, for the message.

    Returns
    -------
    None
        Raises or does nothing.

    Raises
    ------
    TypeError
        Naming the argument: ``path`` first, ``ds`` second (swapped arguments are said to be so).
    """
    import os

    usage = f"{function}(path, ds): the first argument is the file path, the second the dataset"
    if isinstance(path, PolarimetricDataset) and isinstance(ds, (str, os.PathLike)):
        raise TypeError(f"{usage}; got them the other way round: call {function}({ds!r}, ds)")
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"{usage}; path must be a str or Path, got {type(path).__name__}")
    if not isinstance(ds, PolarimetricDataset):
        raise TypeError(f"{usage}; ds must be a PolarimetricDataset, got {type(ds).__name__}")


def with_pixel_mask(
    ds: PolarimetricDataset, bad_pixels=None, *, full_well: float | None = None
) -> PolarimetricDataset:
    """``ds`` with ``bad_pixels`` added to its own and ``full_well`` replacing its own
    (``scatterlab analyze --bad-pixels FILE --full-well E``).

    Parameters
    ----------
    ds : PolarimetricDataset
    bad_pixels : array_like (H, W) or (G, H, W), optional
        Non-zero where a pixel is bad (dead, hot, defective).
    full_well : float, optional [e-]
        Dark-subtracted count at which a pixel saturates (values at or above it are censored).

    Returns
    -------
    PolarimetricDataset
        Validated as a file's keys are (ValueError naming ``bad_pixels`` or ``full_well_e``).
    """
    flat = to_flat(ds)
    G, _, H, W = ds.counts.shape
    if bad_pixels is not None:
        # a sensor mask of a DoFP camera may come on its raw frame (2H, 2W)
        extra = _bad_pixels({"bad_pixels": bad_pixels}, ds.counts.shape, "bad_pixels", True)
        own = flat.get("bad_pixels")
        own = np.zeros((G, H, W), bool) if own is None else np.broadcast_to(own != 0, (G, H, W))
        flat["bad_pixels"] = (extra | own).astype(np.uint8)
    if full_well is not None:
        flat["full_well_e"] = full_well
    out = from_flat(flat, ds.source or "dataset")
    # keep the notes of the reading (e.g. the DoFP demosaicing), not those the new mask replaces
    own_notes = (DEAD_PIXEL_NOTE, LEFT_OUT_NOTE, SATURATED_NOTE, PLATEAU_NOTE)
    out.notes = [
        n for n in ds.notes if not any(o in n for o in own_notes) and n not in out.notes
    ] + out.notes
    return out
