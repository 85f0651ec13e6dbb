"""The RGB-D encoder (CenterArt's first half): configuration, network, losses, read-out, checkpoints.

Layout follows LeRobot's policy folders: ``config.py`` (presets), ``network.py`` (the module), ``losses.py``,
``readout.py`` (maps -> detected objects), ``inputs.py`` (letterboxing with intrinsics), ``checkpoint.py``.
"""

from centerart.models.encoder.config import PRESETS, EncoderConfig
from centerart.models.encoder.network import EncoderOutput, RGBDEncoder

__all__ = ["PRESETS", "EncoderConfig", "EncoderOutput", "RGBDEncoder"]
