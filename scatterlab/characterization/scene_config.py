"""Scene descriptions for the characterization pipeline (TOML), and the bundled default scene.

Keys (units in the names; all optional except where noted):

```toml
title = "painted aluminium and steel, 1550 nm"
wavelength_um = 1.55                  # recorded with the results: the plates' indices below are the ones at
                                      # this wavelength, and the optics are sampled in lambda/D (2 px per lambda/D);
                                      # in [0.01, 100] um, as in a dataset file (1.55e-6 or 1550 is refused)
image_size = 128                      # pixels (square), the pupil grid is half of it
geometry_deg = [30, 35, 40, 45, 50, 55, 60]   # specular theta_i = theta_r per acquisition (Ch. VII)
d_over_r0 = [7.9, 12.9]               # turbulence strengths; a no-turbulence case is always included
photons = 100000                      # expected photo-electrons at the brightest channel pixel (full well)
read_noise = 10.0                     # e- rms
polarizer_deg = [0, 45, 90, 135]       # at least three distinct angles (mod 180 deg), each in [-360, 360] deg
iterations = 150                      # EM iterations per acquisition
psf_model = "pupil"                   # PSF update: "pupil" (Schulz, GS steps) or "em" (non-parametric, Eq. 194)
psf_refine = "none"                   # "layout": refine each blind PSF with a few-material object
                                      # (scatterlab.deconvolution.layout_psf), then restore with it known;
                                      # about 10x the time of a blind restoration
blind_starts = 3                      # random start PSFs per blind restoration, aligned and averaged: the
                                      # ghosts of a wrong PSF estimate change place with the start and
                                      # average down (1: one start, as Sec. 5.3.2); the time grows with it
phase_diversity_waves = 0.0           # > 0: two unpolarized cameras defocused by +/- this many waves (peak
                                      # to valley; or a list, one per d_over_r0, 0 for none at that strength)
                                      # record each turbulent exposure, and the PSF is found by
                                      # phase diversity (scatterlab.deconvolution.phase_diversity), then the
                                      # image restored with it known; 0: blind deconvolution
phase_diversity_share = 0.3333        # share of the light the beam splitter sends to those two cameras
priors = "ch7"                        # DOLP prior set for the classification (ch5, ch6, ch7) or "none"
estimate = ["classes", "n_kappa", "posterior"]   # what to compute (leave out what is not needed; [] restores
                                      # the images and scores them, DOLP and S0 errors and PSF distances, only)
sigma_known = 0.3                     # roughness used by the n, kappa inversion (the reference measured it)
posterior_steps = 1500
calibration_replicates = 4            # re-simulations per geometry that calibrate a blind restoration's bias
model_error = false                   # add the pBRDF's DOLP model error measured against the MoM (issue 17) to
                                      # the region errors: off for simulations rendered by the pBRDF itself
seed = 20101210
plate_zoom = 4.0                      # template magnification: 1 = the whole "st"; 2 = the text's field of
plate_center = [7.2, 8.5]             # Figs. 49-52 (right of the "s", left of the "t") on 256 px; 4 = the
                                      # text's features at 128 px (the same lambda/D per feature, half the field)
region_margin_px = 4                  # erosion of the region masks (default: 2 px / cos of the largest angle)

[[plates]]                            # one painted plate per entry (Figs. 49-61)
metal = "aluminium"
metal_n = 1.44
metal_kappa = 16.0
paint_n = 1.39
paint_kappa = 0.34
metal_roughness = 0.3
paint_roughness = 0.3
# paint_n_prior = [1.3, 1.8]          # optional, per material and index (metal_n_prior, metal_kappa_prior,
                                      # paint_n_prior, paint_kappa_prior): the posteriors' prior range
                                      # [low, high]; default n in [0, 5], kappa in [0, 25]
```
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from pathlib import Path

__all__ = [
    "SceneConfig",
    "Plate",
    "default_scene",
    "diversity_waves",
    "load_scene",
    "plate_labels",
    "quick_scene",
]

ESTIMATES = ("classes", "n_kappa", "posterior")
MAX_IMAGE_SIZE = (
    2048  # pixels: the 2x-wide rendering field and the EM grids of one image fit in a few GiB
)


@dataclass
class Plate:
    """One painted metal plate: indices ``n - j kappa`` at the scene's wavelength and per-axis rms slopes."""

    metal: str = "aluminium"
    metal_n: float = 1.44
    metal_kappa: float = 16.0
    paint_n: float = 1.39
    paint_kappa: float = 0.34
    metal_roughness: float = 0.3
    paint_roughness: float = 0.3
    # prior ranges [low, high] of the region posteriors (None: the inversion's defaults, n in [0, 5],
    # kappa in [0, 25]); what the scientist knows of the material before the measurement
    metal_n_prior: list | None = None
    metal_kappa_prior: list | None = None
    paint_n_prior: list | None = None
    paint_kappa_prior: list | None = None

    def prior_bounds(self, region: str) -> dict:
        """The region posterior's prior ranges for ``region`` ("metal" or "paint").

        Parameters
        ----------
        region : str
            ``"metal"`` or ``"paint"``.

        Returns
        -------
        dict
            ``{"n": (low, high), "kappa": (low, high)}`` with the inversion's defaults
            (:data:`scatterlab.inversion.DEFAULT_BOUNDS`) where the plate gives none.
        """
        from scatterlab.inversion.least_squares import DEFAULT_BOUNDS

        if region not in ("metal", "paint"):
            raise ValueError(f"region must be 'metal' or 'paint', got {region!r}")
        out = {}
        for q in ("n", "kappa"):
            given = getattr(self, f"{region}_{q}_prior")
            out[q] = tuple(float(x) for x in (DEFAULT_BOUNDS[q] if given is None else given))
        return out

    def validate(self, where: str = "plates") -> "Plate":
        """Check every key (type and range); ValueError names the key (``where.key``).

        Parameters
        ----------
        where : str
            The plate's place in the scene, for the messages (e.g. ``"plates[0]"``).

        Returns
        -------
        Plate
            ``self``.
        """
        _check_types(self, where)
        if not isinstance(self.metal, str) or not self.metal.isidentifier():
            raise ValueError(
                f"{where}.metal must be a name (letters, digits, _), got {self.metal!r}"
            )
        for name in ("metal_n", "paint_n"):
            v = getattr(self, name)
            if not (math.isfinite(v) and 0 < v <= 100):
                raise ValueError(f"{where}.{name} must be in (0, 100], got {v!r}")
        for name in ("metal_kappa", "paint_kappa"):
            v = getattr(self, name)
            if not (math.isfinite(v) and 0 <= v <= 1000):
                raise ValueError(f"{where}.{name} must be in [0, 1000], got {v!r}")
        for name in ("metal_roughness", "paint_roughness"):
            v = getattr(self, name)
            if not (math.isfinite(v) and 1e-3 <= v <= 1.5):
                raise ValueError(f"{where}.{name} (rms slope) must be in [0.001, 1.5], got {v!r}")
        for region in ("metal", "paint"):
            for q in ("n", "kappa"):
                name = f"{region}_{q}_prior"
                v = getattr(self, name)
                if v is None:
                    continue
                ok = (
                    isinstance(v, (list, tuple))
                    and len(v) == 2
                    and all(_is(x, float) and math.isfinite(x) for x in v)
                    and 0 <= v[0] < v[1]
                )
                if not ok:
                    raise ValueError(
                        f"{where}.{name} must be [low, high] with 0 <= low < high, got {v!r}"
                    )
                truth = getattr(self, f"{region}_{q}")
                if not v[0] <= truth <= v[1]:
                    # a simulation whose prior excludes its own truth cannot cover it
                    raise ValueError(
                        f"{where}.{name} {list(v)} excludes the plate's {region}_{q} = {truth!r}"
                    )
        return self


