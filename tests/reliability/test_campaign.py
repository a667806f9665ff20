"""The fast subset of tools/campaign.py (issue 17's fault-and-bad-input campaign) must pass in CI."""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def load_campaign():
    spec = importlib.util.spec_from_file_location("lps_campaign", ROOT / "tools" / "campaign.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["lps_campaign"] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


campaign = load_campaign()
FAST = [c for c in campaign.CASES if c.fast]


def test_the_campaign_has_its_cases():
    assert len([c for c in campaign.CASES if c.kind == "input"]) >= 40
    assert len([c for c in campaign.CASES if c.kind == "fault"]) >= 10


@pytest.mark.parametrize("case", FAST, ids=[c.name for c in FAST])
def test_campaign_case(case, tmp_path):
    outcome = case.run(tmp_path)
    assert outcome.ok, f"{case.name}: expected {case.expected}; got {outcome.result}"
