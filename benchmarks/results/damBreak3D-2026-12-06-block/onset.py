"""When the water reaches the box in damBreak3D runs: the first time the force on it exceeds
1 N, the first time P1 exceeds 2 kPa, and P1's largest reading before 0.7 s (value, time).

    python onset.py RUN ...     (a folder holding force.dat[.gz] and sensors.dat[.gz], or a
                                 case with its postProcessing)
"""
import sys, gzip, numpy as np
from pathlib import Path
def load(p):
    p=Path(p)
    op = gzip.open if p.suffix==".gz" else open
    with op(p,"rt") as f:
        rows=[l.split() for l in f if not l.startswith("#") and l.strip()]
    return np.array([[float(x) if x.lower()!="nan" else np.nan for x in r] for r in rows])
for d in sys.argv[1:]:
    d=Path(d)
    fp = next(iter(list(d.glob("force.dat*"))+list(d.glob("postProcessing/boxForce/0/force.dat"))))
    sp = next(iter(list(d.glob("sensors.dat*"))+list(d.glob("postProcessing/sensors/0/sensors.dat"))))
    F=load(fp); S=load(sp)
    t=F[:,0]; fx=np.abs(F[:,1]); i=np.flatnonzero(fx>1.0)
    ts=S[:,0]; p1=S[:,1]; j=np.flatnonzero(np.nan_to_num(p1)>2000)
    w=(ts<0.7); k=np.nanargmax(np.where(w,p1,np.nan)) if np.any(w&np.isfinite(p1)) else None
    force = f"{t[i[0]]:.3f} s" if i.size else "never"
    onset = f"{ts[j[0]]:.3f} s" if j.size else "never"
    peak = "no reading" if k is None else f"{p1[k] / 1000:.1f} kPa at {ts[k]:.3f} s"
    print(f"{str(d):<40} force > 1 N at {force}, P1 > 2 kPa at {onset}, "
          f"P1's largest before 0.7 s {peak}")
