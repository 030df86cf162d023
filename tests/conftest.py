import os

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")
os.environ.setdefault("SCATTERLAB_PROGRESS", "0")


@pytest.fixture
def rng():
    """A fixed-seed generator: statistical tests state their tolerance for this seed."""
    return np.random.default_rng(12345)
