"""Perturbation derivation of the solitary wave series (Fenton 1972 method) to order N."""
import sys, time
import sympy as sp
from fractions import Fraction

N = int(sys.argv[1]) if len(sys.argv) > 1 else 4
NE = N + 1          # equations to order N+1 fix c_N and alpha to their orders

LIM = [NE]
def trunc(d):
    return {k: v for k, v in d.items() if k[0] <= LIM[0] and v != 0}

def add(*ds):
    out = {}
    for d in ds:
        for k, v in d.items():
            out[k] = out.get(k, 0) + v
    return trunc(out)

def scale(d, s):
    return {k: v * s for k, v in d.items()}

def mul(a, b):
    out = {}
    for (i, j), v in a.items():
        for (k, l), w in b.items():
            if i + k <= LIM[0]:
                key = (i + k, j + l)
                out[key] = out.get(key, 0) + v * w
    return {k: sp.expand(v) for k, v in out.items() if v != 0}

def D2(d):
    """d^2/dX^2 of S^j: 4 j^2 S^j - (4 j^2 + 2 j) S^(j+1)."""
    out = {}
    for (i, j), v in d.items():
        if j == 0:
            continue
        out[(i, j)] = out.get((i, j), 0) + 4 * j * j * v
        out[(i, j + 1)] = out.get((i, j + 1), 0) - (4 * j * j + 2 * j) * v
    return out

def E(d):
    """d/dX P(S) = T * E[P], E[P] = -2 S P'(S)."""
    out = {}
    for (i, j), v in d.items():
        if j:
            out[(i, j)] = out.get((i, j), 0) - 2 * j * v
    return out

one = {(0, 0): sp.Integer(1)}
known = {}
eta = {}      # (i, j) -> symbol or value
f = {}
csyms, bsyms = {}, {}
for i in range(1, NE + 1):
    for j in range(1, i + 1):
        eta[(i, j)] = sp.Symbol(f"e_{i}_{j}")
        f[(i, j)] = sp.Symbol(f"g_{i}_{j}")
    csyms[i] = sp.Symbol(f"c_{i}")
for k in range(0, NE):
    bsyms[k] = sp.Symbol(f"b_{k}")

def current(dsym):
    return {k: (sp.sympify(v).subs(known) if not isinstance(v, int) else v) for k, v in dsym.items()}

t0 = time.time()
for order in range(1, NE + 1):
    LIM[0] = order
    # series with what is known substituted (unknowns of higher orders are dropped by trunc)
    et = {k: sp.sympify(v).xreplace(known) for k, v in eta.items() if k[0] <= order}
    c = add({(0, 0): sp.Integer(1)}, {(i, 0): csyms[i].xreplace(known) if csyms[i] not in known else known[csyms[i]] for i in range(1, order + 1)})
    fs = add(scale(c, -1), {k: sp.sympify(v).xreplace(known) for k, v in f.items() if k[0] <= order})
    alpha2 = {(k + 1, 0): bsyms[k].xreplace(known) for k in range(0, order)}
    Y = add(one, et)
    # Y powers
    Yp = [one]
    for p in range(1, 2 * order + 3):
        Yp.append(mul(Yp[-1], Y))
    # derivatives: F2n = alpha^{2n} D2^n f
    F = [fs]
    Ecur = []
    term = fs
    a2n = one
    nmax = order  # alpha^{2n} f^(2n) is O(eps^{n+1})
    Dn = fs
    derivs = [(one, fs)]
    for n in range(1, nmax + 1):
        Dn = D2(Dn)
        a2n = mul(a2n, alpha2)
        derivs.append((a2n, Dn))
    fact = sp.factorial
    psi = {}
    U = {}
    Wp = {}
    for n, (a2, Dn) in enumerate(derivs):
        g = mul(a2, Dn)
        psi = add(psi, scale(mul(Yp[2 * n + 1], g), sp.Integer(-1) ** n / fact(2 * n + 1)))
        U = add(U, scale(mul(Yp[2 * n], g), sp.Integer(-1) ** n / fact(2 * n)))
        Wp = add(Wp, scale(mul(Yp[2 * n + 1], mul(a2, E(Dn))), -sp.Integer(-1) ** n / fact(2 * n + 1)))
    # W^2 = alpha^2 (1 - S) Wp^2
    W2 = mul(mul(alpha2, {(0, 0): 1, (0, 1): -1}), mul(Wp, Wp))
    K = add(psi, c)                                   # psi(Y) + c = 0
    B = add(scale(mul(U, U), sp.Rational(1, 2)), scale(W2, sp.Rational(1, 2)), Y,
            scale(mul(c, c), sp.Rational(-1, 2)), scale(one, -1))
    eqs = [v for (i, j), v in K.items() if i == order] + [v for (i, j), v in B.items() if i == order]
    crest = sum(eta[(order, j)] for j in range(1, order + 1)) - (1 if order == 1 else 0)
    eqs.append(crest)
    eqs = [sp.expand(e.xreplace(known)) for e in eqs]
    eqs = [e for e in eqs if e != 0]
    unk = sorted(set().union(*[e.free_symbols for e in eqs]), key=str)
    sol = sp.solve(eqs, unk, dict=True)
    assert len(sol) == 1, (order, sol)
    sol = sol[0]
    new = {k: v for k, v in sol.items() if not v.free_symbols}
    known.update(sol)
    # re-substitute into pending solutions
    for k, v in list(known.items()):
        known[k] = sp.sympify(v).xreplace(known)
    print(f"order {order}: {len(eqs)} eqs, {len(unk)} unknowns, fixed {sorted(map(str, new))} ({time.time()-t0:.1f}s)", flush=True)

import json
out = {str(k): str(v) for k, v in known.items()}
json.dump(out, open(f"/tmp/fenton/coeffs_{N}.json", "w"), indent=0)
for i in range(1, N + 1):
    print("eta", i, [known.get(eta[(i, j)]) for j in range(1, i + 1)])
print("c", [known.get(csyms[i]) for i in range(1, N + 1)])
print("b", [known.get(bsyms[k]) for k in range(N)])
