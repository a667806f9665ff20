"""The light field tab's content (issue 38) as plain data: a light-field folder's numbers and its EPIs.

A light field is a document of its own in a folder (lightfield.json, the EPI pictures, its report.pdf), not a
section of results.json: its registry entry (:data:`lps_gui.report.registry.FOLDER_SECTIONS`) names the file
that marks such a folder and this content, which the results dock draws. The numbers are the report page's
(:func:`lps_gui.report.pdf.lightfield.epipolar_rows`: formatted once). No Qt here.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

from lps_gui.errors import InputError
from lps_gui.io.jsonfile import read_json
from lps_gui.report.pages.content import SectionContent

LIGHTFIELD_FILE = "lightfield.json"
EPI_FILES = (("epi_before.png", "Epipolar-plane image before rectification"),
             ("epi_after.png", "After rectification: every scene point a straight line, rows level"))


def has_lightfield(folder: Path) -> bool:
    """Whether ``folder`` holds a light field (written by `lps lightfield` or `lps demo --lightfield`)."""
    return (Path(folder) / LIGHTFIELD_FILE).is_file()


def check_lines(check: dict[str, Any] | None) -> list[str]:
    """The epipolar check's numbers as printed lines (lps lightfield, lps demo --lightfield, the GUI's tab): the
    report page's rows (:func:`lps_gui.report.pdf.lightfield.epipolar_rows`), one line each."""
    from lps_gui.report.pdf.lightfield import epipolar_rows

    return [f"{what}: {value}" for what, value in epipolar_rows(check)]


def lightfield_content(folder: Path) -> SectionContent:
    """The folder's numbers (views, the epipolar check, the HCI layout) and its EPIs; a one-line InputError when the
    folder holds no light field."""
    folder = Path(folder)
    if not has_lightfield(folder):
        raise InputError(f"{folder}: no {LIGHTFIELD_FILE} here; choose a folder written by `lps lightfield`")
    doc = read_json(folder / LIGHTFIELD_FILE, "light field file")
    uniform = doc.get("uniform") or {}
    lines = [f"{len(doc.get('views') or [])} views on {' and '.join(doc.get('axes') or ['X'])}",
             *check_lines(doc.get("check")),
             "HCI layout written" if uniform.get("hci") else (uniform.get("refusal") or "HCI layout not written")]
    return SectionContent("Light field", [], lines, pictures=[(str(folder / name), title) for name, title in EPI_FILES])
