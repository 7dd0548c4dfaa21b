"""The rules a spec may silence (``checks: {ignore: [...]}``) are rules of ``hybrid check``."""

from __future__ import annotations

from pathlib import Path

import hybrid
from hybrid.analysis.findings import CAMPAIGN_RULES, RULES
from hybrid.reader.schema import RULE_IDS


def test_every_silenceable_rule_is_a_rule_and_the_rest_are_not_findings_of_a_spec() -> None:
    assert set(RULE_IDS) <= set(RULES)
    # what a spec cannot silence: a spec that does not load, a proof's success (information),
    # and the campaign rules (reported by sweep, not by check)
    assert set(RULES) - set(RULE_IDS) == {"invalid-spec", "property-proved", *CAMPAIGN_RULES}


def test_only_a_refutation_by_a_run_is_reported_as_property_violated() -> None:
    # property-violated means a run of the model shows the violation; the places that
    # emit it are reach's verdict "refuted" (a simulated witness) and nothing else
    root = Path(hybrid.__file__).parent
    emitters = {
        str(path.relative_to(root))
        for path in root.rglob("*.py")
        if '"property-violated"' in path.read_text(encoding="utf-8")
    }
    rule_tables = {"analysis/findings.py", "reader/schema.py"}
    assert emitters - rule_tables == {"reach/check.py", "cli/reach.py"}
    check_source = (root / "reach" / "check.py").read_text(encoding="utf-8")
    assert 'p.verdict == "refuted"' in check_source
