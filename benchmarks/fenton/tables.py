"""Post-process the derived coefficients into eta, alpha, c, u, w, p tables (exact rationals)."""
import json
import sympy as sp
N = 9
k = {sp.Symbol(a): sp.Rational(b) for a, b in json.load(open("coeffs_9.json")).items() if "_10" not in b and not any(ch.isalpha() for ch in b)}
e = lambda i, j: k[sp.Symbol(f"e_{i}_{j}")]
g = lambda i, j: k[sp.Symbol(f"g_{i}_{j}")]
c = [sp.Integer(1)] + [k[sp.Symbol(f"c_{i}")] for i in range(1, N + 1)]
b = [k[sp.Symbol(f"b_{i}")] for i in range(N)]
E_ = sp.Symbol('E')
alpha_ser = sp.series(sp.sqrt(sum(b[i] / b[0] * E_**i for i in range(N))), E_, 0, N).removeO()
alpha = [sp.Rational(alpha_ser.coeff(E_, i)) for i in range(N)]      # alpha = sqrt(3 eps/4) sum alpha_i eps^i

def mul3(a, bb):
    out = {}
    for (i, j, m), v in a.items():
        for (p, q, r), w in bb.items():
            if i + p <= N:
                key = (i + p, j + q, m + r)
                out[key] = out.get(key, 0) + v * w
    return {kk: v for kk, v in out.items() if v != 0}

def add3(*ds):
    out = {}
    for d in ds:
        for kk, v in d.items():
            out[kk] = out.get(kk, 0) + v
    return {kk: v for kk, v in out.items() if v != 0 and kk[0] <= N}

def sc(d, s):
    return {kk: v * s for kk, v in d.items()}

def D2(d):
    out = {}
    for (i, j, m), v in d.items():
        if j == 0:
            continue
        out[(i, j, m)] = out.get((i, j, m), 0) + 4 * j * j * v
        out[(i, j + 1, m)] = out.get((i, j + 1, m), 0) - (4 * j * j + 2 * j) * v
    return out

def Ed(d):
    return {(i, j, m): -2 * j * v for (i, j, m), v in d.items() if j}

cser = {(i, 0, 0): c[i] for i in range(N + 1)}
f = add3(sc(cser, -1), {(i, j, 0): g(i, j) for i in range(1, N + 1) for j in range(1, i + 1)})
a2 = {(i + 1, 0, 0): b[i] for i in range(N)}
U, Wp = {}, {}
Dn, a2n = f, {(0, 0, 0): sp.Integer(1)}
for n in range(0, N + 1):
    if n:
        Dn = D2(Dn)
        a2n = mul3(a2n, a2)
    t = mul3(a2n, Dn)
    U = add3(U, {(i, j, m + 2 * n): v * (-1)**n / sp.factorial(2 * n) for (i, j, m), v in t.items()})
    tw = mul3(a2n, Ed(Dn))
    Wp = add3(Wp, {(i, j, m + 2 * n + 1): -v * (-1)**n / sp.factorial(2 * n + 1) for (i, j, m), v in tw.items()})
u = add3(U, cser)                                      # laboratory frame
W2 = mul3(mul3(a2, {(0, 0, 0): 1, (0, 1, 0): -1}), mul3(Wp, Wp))
P = add3(sc(mul3(cser, cser), sp.Rational(1, 2)), {(0, 0, 0): 1}, sc(mul3(U, U), sp.Rational(-1, 2)),
         sc(W2, sp.Rational(-1, 2)), {(0, 0, 1): -1})
# checks: P at y = 1 + eta vanishes to O(eps^10); u(bed) = c + f
eta = {(i, j): e(i, j) for i in range(1, N + 1) for j in range(1, i + 1)}
def fmt(d):
    return {",".join(map(str, kk)): str(v) for kk, v in sorted(d.items())}
json.dump({"eta": {f"{i},{j}": str(v) for (i, j), v in sorted(eta.items())},
           "c": [str(x) for x in c], "alpha2": [str(x) for x in b], "alpha": [str(x) for x in alpha],
           "u": fmt(u), "w": fmt(Wp), "p": fmt({kk: v for kk, v in P.items() if kk != (0, 0, 0) and kk != (0, 0, 1)})},
          open('tables_9.json', 'w'))
print(len(u), len(Wp), len(P), alpha[:4])