@dataclass
class SceneConfig:
    """A characterization scene (module docstring lists the keys with their units)."""

    title: str = "painted aluminium and steel plates, 1550 nm (Figs. 49-61)"
    wavelength_um: float = 1.55
    image_size: int = 128
    geometry_deg: list = field(default_factory=lambda: [30, 35, 40, 45, 50, 55, 60])
    d_over_r0: list = field(default_factory=lambda: [7.9, 12.9])
    photons: float = 1e5
    read_noise: float = 10.0
    polarizer_deg: list = field(default_factory=lambda: [0, 45, 90, 135])
    iterations: int = 150
    psf_model: str = "pupil"
    psf_refine: str = "none"
    blind_starts: int = 3
    phase_diversity_waves: float | list = 0.0
    phase_diversity_share: float = 0.3333
    priors: str = "ch7"
    estimate: list = field(default_factory=lambda: list(ESTIMATES))
    sigma_known: float = 0.3
    posterior_steps: int = 1500
    calibration_replicates: int = 4
    model_error: bool = False
    seed: int = 20101210
    plate_zoom: float = 4.0
    plate_center: list = field(default_factory=lambda: [7.2, 8.5])
    region_margin_px: int | None = None
    plates: list = field(default_factory=lambda: [Plate(), Plate("steel", 3.60, 5.88)])

    def validate(self) -> "SceneConfig":
        """Check every key (type and range) before anything runs; ValueError names the key."""
        _check_types(self)
        _check_ranges(self)
        if not isinstance(self.plates, list) or not self.plates:
            raise ValueError(
                "plates: at least one [[plates]] entry is needed (an empty list is not allowed)"
            )
        # each plate's keys first: a metal that is not a name (a list, a table) cannot be compared
        for k, p in enumerate(self.plates):
            if not isinstance(p, Plate):
                raise ValueError(f"plates[{k}] must be a table of plate keys")
            p.validate(f"plates[{k}]")
        names = [p.metal for p in self.plates]
        if len(set(names)) != len(names):
            raise ValueError(f"plates: each plate needs its own metal name, got {names}")
        return self


