"""The rules a spec may silence (``checks: {ignore: [...]}``) are rules of ``hybrid check``."""

from __future__ import annotations

from hybrid.analysis.findings import CAMPAIGN_RULES, RULES
from hybrid.reader.schema import RULE_IDS


def test_every_silenceable_rule_is_a_rule_and_the_rest_are_not_findings_of_a_spec() -> None:
    assert set(RULE_IDS) <= set(RULES)
    # what a spec cannot silence: a spec that does not load, a proof's success (information),
    # and the campaign rules (reported by sweep, not by check)
    assert set(RULES) - set(RULE_IDS) == {"invalid-spec", "property-proved", *CAMPAIGN_RULES}
