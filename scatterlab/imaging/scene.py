r"""Scenes: material, roughness and geometry maps rendered into linear Stokes images by the pBRDF.

Illumination is unpolarized, so only the first column of the pBRDF Mueller matrix is needed
(:math:`S = S_0^{in}(F_{00}, F_{10}, F_{20})`), and for observation in the specular plane only the closed form
of Eqs. 200-204 (:math:`F_{20} = 0`, AOP fixed at 0). Materials are evaluated once per label, not per pixel.
Lengths in pixels; angles in radians.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from scatterlab._checks import as_count, as_finite, as_rng, as_scalar
from scatterlab.pbrdf import Model

__all__ = ["Scene", "painted_plate", "render_stokes"]


@dataclass
class Scene:
    """A scene: ``labels`` (H, W) int map into ``materials`` (complex indices) and ``roughness`` (per label),
    seen at one geometry (theta_i, theta_r, phi) [rad]."""

    labels: np.ndarray
    materials: list
    roughness: list
    theta_i: float
    theta_r: float
    phi: float = np.pi
    names: list = field(default_factory=list)

    def __post_init__(self):
        self.labels = np.asarray(self.labels)
        if self.labels.ndim != 2:
            raise ValueError("labels must be a 2-D map")
        if len(self.materials) != len(self.roughness):
            raise ValueError("materials and roughness must have one entry per label")
        if self.labels.min() < 0 or self.labels.max() >= len(self.materials):
            raise ValueError("labels must index into materials")


# the letter template: rectangles (row0, row1, col0, col1) in units of 1/16 of the plate's width
_LETTERS = (
    (3, 4.2, 2, 7),
    (7, 8.2, 2, 7),
    (11, 12.2, 2, 7),  # "s": three horizontal strokes
    (3, 8, 2, 3.2),
    (7, 12, 5.8, 7),  # ... and its two vertical joints
    (2, 12.2, 10.5, 11.7),
    (5, 6.2, 8.5, 13.7),  # "t": the vertical stroke and the cross bar
)


def painted_plate(
    n: int = 256,
    *,
    metal: complex = 1.44 - 16j,
    paint: complex = 1.39 - 0.34j,
    metal_roughness: float = 0.15,
    paint_roughness: float = 0.3,
    theta: float = np.radians(50),
    scratches: int = 3,
    zoom: float = 1.0,
    center=(8.0, 8.0),
    rng=None,
) -> Scene:
    """A painted metal plate with bare-metal letter strokes ("s" and "t" as block strokes) and scratches, seen
    at theta_i = theta_r (the scenes of Figs. 47, 49-61). Defaults: aluminium and green paint at 1550 nm.

    Parameters
    ----------
    n : int
        Field size [pixels] (square), an integer >= 8.
    metal, paint : complex
        Indices ``n - j kappa``.
    metal_roughness, paint_roughness : float
        Per-axis rms facet slopes (scratches: a third of the metal's).
    theta : float
        Specular angle [rad].
    scratches : int
        Number of random straight scratches (about 1 pixel wide), >= 0.
    zoom : float
        Magnification of the letter template: 1 shows the whole "st" (letter strokes n/13 wide); 2 shows a
        field half as wide, e.g. the right side of the "s" and the left side of the "t" as in Figs. 49-52.
        A single number in [0.25, 16].
    center : (float, float)
        Field centre (row, column) in template units, two finite numbers (the template is 16 units wide;
        the "s" spans columns 2-7, the "t" 8.5-13.7).
    rng : optional
        Seeds the scratches.

    Returns
    -------
    Scene
        Labels 0 paint, 1 bare metal (letters), 2 scratches (bare metal, smoother); ``labels`` of shape
        ``(n, n)``.

    Raises
    ------
    ValueError
        ``n`` not an integer >= 8, ``zoom`` not a single number in [0.25, 16], ``scratches`` not an integer
        >= 0, ``center`` not two finite numbers, or a malformed ``rng``.
    """
    n = as_count(n, "n", 8, " [pixels]")
    zoom = as_scalar(zoom, "zoom", 0.25, 16.0)
    as_count(scratches, "scratches", 0)
    allowed = f"center must be (row, column), two finite numbers in template units, got {center!r}"
    try:
        centre = as_finite(center, "center")
    except ValueError:
        raise ValueError(allowed) from None
    if centre.shape != (2,):
        raise ValueError(allowed)
    cy, cx = float(centre[0]), float(centre[1])
    rng = as_rng(rng)
    u = n * zoom / 16  # pixels per template unit
    yy, xx = np.mgrid[0:n, 0:n]
    ty = (yy + 0.5 - n / 2) / u + cy
    tx = (xx + 0.5 - n / 2) / u + cx
    lab = np.zeros((n, n), int)
    for r0, r1, c0, c1 in _LETTERS:
        lab[(ty >= r0) & (ty < r1) & (tx >= c0) & (tx < c1)] = 1
    for _ in range(scratches):
        a = rng.uniform(0, np.pi)
        c = rng.uniform(0.2 * n, 0.8 * n, 2)
        d = np.abs((xx - c[0]) * np.sin(a) - (yy - c[1]) * np.cos(a))
        along = np.abs((xx - c[0]) * np.cos(a) + (yy - c[1]) * np.sin(a))
        lab[(d < 0.6) & (along < 0.3 * n)] = 2
    return Scene(
        lab,
        [paint, metal, metal],
        [paint_roughness, metal_roughness, metal_roughness / 3],
        theta,
        theta,
        np.pi,
        names=["paint", "metal", "scratch"],
    )


def render_stokes(
    scene: Scene, *, shadowing: str = "torrance-sparrow", diffuse: str = "hyde"
) -> np.ndarray:
    """Linear Stokes images of ``scene`` for unpolarized illumination.

    In the specular plane (``phi == pi``) uses the closed form (S2 = 0); otherwise the first column of the
    Mueller pBRDF. One evaluation per material label.

    Parameters
    ----------
    scene : Scene
    shadowing, diffuse : str
        Passed to :class:`scatterlab.pbrdf.Model`.

    Returns
    -------
    ndarray ``(H, W, 3)`` [1/sr per unit incident irradiance]: (S0, S1, S2), Stokes axis last.
    """
    out = np.zeros(scene.labels.shape + (3,))
    for k, (eta, sigma) in enumerate(zip(scene.materials, scene.roughness)):
        mask = scene.labels == k
        if not mask.any():
            continue
        model = Model(sigma, shadowing=shadowing, diffuse=diffuse)
        if scene.phi == np.pi:
            F = model.mueller(eta, scene.theta_i, scene.theta_r, np.pi)
        else:
            F = model.mueller_linear(eta, scene.theta_i, scene.theta_r, scene.phi)
        out[mask] = F[:3, 0]
    return out
