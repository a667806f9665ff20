"""Render the application icon's PNG sizes from ``resources/lps-gui.svg``.

Why a script: desktops, window managers and PyInstaller want raster icons in
fixed sizes, while the drawing lives in one hand-written SVG. The PNGs are
committed, so building or installing never needs this script; rerun it after
editing the SVG::

    QT_QPA_PLATFORM=offscreen .venv/bin/python packaging/render_icons.py
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

RESOURCES = Path(__file__).resolve().parent.parent / "resources"
SVG_NAME = "lps-gui.svg"
ICON_SIZES_PX = (16, 24, 32, 48, 64, 128, 256)


def png_name(size_px: int) -> str:
    """File name of the icon rendered at ``size_px`` x ``size_px`` pixels."""
    return f"lps-gui-{size_px}.png"


def render(svg_path: Path, out_dir: Path, sizes_px: tuple[int, ...] = ICON_SIZES_PX) -> list[Path]:
    """Render ``svg_path`` to one antialiased, transparent PNG per size.

    Parameters
    ----------
    svg_path : Path
        The icon drawing.
    out_dir : Path
        Folder receiving ``lps-gui-<size>.png``.
    sizes_px : tuple of int
        Square edge lengths in pixels.

    Returns
    -------
    list of Path
        The written files, in ``sizes_px`` order.
    """
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    from PySide6.QtCore import Qt
    from PySide6.QtGui import QGuiApplication, QImage, QPainter
    from PySide6.QtSvg import QSvgRenderer

    app = QGuiApplication.instance() or QGuiApplication(sys.argv[:1])  # noqa: F841 (keeps fonts alive)
    renderer = QSvgRenderer(str(svg_path))
    if not renderer.isValid():
        raise SystemExit(f"render_icons: {svg_path} is not a valid SVG; fix the drawing and rerun")
    written = []
    for size_px in sizes_px:
        image = QImage(size_px, size_px, QImage.Format.Format_ARGB32)
        image.fill(Qt.GlobalColor.transparent)
        painter = QPainter(image)
        painter.setRenderHint(QPainter.RenderHint.Antialiasing)
        painter.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform)
        renderer.render(painter)
        painter.end()
        path = out_dir / png_name(size_px)
        if not image.save(str(path), "PNG"):
            raise SystemExit(f"render_icons: cannot write {path}; check the folder is writable")
        written.append(path)
    return written


if __name__ == "__main__":
    for p in render(RESOURCES / SVG_NAME, RESOURCES):
        print(p.relative_to(RESOURCES.parent))
