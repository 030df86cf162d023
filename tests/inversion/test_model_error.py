"""The pBRDF's DOLP model-error term (scatterlab.inversion.model_error).

The coverage test inverts exact (MoM) DOLP that the shipped table was NOT built from: the study
``dolp_vs_mom`` splits its realizations in halves, the table comes from the first half and
``data/dolp_mom_heldout.npz`` holds the specular DOLP (30-60 deg) of the second half.
"""

import warnings
from pathlib import Path

import numpy as np
import pytest

from scatterlab.inversion import (
    dolp_model_error,
    dolp_model_error_covariance,
    fit_dolp,
    sample_posterior,
)
from scatterlab.inversion.model_error import model_error_table

HELDOUT = Path(__file__).parent / "data" / "dolp_mom_heldout.npz"
TH = np.radians([30.0, 40.0, 50.0, 60.0])


def test_table_is_finite_and_shapes_broadcast():
    t = model_error_table()
    err = t["error"]
    assert err.ndim == 4 and np.all(np.isfinite(err)) and np.all(err >= 0)
    e = dolp_model_error(TH[:, None], TH[:, None], np.array([0.1, 0.3, 0.6]), 1.5)
    assert e.shape == (4, 3) and np.all(np.isfinite(e)) and np.all(e >= 0)


def test_unknown_material_or_roughness_takes_the_largest_error():
    t = model_error_table()
    for eta in t["eta"]:
        for s in t["slopes"]:
            known = dolp_model_error(TH, TH, s, eta)
            assert np.all(dolp_model_error(TH, TH, s, None) >= known - 1e-15)
            assert np.all(dolp_model_error(TH, TH, None, eta) >= known - 1e-15)


def test_table_nodes_are_reproduced_and_outside_is_clamped():
    t = model_error_table()
    k, j, i = 0, 0, 2
    s_idx = int(np.argmin(np.abs(t["theta_s"] - t["theta_i"][i])))
    ti, ts = t["theta_i"][i], t["theta_s"][s_idx]
    assert dolp_model_error(ti, ts, t["slopes"][j], t["eta"][k]) == pytest.approx(
        t["error"][k, j, i, s_idx], rel=1e-12
    )
    # clamped: below the smallest tabulated incidence and slope, the edge values
    lo = dolp_model_error(0.0, t["theta_i"][0], 0.01, t["eta"][k])
    edge = dolp_model_error(t["theta_i"][0], t["theta_i"][0], t["slopes"][0], t["eta"][k])
    assert lo == pytest.approx(edge, rel=1e-12)


def test_rms_over_heights_lies_between_the_largest_and_the_largest_over_root_h():
    """The rms of H values lies in [max / sqrt(H), max]; the study simulates at most 3 heights
    per slope (its CELLS), so the two tabulated statistics must obey that on every entry."""
    t = model_error_table()
    mx, rms = t["error"], t["error_rms"]
    assert rms.shape == mx.shape and np.all(np.isfinite(rms)) and np.all(rms >= 0)
    assert np.all(rms <= mx * (1 + 1e-12))
    assert np.all(rms >= mx / np.sqrt(3) * (1 - 1e-12))


def test_a_known_class_takes_the_largest_error_over_its_own_materials():
    """Metal means n < kappa (negative real permittivity): iron and aluminium; dielectric: glass
    and paint. The class's term is the largest over exactly those, and never above the term for
    an unknown material."""
    t = model_error_table()
    metal = [e for e in t["eta"] if e.real < -e.imag]
    dielectric = [e for e in t["eta"] if e.real >= -e.imag]
    assert len(metal) == 2 and len(dielectric) == 2
    for s in t["slopes"]:
        for cls, members in (("metal", metal), ("dielectric", dielectric)):
            got = dolp_model_error(TH, TH, s, material_class=cls)
            want = np.max([dolp_model_error(TH, TH, s, e) for e in members], 0)
            np.testing.assert_allclose(got, want, rtol=1e-12)
            assert np.all(got <= dolp_model_error(TH, TH, s) + 1e-15)
    C = dolp_model_error_covariance(TH, TH, 0.3, material_class="metal")
    assert np.allclose(np.diag(C), dolp_model_error(TH, TH, 0.3, material_class="metal") ** 2)


def test_covariance_is_symmetric_psd_with_the_variances_on_its_diagonal():
    C = dolp_model_error_covariance(TH, TH, 0.3, 3.6 - 5.88j)
    t = dolp_model_error(TH, TH, 0.3, 3.6 - 5.88j)
    assert np.allclose(C, C.T) and np.allclose(np.diag(C), t**2)
    assert np.min(np.linalg.eigvalsh(C)) > -1e-12


def test_bad_input():
    with pytest.raises(ValueError, match="phi"):
        dolp_model_error(TH, TH, 0.3, 1.5, phi=np.pi / 2)
    with pytest.raises(ValueError, match="theta_i"):
        dolp_model_error(-0.1, 0.3, 0.3)
    with pytest.raises(ValueError, match="sigma"):
        dolp_model_error(0.3, 0.3, -1.0)
    with pytest.raises(ValueError, match="eta"):
        dolp_model_error(0.3, 0.3, 0.3, 1.5 + 0.1j)
    with pytest.raises(ValueError, match="material_class"):
        dolp_model_error(0.3, 0.3, 0.3, material_class="semiconductor")
    with pytest.raises(ValueError, match="not both"):
        dolp_model_error(0.3, 0.3, 0.3, 1.5, material_class="dielectric")
    with pytest.raises(ValueError, match="correlation"):
        dolp_model_error_covariance(TH, TH, 0.3, correlation=0.0)


