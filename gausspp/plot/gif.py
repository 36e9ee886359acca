"""Saving an animation as a GIF with one render of the still parts: the moving artists blitted over them.

matplotlib's ``Animation.save`` redraws the whole figure twice a frame (axes, ticks, grid and text included),
about 0.1 s a panel on a shared machine. Here the still parts are rendered once, copied
(``canvas.copy_from_bbox``), and each frame restores them and draws only what moves (``Artist.draw`` through
``Figure.draw_artist``) before its pixels are handed to pillow, which writes the GIF.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import GaussppError


def _pillow() -> Any:
    try:
        from PIL import Image
    except ImportError:
        raise GaussppError("plot.animate: a .gif needs pillow: pip install 'gausspp[plots]'") from None
    return Image


def save_gif(fig: Any, update: Callable[[int], list[Any]], frames: int, out: str | Path, fps: int, dpi: int) -> None:
    """Render ``frames`` frames of ``fig`` (``update(k)`` sets frame ``k`` and returns the artists that move)
    at ``dpi`` and write them to ``out`` as a looping GIF at ``fps`` frames per second."""
    image = _pillow()
    fig.set_dpi(dpi)
    moving = update(0)
    for artist in moving:
        artist.set_animated(True)
    fig.canvas.draw()  # everything that does not move
    background = fig.canvas.copy_from_bbox(fig.bbox)
    pictures = []
    try:
        for k in range(frames):
            fig.canvas.restore_region(background)
            for artist in update(k):
                artist.set_animated(True)
                fig.draw_artist(artist)
            rgba = np.asarray(fig.canvas.buffer_rgba())
            pictures.append(image.fromarray(rgba[..., :3].copy()).quantize(colors=64))
    finally:
        for artist in update(0):
            artist.set_animated(False)
    duration = max(int(round(1000.0 / fps)), 20)
    pictures[0].save(str(out), save_all=True, append_images=pictures[1:], duration=duration, loop=0)
