"""The bed pressure of the 3-D tank against rho g H at every written time.

The bed pressure is the least-squares line p(z) through the fluid particles of the middle
quarter of the tank (|x - 0.2|, |y - 0.2| < 0.1 m) from one kernel support above the bed to
mid-depth, evaluated at the bed (the 2-D tank's measure, sphfoam.sampling.hydrostatic); the
largest fluid speed says whether the water stays at rest. Exits 1 if the bed pressure is
more than 1 % off rho g H at the last time.
"""

import sys
from pathlib import Path

import numpy as np

import sphfoam
from sphfoam.io.fields import read_state

case = Path(__file__).resolve().parent
c = sphfoam.Case(case)
rho0, g = c.transport.rho0, -c.gravity[2]
H = max(r.max[2] for r in c.particles.fluid.values())
reach = c.context.support
times = sorted((float(p.name), p) for p in case.iterdir()
               if p.is_dir() and p.name.replace(".", "").isdigit()
               and (p / "lagrangian").is_dir())
print(f"# rho g H = {rho0 * g * H:.1f} Pa\n# time\tbed (Pa)\terror %\tmax speed (m/s)")
for t, folder in times:
    f = read_state(folder, 3)
    fluid = f["type"] == 0
    x, y, z = f["positions"][fluid].T
    p = f["p"][fluid]
    band = (np.abs(x - 0.2) < 0.1) & (np.abs(y - 0.2) < 0.1) & (z >= reach) & (z <= 0.5 * H)
    bed = np.polyfit(z[band], p[band], 1)[1]
    err = 100 * (bed / (rho0 * g * H) - 1)
    speed = np.linalg.norm(f["U"][fluid], axis=1).max()
    print(f"{t:g}\t{bed:.1f}\t{err:+.2f}\t{speed:.2e}")
sys.exit(0 if abs(err) <= 1.0 else 1)
