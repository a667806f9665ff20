"""Every file a session names stays inside the session folder.

captures.jsonl's ``file`` entries (and any other relative path a session
file holds) are checked here: relative, no ``..``, not resolving outside the
folder through a symlinked sub-folder, and read as regular files without
following a final symlink (O_NOFOLLOW) and with a size limit. A session
copied from someone else can therefore never make lps read /dev/zero,
another user's files, or truncate a file elsewhere.
"""
from __future__ import annotations

from pathlib import Path

from lps_gui.file_limits import check_relative, read_file_limited, resolve_in_session
from lps_gui.io.image_file import MAX_IMAGE_BYTES

__all__ = ["check_relative", "read_session_file", "resolve_in_session"]


def read_session_file(folder: Path | str, rel: str, max_bytes: int = MAX_IMAGE_BYTES, what: str = "image") -> bytes:
    """The bytes of a session file: inside the folder, a regular file, no final symlink, size-limited."""
    return read_file_limited(resolve_in_session(folder, rel), max_bytes, what, follow_symlinks=False)
