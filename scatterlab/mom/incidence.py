r"""Incident fields for the TM (E_z, s-polarized) problem, time dependence exp(+j w t).

* :class:`PlaneWave` -- :math:`\psi = e^{-jk\hat k_i\cdot\mathbf r}`, :math:`\hat k_i = (\sin\theta, -\cos\theta)`
  (Eq. 178: travelling down onto the surface, theta from the vertical, positive x forward).
* :class:`TaperedWave` -- Thorsos's tapered wave (Ref. 125, J. Acoust. Soc. Am. 83, 78 (1988)), the plane
  wave limited by a Gaussian taper of width ``g`` with the first-order correction that makes it satisfy the
  Helmholtz equation to :math:`O((kg\cos\theta)^{-2})`:

  .. math:: \psi = e^{-jk(x\sin\theta - y\cos\theta)(1 + w)}\, e^{-(x + y\tan\theta)^2/g^2},\quad
            w = \frac{2(x + y\tan\theta)^2/g^2 - 1}{(kg\cos\theta)^2}

  (x measured from the taper's centre ``x0``, which also is the phase reference). The power it
  carries down through a horizontal line is

  .. math:: P_{inc} = g\sqrt{\pi/2}\,\cos\theta\left[1 - \frac{1 + 2\tan^2\theta}{2k^2g^2\cos^2\theta}\right]

  (in units of :math:`|\psi|^2` x length), the normalisation of the scattering coefficient (errata to
  Eq. 183, which omits the cosine and the correction). ``correction=False`` gives the plain Gaussian window
  of Eq. 182, allowed only where the correction is negligible (:math:`(kg\cos\theta)^{-2} < 10^{-3}`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scatterlab._checks import as_positive

__all__ = ["PlaneWave", "TaperedWave"]

G_MAX = 1e300  # widest taper [m]: g sqrt(pi/2) (the incident power) stays finite
KGC_MAX = 1e150  # largest k g cos(theta): its square (the taper's correction) stays finite


def _check_real(value, name: str) -> None:
    """ValueError naming ``name`` unless ``value`` is one real number (not a string or bool)."""
    kind = np.asarray(value).dtype.kind if np.ndim(value) == 0 else None
    if kind not in ("i", "u", "f"):
        raise ValueError(f"{name} must be a real number, got {value!r}")


@dataclass(frozen=True)
class PlaneWave:
    """Plane wave incident at ``theta`` [rad] from the vertical (|theta| < pi/2 for surfaces; any for bodies)."""

    theta: float

    def __post_init__(self):
        _check_real(self.theta, "theta")
        if not np.isfinite(self.theta) or abs(self.theta) > 2 * np.pi:
            raise ValueError(
                f"theta must be a finite angle in [-2 pi, 2 pi] rad, got {self.theta!r}"
            )

    def check(self, k: float, length: float | None = None, extent=None) -> None:
        """On an open surface (``length`` given) the wave must come from above: |theta| < pi/2."""
        if length is not None and not abs(self.theta) < np.pi / 2:
            raise ValueError(
                f"theta must be in (-pi/2, pi/2) rad for an open surface, got {self.theta!r}"
            )

    def incident_power(self, k: float) -> float:
        """A plane wave carries infinite power onto an open surface: use :class:`TaperedWave` instead."""
        raise ValueError(
            "a PlaneWave has no finite incident power: scattering coefficients and energies need a "
            "TaperedWave on an open surface (use echo_width or far_field for a plane wave)"
        )

    def direction(self):
        return np.array([np.sin(self.theta), -np.cos(self.theta)])

    def field(self, x, y, k):
        d = self.direction()
        return np.exp(-1j * k * (d[0] * x + d[1] * y))

    def normal_derivative(self, x, y, nx, ny, k):
        d = self.direction()
        return -1j * k * (d[0] * nx + d[1] * ny) * self.field(x, y, k)


@dataclass(frozen=True)
class TaperedWave:
    """Thorsos's tapered plane wave: incidence ``theta`` [rad], taper half-width ``g`` [m], centre ``x0`` [m].

    Parameters
    ----------
    theta : float
        Incidence angle in (-pi/2, pi/2) [rad] from the vertical.
    g : float
        Taper half-width [m], finite, > 0 and at most 1e300 (:data:`G_MAX`); :meth:`check` and
        :meth:`incident_power` also need ``k g cos(theta) <= 1e150`` (:data:`KGC_MAX`, about
        1.6e149 wavelengths), beyond which the taper's correction term overflows.
    x0 : float
        Taper centre [m], finite.
    correction : bool
        Thorsos's first-order correction (module docstring); False is the plain Gaussian window.
    """

    theta: float
    g: float
    x0: float = 0.0
    correction: bool = True

    def __post_init__(self):
        for name in ("theta", "g", "x0"):
            _check_real(getattr(self, name), name)
        if not -np.pi / 2 < self.theta < np.pi / 2:
            raise ValueError(
                f"theta must be in (-pi/2, pi/2) rad (-90, 90 deg) for a tapered wave, got "
                f"{self.theta!r}"
            )
        if not (np.isfinite(self.g) and 0 < self.g <= G_MAX):
            raise ValueError(
                f"g (taper width) must be finite, > 0 and <= {G_MAX:g} [m], got {self.g!r}"
            )
        if not np.isfinite(self.x0):
            raise ValueError(
                f"x0 (taper centre) must be a finite position [m] on the surface, got {self.x0!r}"
            )

    def check(self, k: float, length: float | None = None, extent=None) -> None:
        """Raise ValueError when the taper is too narrow for the angle, the surface too short for the taper,
        or (``extent = (x_first, x_last)`` of the pulse centres) the taper centre ``x0`` off the surface or
        closer than 1.9 g to one of its ends."""
        kgc = self._kgc(k)
        if kgc < 10:
            g_min = 10 / (k * np.cos(self.theta))
            raise ValueError(
                f"taper too narrow for theta = {np.degrees(self.theta):.1f} deg: k g cos(theta) = "
                f"{kgc:.2f} < 10; use g >= {g_min:.4g} (the wavelength's unit; a longer surface may be needed)"
            )
        corr = (1 + 2 * np.tan(self.theta) ** 2) / (2 * kgc**2)
        if corr > 0.02:
            g_min = np.sqrt((1 + 2 * np.tan(self.theta) ** 2) / 0.04) / (k * np.cos(self.theta))
            raise ValueError(
                f"taper too narrow for theta = {np.degrees(self.theta):.1f} deg: the tapered wave's power "
                f"correction (1 + 2 tan^2)/(2 (k g cos)^2) = {corr:.3f} exceeds 0.02 (energy errors of "
                f"several percent); use g >= {g_min:.4g} (the wavelength's unit) and a surface of at least 4 g"
            )
        if not self.correction and kgc**-2 > 1e-3:
            raise ValueError(
                f"the plain Gaussian window (Eq. 182) needs (k g cos(theta))^-2 < 1e-3, got {kgc**-2:.2g}: "
                "use correction=True (Thorsos) or a wider g"
            )
        if length is not None and length < 4 * self.g * (1 - 1e-9):
            raise ValueError(
                f"surface of length {length:.4g} m too short for taper g = {self.g:.4g} m: need "
                f"length >= 4 g (g <= {length / 4:.4g} m), or the taper is cut at its edges"
            )
        if extent is not None:
            lo, hi = float(extent[0]), float(extent[1])
            half = 0.5 * (hi - lo) / max(1, extent[2] - 1) if len(extent) > 2 else 0.0
            lo, hi = lo - half, hi + half  # the ends of the first and last pulses
            if not lo <= self.x0 <= hi:
                raise ValueError(
                    f"x0 = {self.x0:.6g} m (taper centre) is off the surface [{lo:.6g}, {hi:.6g}] m"
                )
            if min(self.x0 - lo, hi - self.x0) < 1.9 * self.g:
                raise ValueError(
                    f"x0 = {self.x0:.6g} m puts the taper (g = {self.g:.4g} m) within 1.9 g of an end "
                    f"of the surface [{lo:.6g}, {hi:.6g}] m: centre it (x0 in "
                    f"[{lo + 1.9 * self.g:.6g}, {hi - 1.9 * self.g:.6g}] m)"
                )

    def _kgc(self, k) -> float:
        """``k g cos(theta)``, a ValueError naming g beyond :data:`KGC_MAX` (its square overflows)."""
        k = float(as_positive(k, "k"))
        c = float(np.cos(self.theta))
        kgc = k * float(self.g) * c  # Python floats: inf on overflow, never a warning
        if not kgc <= KGC_MAX:
            raise ValueError(
                f"g (taper width) = {self.g:.4g} m is too wide for k = {k:.4g} rad/m: k g cos(theta) "
                f"= {kgc:.3g} must be <= {KGC_MAX:g} (g <= {KGC_MAX / (k * c):.4g} m, in the "
                "wavelength's unit), beyond which the taper's correction overflows"
            )
        return kgc

    def _parts(self, x, y, k):
        t = np.tan(self.theta)
        c = np.cos(self.theta)
        u = (x - self.x0) + y * t
        w = (2 * u * u / self.g**2 - 1) / (k * self.g * c) ** 2 if self.correction else 0.0
        phase = -k * ((x - self.x0) * np.sin(self.theta) - y * c)  # phase referred to the centre
        return u, w, phase

    def field(self, x, y, k):
        u, w, phase = self._parts(x, y, k)
        return np.exp(1j * phase * (1 + w)) * np.exp(-u * u / self.g**2)

    def normal_derivative(self, x, y, nx, ny, k):
        """d psi / dn by the chain rule of the closed form (exact for the tapered field as written)."""
        t, c, s = np.tan(self.theta), np.cos(self.theta), np.sin(self.theta)
        u, w, phase = self._parts(x, y, k)
        psi = self.field(x, y, k)
        # grad u = (1, tan); grad(phase) = (-k sin, k cos); grad w = 4 u / g^2 / (k g cos)^2 * grad u
        dw = 4 * u / self.g**2 / (k * self.g * c) ** 2 if self.correction else 0.0 * u
        gx = 1j * (-k * s * (1 + w) + phase * dw) - 2 * u / self.g**2
        gy = 1j * (k * c * (1 + w) + phase * dw * t) - 2 * u / self.g**2 * t
        return (gx * nx + gy * ny) * psi

    def incident_power(self, k: float) -> float:
        """Power through a horizontal line, g sqrt(pi/2) cos(theta) [1 - (1 + 2 tan^2)/(2 k^2 g^2 cos^2)]."""
        kgc = self._kgc(k)
        if kgc < 0.5:  # corr >= 2 below: check raises (too narrow), as it did for corr >= 1
            self.check(k)  # before (k g cos)^2 underflows to 0
        c, t = np.cos(self.theta), np.tan(self.theta)
        corr = (1 + 2 * t * t) / (2 * kgc**2) if self.correction else 0.0
        if corr >= 1:
            # the expansion's correction exceeds its leading term: no finite positive power
            self.check(k)
        return float(self.g * np.sqrt(np.pi / 2) * c * (1 - corr))
