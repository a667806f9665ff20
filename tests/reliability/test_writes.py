"""Items 1 and 2 of issue 17: every write is checked before it replaces a file; result files are a set."""
from __future__ import annotations

import errno
import json
import os
import subprocess
from pathlib import Path

import pytest

from lps_gui.cli import main
from lps_gui.errors import LpsError
from lps_gui.io import atomic
from lps_gui.io.results.document import write_results
from tests.report.conftest import make_results


def last_line(stderr: str) -> str:
    """The error line (progress bars come before it)."""
    return stderr.strip().splitlines()[-1]


OLD_REPORT = b"%PDF-1.4 the previous, good report\n%%EOF\n"


def _report_folder(tmp_path: Path) -> Path:
    folder = tmp_path / "s"
    folder.mkdir()
    results, _ = make_results()
    (folder / "results.json").write_text(json.dumps(results))
    (folder / "report.pdf").write_bytes(OLD_REPORT)
    return folder


@pytest.mark.gui
def test_item1_a_pdf_cut_short_by_a_full_disk_never_replaces_the_report(tmp_path, capsys, monkeypatch):
    """Qt's PDF writer reports no error when the disk fills: the file it leaves ends early (no %%EOF)."""
    from lps_gui.report.pdf.layout import PdfFlow

    finish = PdfFlow.finish

    def finish_on_full_disk(self):
        pages = finish(self)
        [name] = Path(tmp_path / "s").glob(".report.pdf*tmp")
        os.truncate(name, min(8192, os.path.getsize(name) // 2))  # what a full disk left of the PDF
        return pages

    monkeypatch.setattr(PdfFlow, "finish", finish_on_full_disk)
    folder = _report_folder(tmp_path)
    assert main(["report", str(folder)]) == 2
    err = last_line(capsys.readouterr().err)
    assert err.startswith("lps report: error:") and "report.pdf" in err and "previous" in err
    assert (folder / "report.pdf").read_bytes() == OLD_REPORT
    assert sorted(p.name for p in folder.iterdir()) == ["report.pdf", "results.json"]  # no temp file left


def _can_mount_tmpfs() -> bool:
    return os.geteuid() == 0 and subprocess.run(["which", "mount"], capture_output=True).returncode == 0


@pytest.mark.gui
@pytest.mark.skipif(not _can_mount_tmpfs(), reason="needs root to mount a small tmpfs")
def test_item1_report_on_a_really_full_disk(tmp_path, capsys):
    disk = tmp_path / "disk"
    disk.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs", str(disk)], capture_output=True).returncode:
        pytest.skip("tmpfs mount refused")
    try:
        folder = _report_folder(disk)
        try:
            with open(disk / "filler", "wb") as f:
                while True:
                    f.write(b"\0" * 4096)
                    f.flush()
        except OSError:
            pass
        os.truncate(disk / "filler", max(0, os.path.getsize(disk / "filler") - 8192))
        assert main(["report", str(folder)]) == 2
        assert "free disk space" in capsys.readouterr().err
        assert (folder / "report.pdf").read_bytes() == OLD_REPORT
    finally:
        subprocess.run(["umount", str(disk)], check=True)


def test_item1_write_bytes_atomic_checks_the_written_size(tmp_path, monkeypatch):
    target = tmp_path / "f.json"
    target.write_text("old")
    monkeypatch.setattr(atomic.os, "fsync", lambda fd: (_ for _ in ()).throw(OSError(errno.ENOSPC, "No space left on device")))
    with pytest.raises(LpsError, match="free disk space"):
        atomic.write_text_atomic(target, "new content")
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["f.json"]


def test_item2_result_files_are_replaced_as_a_set_or_not_at_all(tmp_path, monkeypatch):
    results, _ = make_results()
    write_results(tmp_path, results)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    changed = dict(results, method="hybrid", positions=results["positions"][:3])
    calls = {"n": 0}
    real_fsync = os.fsync

    def fsync_then_full(fd):  # the first file fits, then the disk is full
        calls["n"] += 1
        if calls["n"] > 1:
            raise OSError(errno.ENOSPC, "No space left on device")
        real_fsync(fd)

    monkeypatch.setattr(os, "fsync", fsync_then_full)
    with pytest.raises(LpsError):
        write_results(tmp_path, changed)
    monkeypatch.undo()
    after = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    assert after == before  # all three old files, no temp files


def test_item2_estimate_on_a_full_disk_is_one_line_and_keeps_the_old_results(point_session, capsys, monkeypatch):
    assert main(["estimate", str(point_session)]) == 0
    names = ("results.json", "positions.csv", "summary.csv")
    before = {n: (point_session / n).read_bytes() for n in names}
    capsys.readouterr()
    real_write = os.write

    def write_until_full(fd, data):
        if len(data) > 200:  # the result files; the lock file's short record still fits
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_write(fd, data)

    monkeypatch.setattr(os, "write", write_until_full)
    assert main(["estimate", str(point_session), "--method", "pnp"]) == 2
    monkeypatch.undo()
    err = last_line(capsys.readouterr().err)
    assert err.startswith("lps estimate: error:") and "No space left" in err
    assert {n: (point_session / n).read_bytes() for n in names} == before
    assert not [p for p in point_session.iterdir() if p.name.endswith(".tmp")]


@pytest.mark.gui
def test_item1_every_pdf_writer_goes_through_the_checked_commit(tmp_path, monkeypatch):
    """The as-found/as-left PDF (and every other report) is committed only when complete: one mechanism."""
    from lps_gui.errors import StorageError
    from lps_gui.report.pdf.compare import write_comparison
    from lps_gui.report.pdf.layout import PdfFlow

    finish = PdfFlow.finish

    def finish_on_full_disk(self):
        pages = finish(self)
        os.truncate(self.path, min(8192, os.path.getsize(self.path) // 2))
        return pages

    folder = _report_folder(tmp_path)
    out = tmp_path / "compare.pdf"
    out.write_bytes(OLD_REPORT)
    monkeypatch.setattr(PdfFlow, "finish", finish_on_full_disk)
    with pytest.raises(StorageError):
        write_comparison(folder, folder, out)
    assert out.read_bytes() == OLD_REPORT
    assert sorted(p.name for p in tmp_path.iterdir()) == ["compare.pdf", "s"]  # no temp file left
