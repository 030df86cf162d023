"""The end-to-end characterization pipeline (Ch. VII) and its scene descriptions; ``scatterlab characterize``."""

from scatterlab.characterization.pipeline import characterize
from scatterlab.characterization.scene_config import SceneConfig, default_scene, load_scene

__all__ = ["characterize", "SceneConfig", "default_scene", "load_scene"]
