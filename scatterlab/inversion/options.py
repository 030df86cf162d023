"""Option groups of the inversion entry points, and the legacy keywords that fill them.

:func:`~scatterlab.inversion.fit_dolp` groups its solver settings in :class:`FitOptions`;
:func:`~scatterlab.inversion.sample_posterior` its prior and sampler settings in
:class:`~scatterlab.inversion.PriorOptions` and :class:`~scatterlab.inversion.SamplerOptions`.
Each still takes the settings as plain keywords; :func:`resolve_options` sorts them.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from scatterlab._checks import as_positive

__all__ = ["MODEL_KEYS", "FitOptions", "resolve_options"]

MODEL_KEYS = ("shadowing", "diffuse", "distribution")  # keywords passed to scatterlab.pbrdf.Model
DEFAULT_STARTS = ((1.5, 0.05), (1.3, 3.0), (3.0, 4.0), (1.0, 10.0), (1.5, 18.0))
DEFAULT_SIGMA_STARTS = (0.05, 1.0)  # besides sigma0, when sigma is fitted (FitOptions.sigma_starts)


@dataclass(frozen=True)
class FitOptions:
    """Solver settings of :func:`~scatterlab.inversion.fit_dolp`.

    Attributes
    ----------
    bounds : dict or None
        ``{"n": (lo, hi), "kappa": (lo, hi), "sigma": (lo, hi)}``; missing names take
        :data:`~scatterlab.inversion.DEFAULT_BOUNDS`; another key is a ValueError.
    starts : non-empty sequence of (n, kappa)
        Starting points; every pixel runs from each and the lowest cost wins.
    sigma0 : float
        Starting roughness (rms slope, dimensionless, finite and > 0; clipped to the sigma
        bounds).
    sigma_starts : tuple of float
        Further starting roughnesses, each run from every (n, kappa) start when sigma is fitted
        (finite and > 0; clipped to the bounds); ``()`` keeps ``sigma0`` alone. From ``sigma0``
        alone, 113 of 400 noiseless pixels (n 1.1-4.5, kappa 0.01-20, sigma 0.02-1.2, five
        geometries 30-70 deg) stopped in a local minimum (DOLP residual 1e-5 to 1e-2, sigma off by
        more than 0.05 at 85); with the default 0.05 and 1.0 as well, 44 (29), at three times
        the run time (``tests/inversion/test_least_squares.py``). Sigma known: no effect.
    max_iter : int
        Levenberg-Marquardt iterations per start (>= 1).
    tol : float
        Relative cost decrease that ends the iteration (finite and > 0).
    """

    bounds: dict | None = None
    starts: tuple = DEFAULT_STARTS
    sigma0: float = 0.3
    sigma_starts: tuple = DEFAULT_SIGMA_STARTS
    max_iter: int = 200
    tol: float = 1e-12

    def validate(self) -> None:
        """Raise a ValueError naming ``sigma0``, ``sigma_starts``, ``max_iter`` or ``tol`` when out of
        range."""
        if np.ndim(self.sigma0) != 0:
            raise ValueError(f"sigma0 must be a single float > 0, got {self.sigma0!r}")
        as_positive(self.sigma0, "sigma0")
        try:
            extra = np.asarray(self.sigma_starts, float)
        except (TypeError, ValueError):
            extra = None
        if extra is None or extra.ndim != 1:
            raise ValueError(
                f"sigma_starts must be a sequence of floats > 0, got {self.sigma_starts!r}"
            )
        as_positive(extra, "sigma_starts")
        if isinstance(self.max_iter, bool) or not (
            isinstance(self.max_iter, (int, np.integer)) and self.max_iter >= 1
        ):
            raise ValueError(f"max_iter must be an integer >= 1, got {self.max_iter!r}")
        if np.ndim(self.tol) != 0:
            raise ValueError(f"tol must be a single float > 0, got {self.tol!r}")
        as_positive(self.tol, "tol")


def resolve_options(kw: dict, groups: dict, extra_keys=MODEL_KEYS):
    """Sort keywords into option dataclasses; the rest must be ``extra_keys``.

    Parameters
    ----------
    kw : dict
        The caller's keywords; consumed (the option names are popped).
    groups : dict
        ``{label: (cls, given)}``: the dataclass of each group and the instance the caller gave
        (``label=cls(...)``) or None. Giving a field both inside the instance and as a keyword is a
        ValueError, as is an instance of another type.
    extra_keys : sequence of str
        The other keywords allowed (by default the pBRDF model's).

    Returns
    -------
    list
        One instance per group (in the order of ``groups``), then the dict of extra keywords.
    """
    out = []
    for label, (cls, given) in groups.items():
        names = {f.name for f in fields(cls)}
        picked = {k: kw.pop(k) for k in list(kw) if k in names}
        if given is not None and picked:
            raise ValueError(
                f"give {sorted(picked)} either inside {label}={cls.__name__}(...) or as keywords, "
                "not both"
            )
        if given is not None and not isinstance(given, cls):
            raise ValueError(f"{label} must be a {cls.__name__}, got {type(given).__name__}")
        out.append(given if given is not None else cls(**picked))
    unknown = sorted(set(kw) - set(extra_keys))
    if unknown:
        allowed = sorted(
            {f.name for cls, _ in groups.values() for f in fields(cls)} | set(extra_keys)
        )
        raise ValueError(f"unknown keyword(s) {unknown}; allowed: {allowed}")
    return out + [dict(kw)]
