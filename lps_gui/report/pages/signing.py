"""The signing block: laboratory, certificate number, the instruments' identifiers and certificates, dates, approval.

A report a lab signs names who measured for whom, with which traceable instruments (the board's and the
thermometer's calibration certificates, the camera), when, and leaves a line for the approving signature.
Every entry comes from session.json ``identification`` (`lps capture --lab ... --board-cert ...` or the GUI's
report set-up); what was not recorded says so. No Qt here.
"""
from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

from lps_gui.io.setup_fields import ID_FIELDS

if TYPE_CHECKING:
    from lps_gui.io.results.model import Results

NOT_RECORDED = "not recorded"
SIGN_LINE = "_" * 34
# identification key -> (lps capture switch, what it is) of the signing block (lps_gui.io.setup_fields.ID_FIELDS)
SIGNING_FIELDS = tuple((f.key, f.flag, f.help) for f in ID_FIELDS if f.signing)


def _instrument(ident: dict[str, Any], id_key: str, cert_key: str, fallback_id: str = "") -> str:
    what = str(ident.get(id_key) or fallback_id or "")
    cert = ident.get(cert_key)
    if not what and not cert:
        return NOT_RECORDED
    return ", ".join(p for p in (what, f"certificate {cert}" if cert else "no certificate recorded") if p)


def signing_rows(session_meta: dict[str, Any], results: "Results | dict[str, Any]", today: str | None = None
                 ) -> list[tuple[str, str]]:
    """(label, text) rows of the signing block, in the order a certificate prints them."""
    from lps_gui.io.results.model import as_results

    results = as_results(results)
    ident = session_meta.get("identification") or {}
    camera = session_meta.get("camera") or {}
    measured = str(session_meta.get("created") or (results.session_meta or {}).get("created") or NOT_RECORDED)
    return [
        ("Laboratory", str(ident.get("lab") or NOT_RECORDED)),
        ("Certificate no.", str(ident.get("certificate_number") or NOT_RECORDED)),
        ("Board", _instrument(ident, "board_id", "board_certificate")),
        ("Thermometer", _instrument(ident, "thermometer", "thermometer_certificate")),
        ("Camera", _instrument(ident, "camera_serial", "camera_certificate", str(camera.get("serial") or ""))),
        ("Measured on", measured),
        ("Results computed", str(results.created or NOT_RECORDED)),
        ("Report issued", today or time.strftime("%Y-%m-%d")),
        ("Approved by", str(ident.get("approved_by") or SIGN_LINE)),
        ("Signature and date", SIGN_LINE),
    ]
