"""Plotting helpers (matplotlib and pyvista are imported lazily, inside the functions).

Nothing in the physics imports this package. The studies (``scatterlab.studies``) and the reports
(characterization, inversion) share these helpers.
"""

from __future__ import annotations

import contextlib
import os
import sys

import numpy as np

from scatterlab.polarization import dolp as stokes_dolp

__all__ = ["headless_pyplot", "offscreen_plotter", "polar_contour", "pbrdf_lobe_png"]


def headless_pyplot():
    """``matplotlib.pyplot`` on the non-interactive Agg backend (files only, no display needed).

    Returns
    -------
    module
        ``matplotlib.pyplot``, imported on first use (matplotlib stays a lazy import).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as pyplot

    return pyplot


@contextlib.contextmanager
def offscreen_plotter(window_size=(700, 560)):
    """A pyvista ``Plotter`` that renders off screen, closed on exit.

    On a Linux machine without a display (no ``DISPLAY`` or ``WAYLAND_DISPLAY``), VTK first tries
    X, prints "bad X server connection" and then renders through EGL or OSMesa. That warning is not
    printed here; VTK's errors are, and a rendering that fails still raises.

    Parameters
    ----------
    window_size : tuple of int
        Image size ``(width, height)`` [pixels].

    Yields
    ------
    pyvista.Plotter
    """
    import pyvista as pv

    headless = sys.platform.startswith("linux") and not (
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
    )
    logger = None
    if headless:
        try:
            from vtkmodules.vtkCommonCore import vtkLogger as logger
        except ImportError:  # an older VTK without its logger
            logger = None
    if logger is not None:
        cutoff = logger.GetCurrentVerbosityCutoff()
        logger.SetStderrVerbosity(logger.VERBOSITY_ERROR)
    pl = pv.Plotter(off_screen=True, window_size=window_size)
    try:
        yield pl
    finally:
        pl.close()
        if logger is not None:
            logger.SetStderrVerbosity(cutoff)


def polar_contour(
    theta_r,
    phi,
    values,
    *,
    ax=None,
    fig=None,
    levels=20,
    cmap="viridis",
    label=None,
    vmin=None,
    vmax=None,
):
    """Filled contour of ``values(theta_r, phi)`` on a polar axis (radius theta_r in degrees).

    Parameters
    ----------
    theta_r, phi : 1-D arrays [rad] (grid axes)
    values : array, shape ``(theta_r.size, phi.size)``
    ax, fig : matplotlib axes (polar) and figure, created when omitted.

    Returns
    -------
    fig, ax
    """
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(subplot_kw={"projection": "polar"}, figsize=(4.2, 4))
    P, T = np.meshgrid(phi, np.degrees(theta_r))
    cs = ax.contourf(P, T, values, levels=levels, cmap=cmap, vmin=vmin, vmax=vmax)
    ax.set_rlim(0, 90)
    ax.set_rticks([30, 60, 90])
    if fig is not None:
        fig.colorbar(cs, ax=ax, shrink=0.75, label=label)
    return fig, ax


def pbrdf_lobe_png(
    model, eta, theta_i, path, *, n_theta=90, n_phi=180, window_size=(700, 560), title=None
):
    """Render the pBRDF lobe ``F00(theta_r, phi)`` as a 3-D surface coloured by DOLP and save a PNG.

    The surface point in direction ``(theta_r, phi)`` sits at radius ``F00 / max F00``; its colour
    is the DOLP of the scattered light for unpolarized illumination (NaN, pyvista's NaN colour,
    where no light is scattered). Off-screen pyvista rendering; returns the path.

    Parameters
    ----------
    model : pBRDF model
        Object with ``mueller_linear(eta, theta_i, theta_r, phi)`` returning ``(..., 4, 4)``.
    eta : complex or float
        Refractive index passed to the model.
    theta_i : float
        Incidence angle [rad].
    path : str or os.PathLike
        Output PNG file.
    n_theta, n_phi : int
        Number of samples in ``theta_r`` (0 to 89.5 deg) and ``phi`` (0 to 2 pi).
    window_size : tuple of int
        Image size ``(width, height)`` [pixels].
    title : str, optional
        Text drawn in the image.

    Returns
    -------
    str or os.PathLike
        ``path``, as given.
    """
    import pyvista as pv

    tr = np.linspace(0, np.radians(89.5), n_theta)
    ph = np.linspace(0, 2 * np.pi, n_phi)
    TR, PH = np.meshgrid(tr, ph, indexing="ij")
    F = model.mueller_linear(eta, np.full_like(TR, theta_i), TR, PH)
    f00 = F[..., 0, 0]
    dolp = stokes_dolp(
        F[..., :, 0]
    )  # unpolarized illumination: the first column; NaN where F00 = 0
    r = f00 / f00.max()
    x, y, z = r * np.sin(TR) * np.cos(PH), r * np.sin(TR) * np.sin(PH), r * np.cos(TR)
    grid = pv.StructuredGrid(x, y, z)
    grid["DOLP"] = dolp.ravel(order="F")
    with offscreen_plotter(window_size) as pl:
        pl.add_mesh(grid, scalars="DOLP", cmap="viridis", clim=(0, 1), smooth_shading=True)
        pl.add_mesh(pv.Disc(inner=0, outer=1.05, c_res=60), color="lightgrey", opacity=0.3)
        if title:
            pl.add_text(title, font_size=10)
        pl.camera_position = [(2.2, -2.6, 1.8), (0, 0, 0.25), (0, 0, 1)]
        pl.screenshot(str(path))
    return path