def _coverage(noise=0.005, draws=4, seed=0):
    """Fraction of (material, cell, noise draw) whose 95 % Laplace intervals of fit_dolp cover the
    true (n, kappa), without the model-error term and with it as a covariance across geometries,
    for a pipeline that knows neither the material nor the roughness (sigma = eta = None: the
    largest tabulated error; specular DOLP does not determine sigma, Fig. 58, so a fitted sigma
    cannot select the error)."""
    z = np.load(HELDOUT)
    th = np.radians(z["theta_deg"])
    rng = np.random.default_rng(seed)
    C = dolp_model_error_covariance(th, th) + noise**2 * np.eye(th.size)
    hits = {"without": [], "with": []}
    for eta, rows in zip(z["eta"], z["dolp"]):
        truth = np.array([eta.real, -eta.imag])
        y = np.clip(np.abs(rows[None] + noise * rng.standard_normal((draws,) + rows.shape)), 0, 1)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fits = {
                "without": fit_dolp(y, th, th, noise=noise),
                "with": fit_dolp(y, th, th, covariance=C),
            }
        for key, f in fits.items():
            p = np.stack([f.n, f.kappa], -1)
            ok = ~(np.abs(p - truth) > 1.96 * f.errors[..., :2])  # NaN: undetermined, infinite
            hits[key].append(ok.all(-1).ravel())
    return {k: float(np.mean(np.concatenate(v))) for k, v in hits.items()}


def test_exact_solution_dolp_is_covered_only_with_the_model_error_term():
    """Held-out MoM DOLP (4 materials x 8 roughness cells, 30-60 deg specular) plus noise 0.005.
    Without the term the intervals miss the truth in most cases (measured 31 %); with it the
    pooled coverage is at the nominal 95 % (measured 96 % with the table of the largest error
    over the heights, 95 % with the first, rms, table). Tolerance: the 32 cells are the
    independent units, binomial sd 0.04 at 95 %: >= 0.85 is 2.5 sd; <= 0.6 without."""
    cov = _coverage()
    assert cov["without"] <= 0.6
    assert cov["with"] >= 0.85


def test_the_term_plugs_into_sample_posterior():
    """The output is the ``systematic`` of sample_posterior: the likelihood's error per geometry
    becomes sqrt(noise^2 + t^2)."""
    z = np.load(HELDOUT)
    th = np.radians(z["theta_deg"])
    y = np.clip(np.abs(z["dolp"][0, 0]), 0, 1)
    t = dolp_model_error(th, th, 0.3, z["eta"][0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = sample_posterior(
            y, th, th, 0.005, 1, systematic=t, n_walkers=8, n_ensembles=1, n_steps=40
        )
    assert np.allclose(post.data_error(), np.sqrt(0.005**2 + t**2))
    assert np.all(np.isfinite(post.samples))


def test_aluminium_is_covered_by_the_sampled_posterior_with_the_independent_term():
    """The pipeline's form (characterization.region_posteriors with model_error=True): sigma
    known, material unknown, ``systematic = dolp_model_error(th, th, sigma)``, emcee. Held-out
    aluminium DOLP (8 roughness cells) plus noise 0.01: the 95 % credible intervals hold the
    true (n, kappa) = (1.44, 16) in every cell (measured 8 of 8; the Laplace intervals of fit_dolp
    with the same term held it in 71 % of the study's cases: a metal's kappa posterior spans most
    of the prior, far from Gaussian). Tolerance: 8 independent cells, >= 7 of 8 (at a true rate
    of 95 % the chance of 6 or fewer is 6 %)."""
    z = np.load(HELDOUT)
    th = np.radians(z["theta_deg"])
    k = int(np.flatnonzero(z["materials"] == "aluminium")[0])
    eta = z["eta"][k]
    truth = np.array([eta.real, -eta.imag])
    rng = np.random.default_rng(4)
    y = np.clip(np.abs(z["dolp"][k] + 0.01 * rng.standard_normal(z["dolp"][k].shape)), 0, 1)
    hits = []
    for row, (slope, _) in zip(y, z["cells"]):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            post = sample_posterior(
                row,
                th,
                th,
                0.01,
                rng,
                sigma=slope,
                systematic=dolp_model_error(th, th, slope),
                n_walkers=16,
                n_ensembles=1,
                n_steps=300,
                moves="de",
            )
        lo, hi = post.interval(0.95)[:, :2]
        hits.append(bool(np.all((lo <= truth) & (truth <= hi))))
    assert sum(hits) >= 7, hits


def test_the_80_deg_row_leaves_the_pipelines_30_to_60_deg_unchanged():
    """The table reaches 80 deg (longer surfaces, see the study); between 30 and 60 deg the
    interpolation never reaches that row, so the pipeline's term is the same as without it."""
    t = model_error_table()
    assert np.degrees(t["theta_i"][-1]) == pytest.approx(80.0)
    cut = dict(t, theta_i=t["theta_i"][:-1], error=t["error"][:, :, :-1])
    for s in (None, 0.1, 0.3, 0.6):
        assert np.array_equal(
            dolp_model_error(TH, TH, s, table=t), dolp_model_error(TH, TH, s, table=cut)
        )
    # at 80 deg the 80 deg row, not the 70 deg one clamped
    s_idx = int(np.argmin(np.abs(t["theta_s"] - t["theta_i"][-1])))
    at80 = dolp_model_error(t["theta_i"][-1], t["theta_s"][s_idx], 0.3, 1.5, table=t)
    assert at80 == pytest.approx(t["error"][0, 1, -1, s_idx], rel=1e-12)
    assert np.all(np.isfinite(t["error"][:, :, -1])) and np.all(t["error"][:, :, -1] >= 0)