_LISTS = {
    "geometry_deg": float,
    "d_over_r0": float,
    "polarizer_deg": float,
    "estimate": str,
    "plate_center": float,
}


def _check_types(obj, where: str = "") -> None:
    """Type of every field of a dataclass against its default's type (ints accept ints only)."""
    prefix = f"{where}." if where else ""
    for f in fields(obj):
        v = getattr(obj, f.name)
        optional = f.name == "region_margin_px" or f.name.endswith("_prior")  # None: the default
        if f.name == "plates" or (optional and v is None):
            continue
        if f.name.endswith("_prior"):  # [low, high], checked with the ranges
            if not (isinstance(v, list) and all(_is(x, float) for x in v)):
                raise ValueError(
                    f"{prefix}{f.name} must be a list [low, high] of floats, got {v!r}"
                )
            continue
        if (
            f.name == "phase_diversity_waves"
        ):  # a number or a list of numbers (checked with the ranges)
            if not (_is(v, float) or (isinstance(v, list) and all(_is(x, float) for x in v))):
                raise ValueError(
                    f"{prefix}{f.name} must be a float or a list of floats (one per d_over_r0), "
                    f"got {v!r}"
                )
            continue
        if f.name in _LISTS:
            kind = _LISTS[f.name]
            ok = isinstance(v, list) and all(_is(x, kind) for x in v)
            if not ok:
                raise ValueError(f"{prefix}{f.name} must be a list of {kind.__name__}s, got {v!r}")
            continue
        kind = {"int": int, "float": float, "str": str, "int | None": int}.get(
            str(f.type), type(f.default)
        )
        if not _is(v, kind):
            what = {"int": "an integer", "float": "a number", "str": "a string"}.get(
                kind.__name__, f"a {kind.__name__}"
            )
            raise ValueError(f"{prefix}{f.name} must be {what}, got {v!r}")


def _is(v, kind) -> bool:
    if kind is float:
        return isinstance(v, (int, float)) and not isinstance(v, bool)
    if kind is int:
        return isinstance(v, int) and not isinstance(v, bool)
    return isinstance(v, kind)


