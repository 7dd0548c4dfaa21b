"""The names of the ways a campaign draws samples, apart from the code that draws them.

The command line offers them as choices when it builds its parser; importing
:mod:`hybrid.campaigns.space` (numpy, the model) for three names would cost every
``hybrid validate`` a tenth of a second.

Examples
--------
>>> SAMPLERS
('lhs', 'sobol', 'random')
"""

from __future__ import annotations

__all__ = ["SAMPLERS"]

SAMPLERS = ("lhs", "sobol", "random")
"""How samples are drawn: Latin hypercube, scrambled Sobol, uniform."""
