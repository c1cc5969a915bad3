"""Near the container model's front face (SPHERIC Test 2 at H/dx = 15, Adami walls): the
x-acceleration of the fluid particles within 1.2 dx of the face's outer wall row (mid face,
z < 0.12 m) from their wall neighbours and from their fluid neighbours, each split into the
p_a and p_b parts of the momentum form T(3.25), -m_b (p_a + p_b)/(rho_a rho_b) dW/dx; +x is
away from the box.

    python face_forces.py CASE TIME
"""
import sys
import numpy as np
from scipy.spatial import cKDTree
from sphfoam import api

case, t = sys.argv[1], float(sys.argv[2])
dx = 0.036666667; h = 1.3 * dx; R = 2 * h        # the tutorial's dx; Wendland C2, h = 1.3 dx
alpha = 21 / (16 * np.pi * h**3)
def dWdr(r):
    q = r / h
    return np.where(q < 2, alpha * (-5 * q * (1 - q / 2) ** 3) / h, 0.0)
s = api.read_time(case, t)
X = s["positions"]; p = s["p"]; rho = s["rho"]; m = s["mass"]; typ = s["type"]
fl = typ == 0; wl = ~fl
xo = 0.7918                 # the face's outer wall row (the face x = 0.8245 m)
sel = fl & (X[:, 0] > xo) & (X[:, 0] < xo + 1.2 * dx) & (X[:, 1] > 0.32) & (X[:, 1] < 0.68) & (X[:, 2] < 0.12)
tree = cKDTree(X)
rows = []
for a in np.flatnonzero(sel):
    nb = np.array(tree.query_ball_point(X[a], R)); nb = nb[nb != a]
    d = X[a] - X[nb]; r = np.linalg.norm(d, axis=1)
    gx = dWdr(r) * d[:, 0] / np.maximum(r, 1e-12)
    c = m[nb] / (rho[a] * rho[nb]) * gx
    w = wl[nb]
    A_pa_w = -(p[a] * c[w]).sum(); A_pb_w = -(p[nb][w] * c[w]).sum()
    A_pa_f = -(p[a] * c[~w]).sum(); A_pb_f = -(p[nb][~w] * c[~w]).sum()
    pw = p[nb][w & (r < 1.5 * dx)].mean() if (w & (r < 1.5 * dx)).any() else np.nan
    rows.append((X[a, 0] - xo, s["U"][a, 0], p[a], pw, A_pa_w, A_pb_w, A_pa_f, A_pb_f))
rows = np.array(rows)
print(f"t={t}: {len(rows)} fluid particles within 1.2 dx of the outer row, mid face, z<0.12")
print("  mean: gap/dx %.2f  u %.2f  p_a %.0f  p_w(near) %.0f  | wall: p_a-part %.1f  p_w-part %.1f | fluid: p_a-part %.1f p_b-part %.1f  total %.1f m/s2"
      % (rows[:, 0].mean() / dx, rows[:, 1].mean(), rows[:, 2].mean(), np.nanmean(rows[:, 3]),
         *rows[:, 4:].mean(0), rows[:, 4:].sum(1).mean()))
for r_ in rows[np.argsort(rows[:, 0])][:6]:
    print("   gap/dx %.2f u %.2f p_a %.0f p_w %.0f | %.1f %.1f | %.1f %.1f | tot %.1f" % (r_[0] / dx, *r_[1:], r_[4:].sum()))
