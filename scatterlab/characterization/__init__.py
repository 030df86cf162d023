"""The end-to-end characterization pipeline (Ch. VII) and its scene descriptions; ``scatterlab characterize``.

Stages: :mod:`acquisition` -> :mod:`restoration` -> :mod:`registration` -> :mod:`estimation` -> :mod:`metrics`
-> :mod:`report`, orchestrated by :func:`characterize` (:mod:`pipeline`); :class:`Ideal` replaces stages by
their ideal versions for the error budget.
"""

from scatterlab.characterization.acquisition import Acquisition, Ideal, acquire
from scatterlab.characterization.pipeline import characterize, observe, run_plate
from scatterlab.characterization.scene_config import Plate, SceneConfig, default_scene, load_scene

__all__ = [
    "characterize",
    "observe",
    "run_plate",
    "acquire",
    "Acquisition",
    "Ideal",
    "SceneConfig",
    "Plate",
    "default_scene",
    "load_scene",
]