def _finite(cfg, name, lo, hi, *, lo_open=False):
    v = getattr(cfg, name)
    ok = math.isfinite(v) and (v > lo if lo_open else v >= lo) and v <= hi
    if not ok:
        raise ValueError(f"{name} must be in {'(' if lo_open else '['}{lo:g}, {hi:g}], got {v!r}")


# the wavelengths a scene may have [um]: those of a dataset file (scatterlab.io.dataset), ultraviolet to
# far infrared; a value outside is a unit mistake (metres: 1.55e-6, nanometres: 1550)
WAVELENGTH_RANGE_UM = (0.01, 100.0)


def _check_wavelength(v) -> None:
    """ValueError naming ``wavelength_um`` outside :data:`WAVELENGTH_RANGE_UM` (a unit mistake)."""
    lo, hi = WAVELENGTH_RANGE_UM
    if not (math.isfinite(v) and lo <= v <= hi):
        hint = "metres? nanometres? " if v > 0 else ""
        raise ValueError(
            f"wavelength_um must be in [{lo:g}, {hi:g}] um, got {v!r} ({hint}the key is in micrometres: "
            "1.55 for 1.55e-6 m or 1550 nm)"
        )


# the polarizer angles a scene may give [deg]: a full turn either way (beyond it, a typing error)
POLARIZER_RANGE_DEG = (-360.0, 360.0)


def _check_ranges(cfg: SceneConfig) -> None:
    import numpy as np

    if not (16 <= cfg.image_size <= MAX_IMAGE_SIZE and cfg.image_size % 2 == 0):
        raise ValueError(
            f"image_size must be an even number of pixels in [16, {MAX_IMAGE_SIZE}] "
            f"(memory grows as its square), got {cfg.image_size}"
        )
    if not cfg.geometry_deg or not all(math.isfinite(g) and 0 < g < 89 for g in cfg.geometry_deg):
        raise ValueError(f"geometry_deg must list angles in (0, 89) deg, got {cfg.geometry_deg}")
    # pi / 2: the largest a polar angle in radians can be
    if all(g < math.pi / 2 for g in cfg.geometry_deg):
        raise ValueError(
            f"geometry_deg {cfg.geometry_deg} are all below {math.pi / 2:.4f} deg, where the DOLP is "
            "below 1e-3 and determines nothing: radians given as degrees?"
        )
    if not all(math.isfinite(x) and 0 < x <= 100 for x in cfg.d_over_r0):
        raise ValueError(f"d_over_r0 entries must be in (0, 100], got {cfg.d_over_r0}")
    _check_wavelength(cfg.wavelength_um)
    _finite(cfg, "photons", 0, 1e12, lo_open=True)
    _finite(cfg, "read_noise", 0, 1e6)
    _finite(cfg, "sigma_known", 1e-3, 1.5)
    _finite(cfg, "plate_zoom", 0.25, 16)
    if len(cfg.plate_center) != 2 or not all(
        math.isfinite(c) and 0 <= c <= 16 for c in cfg.plate_center
    ):
        raise ValueError(
            f"plate_center must be [row, column] in template units within [0, 16], "
            f"got {cfg.plate_center}"
        )
    lo, hi = POLARIZER_RANGE_DEG
    if not all(math.isfinite(x) and lo <= x <= hi for x in cfg.polarizer_deg):
        raise ValueError(
            f"polarizer_deg entries must be finite angles in [{lo:g}, {hi:g}] deg, "
            f"got {cfg.polarizer_deg}"
        )
    a = np.mod(np.radians(cfg.polarizer_deg), np.pi)
    if len(np.unique(np.round(a, 9))) < 3:
        raise ValueError(
            f"polarizer_deg needs at least three distinct angles (mod 180 deg), "
            f"got {cfg.polarizer_deg}"
        )
    if cfg.psf_model not in ("em", "pupil"):
        raise ValueError(f"psf_model must be 'em' or 'pupil', got {cfg.psf_model!r}")
    if cfg.psf_refine not in ("none", "layout"):
        raise ValueError(f"psf_refine must be 'none' or 'layout', got {cfg.psf_refine!r}")
    waves = cfg.phase_diversity_waves
    if isinstance(waves, list) and len(waves) != len(cfg.d_over_r0):
        raise ValueError(
            f"phase_diversity_waves must have one entry per d_over_r0 ({len(cfg.d_over_r0)}), "
            f"got {len(waves)}"
        )
    if not all(math.isfinite(w) and 0 <= w <= 10 for w in np.atleast_1d(waves)):
        raise ValueError(f"phase_diversity_waves must be in [0, 10] waves, got {waves!r}")
    _finite(cfg, "phase_diversity_share", 0, 0.9, lo_open=True)
    if not 1 <= cfg.blind_starts <= 64:
        raise ValueError(f"blind_starts must be in [1, 64], got {cfg.blind_starts}")
    if not 1 <= cfg.iterations <= 100000:
        raise ValueError(f"iterations must be in [1, 100000], got {cfg.iterations}")
    if not 100 <= cfg.posterior_steps <= 10**6:
        raise ValueError(f"posterior_steps must be in [100, 1000000], got {cfg.posterior_steps}")
    if not 1 <= cfg.calibration_replicates <= 100:
        raise ValueError(
            f"calibration_replicates must be in [1, 100], got {cfg.calibration_replicates}"
        )
    if not 0 <= cfg.seed < 2**63:
        raise ValueError(f"seed must be in [0, 2^63), got {cfg.seed}")
    if cfg.region_margin_px is not None and not 0 <= cfg.region_margin_px <= cfg.image_size // 8:
        raise ValueError(
            f"region_margin_px must be in [0, image_size/8], got {cfg.region_margin_px}"
        )
    if cfg.priors not in ("ch5", "ch6", "ch7", "none"):
        raise ValueError(f"priors must be one of ch5, ch6, ch7, none, got {cfg.priors!r}")
    bad = set(cfg.estimate) - set(ESTIMATES)
    if bad:
        raise ValueError(f"estimate entries must be among {ESTIMATES}, got {sorted(bad)}")
    if "n_kappa" in cfg.estimate and len(cfg.geometry_deg) < 2:
        raise ValueError("geometry_deg: estimating n and kappa needs at least two geometries")


