"""Scene descriptions for the characterization pipeline (TOML), and the bundled default scene.

Keys (units in the names; all optional except where noted):

```toml
title = "painted aluminium and steel, 1550 nm"
wavelength_um = 1.55                  # recorded with the results: the plates' indices below are the ones at
                                      # this wavelength, and the optics are sampled in lambda/D (2 px per lambda/D)
image_size = 128                      # pixels (square), the pupil grid is half of it
geometry_deg = [30, 35, 40, 45, 50, 55, 60]   # specular theta_i = theta_r per acquisition (Ch. VII)
d_over_r0 = [7.9, 12.9]               # turbulence strengths; a no-turbulence case is always included
photons = 100000                      # expected photo-electrons at the brightest channel pixel (full well)
read_noise = 10.0                     # e- rms
polarizer_deg = [0, 45, 90, 135]
iterations = 150                      # EM iterations per acquisition
psf_model = "pupil"                   # PSF update: "pupil" (Schulz, GS steps) or "em" (non-parametric, Eq. 194)
priors = "ch7"                        # DOLP prior set for the classification (ch5, ch6, ch7) or "none"
estimate = ["classes", "n_kappa", "posterior"]   # what to compute (leave out what is not needed)
sigma_known = 0.3                     # roughness used by the n, kappa inversion (the reference measured it)
posterior_steps = 1500
seed = 20101210

[[plates]]                            # one painted plate per entry (Figs. 49-61)
metal = "aluminium"
metal_n = 1.44
metal_kappa = 16.0
paint_n = 1.39
paint_kappa = 0.34
metal_roughness = 0.3
paint_roughness = 0.3
```
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path


__all__ = ["SceneConfig", "default_scene", "load_scene"]

ESTIMATES = ("classes", "n_kappa", "posterior")


@dataclass
class Plate:
    metal: str = "aluminium"
    metal_n: float = 1.44
    metal_kappa: float = 16.0
    paint_n: float = 1.39
    paint_kappa: float = 0.34
    metal_roughness: float = 0.3
    paint_roughness: float = 0.3


@dataclass
class SceneConfig:
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
    priors: str = "ch7"
    estimate: list = field(default_factory=lambda: list(ESTIMATES))
    sigma_known: float = 0.3
    posterior_steps: int = 1500
    seed: int = 20101210
    plates: list = field(default_factory=lambda: [Plate(), Plate("steel", 3.60, 5.88)])

    def validate(self) -> "SceneConfig":
        if self.image_size < 16 or self.image_size % 2:
            raise ValueError("image_size must be an even number of pixels >= 16")
        if not self.geometry_deg or not all(0 < g < 90 for g in self.geometry_deg):
            raise ValueError("geometry_deg must list angles in (0, 90) deg")
        if any(x <= 0 for x in self.d_over_r0):
            raise ValueError("d_over_r0 entries must be > 0")
        if not self.wavelength_um > 0:
            raise ValueError(f"wavelength_um must be > 0, got {self.wavelength_um}")
        if self.photons <= 0 or self.read_noise < 0:
            raise ValueError("photons must be > 0 and read_noise >= 0")
        if len(self.polarizer_deg) < 3:
            raise ValueError("polarizer_deg needs at least three angles")
        if self.psf_model not in ("em", "pupil"):
            raise ValueError(f"psf_model must be 'em' or 'pupil', got {self.psf_model!r}")
        if self.iterations < 1:
            raise ValueError(f"iterations must be >= 1, got {self.iterations}")
        if self.priors not in ("ch5", "ch6", "ch7", "none"):
            raise ValueError("priors must be one of ch5, ch6, ch7, none")
        bad = set(self.estimate) - set(ESTIMATES)
        if bad:
            raise ValueError(f"estimate entries must be among {ESTIMATES}, got {sorted(bad)}")
        if "n_kappa" in self.estimate and len(self.geometry_deg) < 2:
            raise ValueError("estimating n and kappa needs at least two geometries")
        if not self.plates:
            raise ValueError("at least one [[plates]] entry is needed")
        return self


def default_scene() -> SceneConfig:
    """The bundled scene: painted aluminium and painted steel at 1550 nm, seven specular geometries."""
    return SceneConfig().validate()


def load_scene(path) -> SceneConfig:
    """Read a TOML scene description (module docstring); unknown keys raise ValueError naming them."""
    import tomllib

    data = tomllib.loads(Path(path).read_text())
    plates = [Plate(**p) for p in data.pop("plates", [])] or None
    known = set(SceneConfig.__dataclass_fields__)
    unknown = set(data) - known
    if unknown:
        raise ValueError(f"unknown scene keys {sorted(unknown)}; allowed: {sorted(known)}")
    cfg = SceneConfig(**data)
    if plates is not None:
        cfg.plates = plates
    return cfg.validate()
