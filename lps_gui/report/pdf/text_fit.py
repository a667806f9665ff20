"""Every string a report draws, measured against the box it is drawn in (the clipping check).

A PDF viewer shows a cell cut at its column while text extraction still
reads it whole ("not resolved" printed as "solved"), so the check is made
where the text is laid out: :func:`draw_text` measures the string with the
painter's font metrics on its device, draws it, and records a
:class:`DrawnText`; an entry whose text needs more room than its box is an
overflow, and every report's tests assert there is none. :func:`fit_widths`
widens table columns to their contents and :func:`fitting_size` shrinks a
one-line label's font until it fits. Qt is imported inside functions only.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

TOLERANCE = 0.02  # relative slack of a measured width against its box (sub-pixel rounding)
FONT_FAMILY = "DejaVu Sans"


def font(size_pt: float, bold: bool = False) -> Any:
    """The report's font at ``size_pt`` points (DejaVu Sans: full Unicode, prints well)."""
    from PySide6.QtGui import QFont

    f = QFont(FONT_FAMILY)
    f.setPointSizeF(size_pt)
    f.setBold(bold)
    f.setStyleHint(QFont.StyleHint.SansSerif)
    return f


@dataclass(frozen=True)
class DrawnText:
    """One drawn string: where (page, kind), its box and what it needed (device units)."""

    page: int
    where: str  # "table", "heading", "paragraph", "axis", "title", "legend", "footer", "caption", "picture"
    text: str
    room: tuple[float, float]  # box width, height
    need: tuple[float, float]  # measured width, height

    @property
    def overflow(self) -> bool:
        return (self.need[0] > self.room[0] * (1 + TOLERANCE) + 0.5
                or self.need[1] > self.room[1] * (1 + TOLERANCE) + 0.5)


@dataclass
class TextLog:
    """Every :class:`DrawnText` of one document; ``page`` is the page being painted."""

    page: int = 1
    texts: list[DrawnText] = field(default_factory=list)

    def overflows(self) -> list[DrawnText]:
        return [t for t in self.texts if t.overflow]

    def clipped(self) -> list[str]:
        """``"page N: text"`` of every string that does not fit its box (none in a good report)."""
        return [f"page {t.page}: {t.text}" for t in self.overflows()]

    def on_page(self, page: int) -> list[str]:
        return [t.text for t in self.texts if t.page == page]


def measure(painter: Any, rect: Any, flags: int, text: str) -> tuple[float, float]:
    """(width, height) ``text`` takes with the painter's font on its device, wrapped when ``flags`` say so."""
    from PySide6.QtCore import QRectF, Qt
    from PySide6.QtGui import QFontMetricsF

    fm = QFontMetricsF(painter.font(), painter.device())
    if flags & int(Qt.TextFlag.TextWordWrap):
        br = fm.boundingRect(QRectF(0, 0, rect.width(), 1e7), flags, text)
        return br.width(), br.height()
    lines = text.split("\n")
    return max(fm.horizontalAdvance(line) for line in lines), fm.height() * len(lines)


def draw_text(painter: Any, rect: Any, flags: int, text: str, log: TextLog | None, where: str) -> bool:
    """Draw ``text`` in ``rect`` and record it; returns True when it fits.

    A right-aligned (or centred) string wider than its box is drawn from the
    box's left edge, so what is lost, if anything, is its end and never its
    start; it is recorded as an overflow either way.
    """
    from PySide6.QtCore import Qt

    need = measure(painter, rect, int(flags), text)
    fits = need[0] <= rect.width() * (1 + TOLERANCE) + 0.5
    if not fits:
        horizontal = int(Qt.AlignmentFlag.AlignHorizontal_Mask)
        flags = (int(flags) & ~horizontal) | int(Qt.AlignmentFlag.AlignLeft)
    painter.drawText(rect, int(flags), text)
    entry = DrawnText(log.page if log is not None else 0, where, text, (rect.width(), rect.height()), need)
    if log is not None:
        log.texts.append(entry)
    return not entry.overflow


def fitting_size(painter: Any, text: str, width: float, size_pt: float, min_pt: float, bold: bool = False) -> float:
    """The largest font size from ``size_pt`` down to ``min_pt`` (0.5 pt steps) at which ``text`` fits ``width``."""
    from PySide6.QtGui import QFontMetricsF

    size = size_pt
    while size > min_pt and QFontMetricsF(font(size, bold), painter.device()).horizontalAdvance(text) > width:
        size -= 0.5
    return max(size, min_pt)


def fit_widths(widths: Sequence[float], need: Sequence[float], max_total: float) -> list[float]:
    """Column widths that hold ``need`` where possible: slack of other columns first, then up to ``max_total``.

    A column that still cannot hold its widest cell keeps what it got; its
    cells are wrapped by the caller.
    """
    w = [float(x) for x in widths]
    room = max(0.0, max_total - sum(w))
    short = [max(0.0, n - c) for n, c in zip(need, w)]
    deficit = sum(short)
    if deficit <= 0:
        return w
    slack = [max(0.0, c - n) for n, c in zip(need, w)]
    take = min(sum(slack), deficit)
    if take > 0:
        w = [c - take * s / sum(slack) for c, s in zip(w, slack)]
    extra = min(deficit - take, room)
    given = take + extra
    return [c + given * d / deficit for c, d in zip(w, short)]