def diversity_waves(cfg: SceneConfig, d_over_r0) -> float:
    """The defocus [waves, peak to valley] of the phase-diversity cameras at turbulence ``d_over_r0``.

    Parameters
    ----------
    cfg : SceneConfig
    d_over_r0 : float or None
        One of ``cfg.d_over_r0`` (None: no turbulence, no cameras).

    Returns
    -------
    float
        0 when there are no cameras.
    """
    waves = cfg.phase_diversity_waves
    if d_over_r0 is None or not waves:
        return 0.0
    if not isinstance(waves, list):
        return float(waves)
    matches = [w for w, d in zip(waves, cfg.d_over_r0) if d == d_over_r0]
    return float(matches[0]) if matches else 0.0


def default_scene() -> SceneConfig:
    """The bundled scene: painted aluminium and painted steel at 1550 nm, seven specular geometries.

    Returns
    -------
    SceneConfig
    """
    return SceneConfig().validate()


LIKELY_NANOMETRES_UM = (
    30.0  # a wavelength_um above this is more likely nanometres than far infrared
)
QUICK_IMAGE_SIZE = 64
QUICK_GEOMETRIES = 3


def quick_scene(cfg: SceneConfig) -> SceneConfig:
    """A small, fast version of a scene (``characterize --quick``): a smoke test, not a reproduction.

    At most :data:`QUICK_IMAGE_SIZE` pixels, :data:`QUICK_GEOMETRIES` geometries spread over the scene's
    range (both ends kept; a scene with fewer keeps all), the first D/r0 only, 15 EM iterations and 400
    posterior steps. A region margin set in pixels shrinks with the image.

    Parameters
    ----------
    cfg : SceneConfig
        A validated scene (left unchanged).

    Returns
    -------
    SceneConfig
        The reduced scene, validated.

    Raises
    ------
    ValueError
        The reduced scene is invalid; the message says that ``--quick`` made it so.
    """
    import copy

    q = copy.deepcopy(cfg)
    size = min(cfg.image_size, QUICK_IMAGE_SIZE)
    g = list(cfg.geometry_deg)
    if len(g) > QUICK_GEOMETRIES:
        idx = sorted(
            {round(i * (len(g) - 1) / (QUICK_GEOMETRIES - 1)) for i in range(QUICK_GEOMETRIES)}
        )
        g = [g[i] for i in idx]
    q.image_size, q.geometry_deg, q.d_over_r0 = size, g, list(cfg.d_over_r0[:1])
    if isinstance(cfg.phase_diversity_waves, list):
        q.phase_diversity_waves = list(cfg.phase_diversity_waves[:1])
    if cfg.region_margin_px is not None:
        q.region_margin_px = int(round(cfg.region_margin_px * size / cfg.image_size))
    q.iterations, q.posterior_steps = min(cfg.iterations, 15), min(cfg.posterior_steps, 400)
    q.title = f"{cfg.title} -- quick: a smoke test, not a reproduction"
    try:
        return q.validate()
    except ValueError as exc:
        raise ValueError(
            f"--quick reduced the scene ({size} px, geometries {g} deg, D/r0 {q.d_over_r0}) and then: {exc}"
        ) from exc


