"""The JPEG a model is sent for a frame (Pillow, imported by the first JPEG only)."""

from __future__ import annotations

import io

import numpy as np
from PIL import Image


def encode_jpeg(frame: np.ndarray, quality: int) -> bytes:
    """``frame`` as the JPEG at ``quality`` the model is sent."""
    out = io.BytesIO()
    Image.fromarray(frame).save(out, format="JPEG", quality=quality)
    return out.getvalue()
