"""Visual prompting: the letters of prompt points drawn on the image, as Explore until Confident
does, so a real VLM can be asked "which direction (black letters on the image)".

Black letters on a white disc stand out on any scene; the disc scales with the image so the letters
stay legible after a model's processor downsizes the frame.
"""

from __future__ import annotations

import numpy as np
from PIL import Image, ImageDraw, ImageFont

_DISC_SHARE = 0.035  # disc radius as a share of the image's longer side


def draw_marks(rgb: np.ndarray, marks: dict[str, tuple[float, float]]) -> np.ndarray:
    """A copy of the HxWx3 uint8 ``rgb`` with each letter drawn centred at its (u, v) pixel.

    Args:
        rgb: the image.
        marks: each letter's pixel (u, v).

    Returns:
        The marked copy.
    """
    if not marks:
        return rgb.copy()
    image = Image.fromarray(np.ascontiguousarray(rgb, dtype=np.uint8))
    radius = max(7, round(_DISC_SHARE * max(image.size)))
    font = ImageFont.load_default(size=round(1.4 * radius))
    draw = ImageDraw.Draw(image)
    for letter, (u, v) in marks.items():
        draw.ellipse((u - radius, v - radius, u + radius, v + radius), fill="white", outline="black")
        draw.text((u, v), letter, fill="black", font=font, anchor="mm")
    return np.asarray(image).copy()