def plate_labels(cfg: SceneConfig, rng):
    """The plate's object-coordinate label map ``(image_size, image_size)`` (0 paint, 1 metal, 2 scratch).

    Parameters
    ----------
    cfg : SceneConfig
    rng : numpy.random.Generator
        Seeds the scratches.

    Returns
    -------
    ndarray of int, shape (image_size, image_size)
    """
    from scatterlab.imaging import painted_plate

    return painted_plate(
        cfg.image_size, zoom=cfg.plate_zoom, center=tuple(cfg.plate_center), rng=rng
    ).labels


def load_scene(path) -> SceneConfig:
    """Read a TOML scene description (module docstring).

    Unknown keys (also inside ``[[plates]]``), wrong types and out-of-range values raise ValueError naming
    the key; a file that is not TOML raises ValueError saying that a TOML scene was expected.

    Parameters
    ----------
    path : path
        TOML scene file.

    Returns
    -------
    SceneConfig
        Validated.
    """
    import tomllib

    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise ValueError(f"{path}: expected a TOML scene file ({exc})") from None
    plates = data.pop("plates", None)
    known = {f.name for f in fields(SceneConfig)} - {"plates"}
    unknown = set(data) - known
    if unknown:
        raise ValueError(f"{path}: unknown scene keys {sorted(unknown)}; allowed: {sorted(known)}")
    cfg = SceneConfig(**data)
    if plates is not None:
        if not isinstance(plates, list):
            raise ValueError(f"{path}: plates must be [[plates]] tables")
        pk = {f.name for f in fields(Plate)}
        cfg.plates = []
        for k, p in enumerate(plates):
            if not isinstance(p, dict):
                raise ValueError(f"{path}: plates[{k}] must be a [[plates]] table, got {p!r}")
            bad = set(p) - pk
            if bad:
                raise ValueError(
                    f"{path}: unknown key(s) {sorted(bad)} in plates[{k}]; allowed: {sorted(pk)}"
                )
            missing = [key for key in ("metal_n", "metal_kappa") if key not in p]
            metal = p.get("metal", "aluminium")  # not a string: validate() names it below
            if isinstance(metal, str) and metal != "aluminium" and missing:
                import warnings

                warnings.warn(
                    f"{path}: plates[{k}] names metal {p['metal']!r} but not {' or '.join(missing)}: "
                    f"aluminium's {', '.join(f'{m} = {getattr(Plate, m)}' for m in missing)} is used",
                    UserWarning,
                    stacklevel=2,
                )
            cfg.plates.append(Plate(**p))
    try:
        cfg.validate()
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None
    if cfg.wavelength_um > LIKELY_NANOMETRES_UM:
        import warnings

        warnings.warn(
            f"{path}: wavelength_um = {cfg.wavelength_um:g} is beyond the thermal infrared: nanometres given "
            f"as micrometres? (the plates' indices must be the ones at this wavelength)",
            UserWarning,
            stacklevel=2,
        )
    return cfg
