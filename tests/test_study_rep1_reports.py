"""Tables 4-5 and Figs. 41-42: report sentences generated from the numbers (issue 19).

Hand-made numbers, each chosen so that the old fixed wording would have been wrong.
"""

import importlib

import numpy as np
import pytest

from scatterlab import study_runner

STUDIES = study_runner.discover()  # mounts this checkout's studies/ as scatterlab.studies
_common = importlib.import_module("scatterlab.studies._common")
T4 = STUDIES["table4"].module
T5 = STUDIES["table5"].module
T5S = STUDIES["table5_synthetic"].module


def test_table5_no_case_reaching_2x_is_not_called_the_other_cases():
    # the old text said "NOT reproduced in the other cases" when none was reproduced
    assert T5._shrink_text(0, 4) == "NOT reproduced in any case. "
    assert T5._shrink_text(1, 4) == "Reproduced in 1 of 4 cases, NOT in the other 3. "
    assert T5._shrink_text(4, 4) == "Reproduced in all 4 cases. "


def test_table5_synthetic_quick_mode_does_not_judge():
    # 30 pixels: a band sqrt(2000 / 30) = 8 x the full run's; 1 of 6 inside was called "partly"
    verdict, text = T5S._verdict(1, 6, 30, quick=True)
    assert verdict == "not reproduced"
    assert "cannot judge" in text and "8 x wider" in text
    assert T5S._verdict(1, 6, 2000, quick=False)[0] == "partly"
    assert T5S._verdict(0, 6, 2000, quick=False)[0] == "not reproduced"
    assert T5S._verdict(6, 6, 2000, quick=False)[0] == "reproduced"


def test_table4_metal_share_mismatch_is_stated():
    implied = {"aluminium": 0.40, "steel": 0.49}
    text = T4._share_text({"aluminium": 0.328, "steel": 0.269}, implied)
    assert "not like for like" in text and "aluminium, steel" in text
    text = T4._share_text({"aluminium": 0.38, "steel": 0.269}, implied)
    assert "for steel, so there" in text
    assert "matches" in T4._share_text({"aluminium": 0.41, "steel": 0.47}, implied)


def test_table4_uncertainty_with_one_screen_is_the_binomial_error():
    # p = 0.4 over 1600 pixels: sqrt(0.24 / 1600) = 0.01225
    assert T4._binomial_u(0.4, np.ones(1600, bool)) == pytest.approx(0.012247, rel=1e-4)


def test_fig42_chain_accuracy_is_the_computed_d_eta():
    # flame-sprayed Al: literature 1.226 - j10.413, published fit 0.8886 - j3.4602:
    # shift |(-0.3374) + 6.9528j| = 6.961
    text = _common._chain_accuracy_text(1.5e-2, 1.226 - 10.413j, "0.8886 - j3.4602")
    assert "|d eta| = 1.5e-02" in text and "= 7" in text and "far smaller" in text
    assert "a few 1e-3" not in text
    assert "not smaller" in _common._chain_accuracy_text(8.0, 1.226 - 10.413j, "0.8886 - j3.4602")
