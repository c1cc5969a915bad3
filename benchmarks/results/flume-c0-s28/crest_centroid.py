"""The crest tracker's x_c (the vertex of the parabola through the readings above half the
crest) beside the centroid of the same readings, on a case's written times.

    python crest_centroid.py CASE     # on a copy of the case: it rewrites postProcessing/crest

Saves CASE/centroid.npy: one row per written time, (vertex x_c, centroid, crest height).
"""
import os
import sys

import numpy as np
from typer.testing import CliRunner

import sphfoam.sampling.waves as waves
from sphfoam.cli import app

rows = []
_crest = waves.crest


def crest_and_centroid(gx, eta, fit_above=0.5):
    xc, top = _crest(gx, eta, fit_above)
    e = np.where(np.isfinite(eta), eta, -np.inf)
    j = int(np.argmax(e))
    below = np.flatnonzero(e < fit_above * top)
    i0 = below[below < j][-1] + 1 if (below < j).any() else 0
    i1 = below[below > j][0] if (below > j).any() else e.size
    w = e[i0:i1] - fit_above * top
    rows.append((xc, float((gx[i0:i1] * w).sum() / w.sum()), top))
    return xc, top


waves.crest = crest_and_centroid
case = sys.argv[1]
print(CliRunner().invoke(app, ["sample", case, "-f", "crest"]).output)
np.save(os.path.join(case, "centroid.npy"), np.array(rows))
