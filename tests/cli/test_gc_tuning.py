"""`lps` freezes the objects alive when a command is done (the exit then skips collecting them), and a later
main() in the same process gives them back to the collector first."""
import gc

import lps_gui.cli as cli
from lps_gui.gc_tuning import paused


def test_main_freezes_at_the_end_and_unfreezes_at_the_start(monkeypatch, capsys):
    seen = []
    real = cli._main

    def spy(argv):
        seen.append(gc.get_freeze_count())
        return real(argv)

    monkeypatch.setattr(cli, "_main", spy)
    try:
        assert cli.main([]) == 2  # no command: help, exit status 2
        assert gc.get_freeze_count() > 0
        assert cli.main([]) == 2
        assert seen == [0, 0]  # each run starts with nothing frozen
    finally:
        gc.unfreeze()
    capsys.readouterr()


def test_paused_restores_the_collector_as_it_was():
    assert gc.isenabled()
    with paused():
        assert not gc.isenabled()
        with paused():
            assert not gc.isenabled()
        assert not gc.isenabled()  # an outer pause is not ended by an inner one
    assert gc.isenabled()
    gc.disable()
    try:
        with paused():
            pass
        assert not gc.isenabled()  # a collector the caller turned off stays off
    finally:
        gc.enable()
