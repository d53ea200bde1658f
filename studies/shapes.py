"""Error shapes the independent generators share: outside the workbench's catalogue forms
(issue 39), and outside the package (numpy only)."""
from __future__ import annotations

import numpy as np


def worn_backlash(positions: np.ndarray, directions: np.ndarray, low: float, high: float,
                  rng) -> np.ndarray:
    """Backlash of a worn screw: the lost motion, signed by the direction of approach, is
    largest where the screw works most (a bump somewhere along the travel, up to 1.6
    times its size at the ends) - not the catalogue's one step over the whole travel."""
    centre = rng.uniform(low + 0.25 * (high - low), low + 0.75 * (high - low))
    width = 0.2 * (high - low)
    return directions * (1.0 + 0.6 * np.exp(-0.5 * ((positions - centre) / width) ** 2))
