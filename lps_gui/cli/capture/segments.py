"""`lps capture` of a stitched plan: between segments the operator moves the board, then presses Enter.

The engine pauses before each new segment with a "move board" event saying
where the board goes; here the message is printed and the capture resumes on
Enter. Without a terminal to answer (stdin closed), the capture stops there,
every frame kept: resume it from a terminal after moving the board.
"""
from __future__ import annotations

import sys
from typing import Any, Callable


def operator_moves_board(engine: Any, answer: Callable[[str], str] = input) -> Callable[[Any], None]:
    """An engine listener: on "move board", ask the operator and resume (or abort when nobody can answer)."""

    def on_event(event: Any) -> None:
        if event.kind != "move board":
            return
        print(f"\nlps capture: {event.message}", file=sys.stderr)
        try:
            answer("press Enter when the board is fixed in its new place (Ctrl-D stops, frames are kept) ")
        except (EOFError, KeyboardInterrupt):
            print("lps capture: nobody to move the board; stopping here (resume after moving it)", file=sys.stderr)
            engine.abort()
            return
        engine.resume()

    return on_event
