"""Error lines worded for the window: the CLI's switches become the panel, button or field that does the same.

The layers below the GUI raise one-line errors written for ``lps`` ("use
--resume or choose an empty folder"). The GUI shows the same cause with what
to do here; an unknown switch is only unquoted (never dropped, the cause stays
readable).
"""
from __future__ import annotations

import re

# (pattern, replacement) applied in order; the first ones are whole advice phrases
GUI_WORDING: tuple[tuple[str, str], ...] = (
    (r"use --resume or choose an empty folder", "resume it (Capture: Resume session…) or choose an empty folder"),
    (r"pass --intrinsics FILE or run `lps intrinsics` first",
     "choose an intrinsics file in the Estimation panel, or calibrate in the Intrinsics panel first"),
    (r"resume it with --stage and --camera", "connect the stage and camera it was captured with, then resume it"),
    (r"re-capture a real stage with `lps capture --compensation`",
     "capture the real stage again with a compensation table (Capture: Session)"),
    (r"\(`lps detect --force`\)", "(detect the corners again)"),
    (r"`lps detect --force`", "detecting the corners again"),
    (r"\(--stage sim\)", "(Stage: Simulated stage)"),
    (r"check --board matches", "check the board settings match"),
    (r"--home or --unlock", "Home or Unlock"),
    (r"choose another --(out|report)\b", "choose another file"),
    (r"lps capture --board-temp", "the board temperature (Capture: For the report)"),
    (r"`lps ([a-z-]+)`", r"the \1 step"),
    (r"(?<![\w-])--([a-z][a-z-]*)", r"\1"),  # any other switch: its plain name
)


def for_gui(message: str) -> str:
    """``message`` with the CLI's switches and commands replaced by what the GUI offers."""
    for pattern, repl in GUI_WORDING:
        message = re.sub(pattern, repl, message)
    return message
