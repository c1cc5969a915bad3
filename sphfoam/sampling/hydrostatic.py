"""Pressure at the bed of a water column at rest (hydrostatic tank checks)."""

from __future__ import annotations

import numpy as np


def bed_pressure(x, y, p, *, x0: float, width: float, depth: float, reach: float, dx: float,
                 bed: float = 0.0) -> tuple[float, float, float]:
    """(bed pressure, bottom-row pressure, bottom-row height) of fluid particles at rest.

    The bed pressure is the least-squares line p(y) through the fluid particles of the middle
    half of the tank (x0 + width/4 .. x0 + 3 width/4) from one kernel support (``reach``)
    above the bed up to mid-depth, evaluated at the bed: the pressure the column brings down
    to the wall, whatever the boundary model does to the rows within its reach. The bottom
    row (within dx/2 of the lowest particle) is reported as well, because that is where the
    boundary models differ (T §3.8).
    """
    mid = (x > x0 + 0.25 * width) & (x < x0 + 0.75 * width)
    band = mid & (y >= bed + reach) & (y <= bed + 0.5 * depth)
    _, intercept = np.polyfit(y[band] - bed, p[band], 1)
    row = mid & (y < y[mid].min() + 0.5 * dx)
    return float(intercept), float(p[row].mean()), float(y[row].mean())
