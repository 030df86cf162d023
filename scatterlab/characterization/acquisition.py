r"""Acquisition stage: a painted plate seen by a 4-channel polarimeter, with or without turbulence (Ch. VII).

The plate (object coordinates: labels 0 paint, 1 bare metal, 2 scratches) is rendered with the pBRDF
(:func:`scatterlab.imaging.render_stokes`, unpolarized light, specular geometry) as a distant camera sees it,
foreshortened by :math:`\cos\theta_r` along the plane of incidence. The camera field is rendered with a margin
of half the image on every side (the plate is larger than the field) and blurred there, so that light from
outside the field enters it and nothing wraps around: the images are what a real camera records, not a
periodic simulation. The channels are imaged through the diffraction-limited pupil (no turbulence) or through
one Kolmogorov phase screen per D/r0 (tilt kept, shared by all channels: a division-of-amplitude polarimeter),
then detected with shot and read noise.

With ``phase_diversity_waves`` > 0 in the scene, a beam splitter sends ``phase_diversity_share`` of the light
to two unpolarized cameras defocused by +/- that many waves (peak to valley), which record the same instant
through the same screen: the frames :func:`scatterlab.deconvolution.phase_diversity` identifies the PSF from.
The polarimeter keeps the rest of the light (its counts fall by the share).

:class:`Ideal` switches parts of the chain to their ideal version, for the error budget
(``studies/characterization_error_budget.py``): noise-free counts, no optics at all (no halo, no edge mixing),
no foreshortening, the true PSF given to the restoration, perfect registration, true classes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Ideal", "Acquisition", "acquire", "plate_scene"]


@dataclass(frozen=True)
class Ideal:
    """Stages replaced by their ideal versions (all False: the realistic pipeline).

    Attributes
    ----------
    noise : bool
        Noise-free counts (expected photo-electrons), no shot or read noise.
    optics : bool
        No blur at all: neither the diffraction halo nor turbulence (so no edge mixing either).
    foreshortening : bool
        The camera sees the plate in object coordinates (no keystone stretch, no resampling).
    psf : bool
        The restoration is given the true PSF (known-PSF EM) instead of estimating it blindly.
    registration : bool
        Images are aligned with the true object instead of the no-turbulence image.
    classes : bool
        The true labels are used as classes.
    """

    noise: bool = False
    optics: bool = False
    foreshortening: bool = False
    psf: bool = False
    registration: bool = False
    classes: bool = False

    def label(self) -> str:
        """Short name of the switched stages (``"none"`` for the realistic pipeline)."""
        on = [k for k, v in self.__dict__.items() if v]
        return "+".join(on) if on else "none"


@dataclass
class Acquisition:
    """One acquisition: channel counts of one plate at one specular geometry and one turbulence case.

    Attributes
    ----------
    theta : float
        theta_i = theta_r [rad].
    case : str
        ``"no_turbulence"`` or ``"D_r0_<value>"``.
    d_over_r0 : float or None
        Turbulence strength (None: diffraction-limited).
    counts : ndarray, shape (K, H, W)
        Dark-subtracted channel images [photo-electrons].
    angles : ndarray, shape (K,)
        Polarizer angles [rad].
    psf_true : ndarray, shape (H, W)
        The PSF the data were blurred with (centred, unit sum; a delta with ``Ideal(optics=True)``).
    pupil : ndarray, shape (H/2, H/2)
        The aperture (2 pixels per lambda/D in the image).
    truth_s0, truth_dolp : ndarray, shape (H, W)
        The object's S0 [1/sr per unit irradiance] and DOLP (signed S1/S0: the AOP is fixed at 0) in object
        coordinates.
    foreshortened : bool
        Whether the camera saw the plate foreshortened (False with ``Ideal(foreshortening=True)``).
    diversity_counts : ndarray, shape (2, H, W), or None
        Dark-subtracted counts of the defocused cameras [photo-electrons] (None: no phase diversity).
    diversity_phases : ndarray, shape (2, H/2, H/2), or None
        Their known pupil-phase offsets [rad] (+/- ``phase_diversity_waves`` of defocus).
    diversity_share : float
        Share of the light the beam splitter sends to the two cameras together (0: none).
    read_noise : float
        Read noise per read [e- rms] (each image and its dark frame are read once).
    full_well : float or None
        Dark-subtracted count at which a pixel saturates [photo-electrons]: values at or above it are
        censored in the restoration, and a pixel with such a channel has no measured DOLP.
    valid : ndarray of bool, shape (H, W), or None
        Pixels to measure with (False: dead, hot or defective; left out of the likelihood and left
        unclassified); None: all.
    """

    theta: float
    case: str
    d_over_r0: float | None
    counts: np.ndarray
    angles: np.ndarray
    psf_true: np.ndarray
    pupil: np.ndarray
    truth_s0: np.ndarray
    truth_dolp: np.ndarray
    foreshortened: bool = True
    diversity_counts: np.ndarray | None = None
    diversity_phases: np.ndarray | None = None
    diversity_share: float = 0.0
    read_noise: float = 0.0
    valid: np.ndarray | None = None
    full_well: float | None = None


def plate_scene(plate, labels, theta):
    """The :class:`scatterlab.imaging.Scene` of a plate's label map at ``theta`` [rad] (specular).

    Scratches are bare metal of the plate's roughness: an isotropic pBRDF cannot give their wire-grid
    polarization, and a smoother scratch would outshine the plate, which the measured images do not show.

    Parameters
    ----------
    plate : Plate
        Materials and roughnesses.
    labels : ndarray of int, shape (H, W)
        Label map (0 paint, 1 metal, 2 scratch).
    theta : float
        Specular angle theta_i = theta_r [rad].

    Returns
    -------
    Scene
        Per-pixel index, roughness and geometry for :func:`scatterlab.imaging.render_stokes`.
    """
    from scatterlab.imaging import Scene

    metal = plate.metal_n - 1j * plate.metal_kappa
    paint = plate.paint_n - 1j * plate.paint_kappa
    rough = [plate.paint_roughness, plate.metal_roughness, plate.metal_roughness]
    return Scene(labels, [paint, metal, metal], rough, theta, theta, np.pi)


def _field_psf(pupil, screen, shape):
    """PSF through ``pupil`` with phase ``screen`` (None: diffraction-limited), centred on ``shape``."""
    from scatterlab.deconvolution import resample_psf
    from scatterlab.imaging import psf

    return resample_psf(psf(pupil, screen, pad=2), shape)


def _camera_psf(pupil, d_over_r0, psf, ideal: Ideal, shape, rng):
    """The PSF that blurs the camera field ``shape`` and the screen [rad] it was made with: a given PSF,
    none (``ideal.optics``), the diffraction-limited pupil's, or the pupil's through one new Kolmogorov
    screen of ``d_over_r0`` (the screen is None when there is none)."""
    from scatterlab.deconvolution import resample_psf
    from scatterlab.imaging import phase_screen

    if psf is not None:
        return resample_psf(np.clip(np.asarray(psf, float), 0, None), shape), None
    n = pupil.shape[0]
    # the screen is drawn even when the optics are ideal: the noise that follows keeps its draws
    screen = None if d_over_r0 is None else phase_screen(n, 1.0, n / d_over_r0, rng)
    if ideal.optics:
        h = np.zeros(shape)
        h[shape[0] // 2, shape[1] // 2] = 1.0
        return h, screen
    return _field_psf(pupil, screen, shape), screen


def acquire(
    plate, labels, theta, case, d_over_r0, cfg, rng, ideal: Ideal = Ideal(), *, psf=None
) -> Acquisition:
    """Simulate one acquisition of ``plate`` at the specular geometry ``theta``.

    Parameters
    ----------
    plate : Plate
        Materials and roughnesses (:class:`~scatterlab.characterization.scene_config.Plate`).
    labels : ndarray of int, shape (H, W)
        Object-coordinate label map (0 paint, 1 metal, 2 scratch).
    theta : float
        theta_i = theta_r [rad], in (0, 89) deg.
    case : str
        Name of the case (``"no_turbulence"``, ``"D_r0_7.9"``).
    d_over_r0 : float or None
        Turbulence strength; None for the diffraction-limited system.
    cfg : SceneConfig
        Photon budget, read noise and polarizer angles.
    rng : numpy.random.Generator
        Draws the phase screen and the noise.
    ideal : Ideal
        ``noise``, ``optics`` and ``foreshortening`` act here.
    psf : ndarray, shape (H, W), optional
        Blur with this centred PSF instead of the one of the pupil and screen (re-simulation of an estimate;
        no defocused cameras then).

    Returns
    -------
    Acquisition
    """
    from scatterlab.characterization.registration import foreshorten
    from scatterlab.characterization.scene_config import diversity_waves
    from scatterlab.imaging import channel_images as channels_of
    from scatterlab.imaging import circular_pupil, detect, render_stokes
    from scatterlab.polarization import signed_dolp

    labels = np.asarray(labels)
    H, W = labels.shape
    angles = np.radians(cfg.polarizer_deg)
    S_obj = render_stokes(plate_scene(plate, labels, theta))
    # the camera field with a margin of half the image on each side: light from outside enters, none wraps
    my, mx = H // 2, W // 2
    wide = np.pad(labels, ((my, my), (mx, mx)), mode="edge")
    seen = wide if ideal.foreshortening else foreshorten(wide, theta)
    S_cam = render_stokes(plate_scene(plate, seen, theta))
    n = H // 2
    pupil = circular_pupil(n, n / 2)
    h_wide, screen = _camera_psf(pupil, d_over_r0, psf, ideal, seen.shape, rng)
    crop = (slice(None), slice(my, my + H), slice(mx, mx + W))
    channels = np.clip(channels_of(S_cam, angles, h_wide)[crop], 0.0, None)  # FFT round-off
    # the brightest channel pixel gets cfg.photons without a beam splitter; the polarimeter keeps 1 - share
    share = cfg.phase_diversity_share if _has_diversity(cfg, d_over_r0, psf, ideal) else 0.0
    unit = channels.max()

    def detected(images):
        if ideal.noise:
            return cfg.photons * images / unit
        return detect(images, rng, photons=cfg.photons, read_noise=cfg.read_noise, scale=unit)

    counts = detected((1.0 - share) * channels)
    div_counts = div_phases = None
    if share > 0:
        from scatterlab.deconvolution import defocus_phase

        w = diversity_waves(cfg, d_over_r0)
        div_phases = np.stack([defocus_phase(pupil, w), defocus_phase(pupil, -w)])
        # each camera records share / 2 of all the light the polarimeter's channels record together
        div_counts = np.stack(
            [
                detected(0.5 * share * channels_of(S_cam, angles, h).sum(0, keepdims=True)[crop])[0]
                for h in (_field_psf(pupil, screen + t, seen.shape) for t in div_phases)
            ]
        )
    from scatterlab.deconvolution import resample_psf

    psf_true = resample_psf(h_wide, (H, W))
    truth_dolp = signed_dolp(S_obj)  # S1 / S0 (the AOP is fixed at 0), NaN where S0 = 0
    return Acquisition(
        theta=float(theta),
        case=case,
        d_over_r0=d_over_r0,
        counts=counts,
        angles=angles,
        psf_true=psf_true,
        pupil=pupil,
        truth_s0=S_obj[..., 0],
        truth_dolp=truth_dolp,
        foreshortened=not ideal.foreshortening,
        diversity_counts=div_counts,
        diversity_phases=div_phases,
        diversity_share=share,
        read_noise=float(cfg.read_noise),
    )


def _has_diversity(cfg, d_over_r0, psf, ideal: Ideal) -> bool:
    """Whether this acquisition has defocused cameras: turbulence, a scene that asks for them, real optics
    and the pupil's own PSF (not a given one)."""
    from scatterlab.characterization.scene_config import diversity_waves

    waves = diversity_waves(cfg, d_over_r0)
    return waves > 0 and psf is None and not ideal.optics
