"""Terms without axes (issue 32): the reductions ``dot(A@, B@)`` and ``sum@(E)`` of
``expand_components``, code per dimension (``Term.code``, ``Term.dims``) and the plan's refusal
of a model without a form for the case's dimension."""

from __future__ import annotations

import ast
import dataclasses
import re

import pytest

from sphfoam.engine import terms as T
from sphfoam.engine.bodies import components, expand
from sphfoam.engine.plan import Selection
from test_contract import _pipeline_models, selection  # tests/ is on sys.path (rootdir)

D2 = (("x", "u"), ("y", "v"))
D3 = (("x", "u"), ("y", "v"), ("z", "w"))


# --- the reductions -----------------------------------------------------------------------------
def test_dot_of_two_vectors():
    assert T.expand_components("drho_a += mb * dot(U@c_ab, gW@)", D2) == \
        "drho_a += mb * (uc_ab * gWx + vc_ab * gWy)"
    assert T.expand_components("x = dot(d@_ab, gW@) / r2", D3) == \
        "x = (dx_ab * gWx + dy_ab * gWy + dz_ab * gWz) / r2"


def test_sum_over_the_components():
    assert T.expand_components("s = sum@(g@ * d@_ab)", D2) == "s = (gx * dx_ab + gy * dy_ab)"
    assert T.expand_components("s = sum@(U@_ab * U@_ab)", D3) == \
        "s = (u_ab * u_ab + v_ab * v_ab + w_ab * w_ab)"
    # a term that is not a product keeps its parentheses (the same evaluation order)
    assert T.expand_components("s = sum@(a@ - b@)", D2) == "s = ((ax - bx) + (ay - by))"


def test_nested_parentheses_in_the_arguments():
    got = T.expand_components("x = dot(aux[I_g_@, a] + aux[I_g_@, b], f(gW@) * (1.0 + c))", D2)
    assert got == ("x = ((aux[I_g_x, a] + aux[I_g_x, b]) * (f(gWx) * (1.0 + c))"
                   " + (aux[I_g_y, a] + aux[I_g_y, b]) * (f(gWy) * (1.0 + c)))")
    assert T.expand_components("y = sum@(dot(U@_ab, gW@) * d@_ab)", D2) == \
        "y = ((u_ab * gWx + v_ab * gWy) * dx_ab + (u_ab * gWx + v_ab * gWy) * dy_ab)"
    with pytest.raises(T.ContractError):
        T.expand_components("x = dot(a@, b@, c@)", D2)


def test_a_line_with_reductions_only_is_written_once():
    code = "lam = dot(d@_ab, gW@) / r2\nacc_@ += lam * U@_ab"
    assert T.expand_components(code, D3).splitlines() == [
        "lam = (dx_ab * gWx + dy_ab * gWy + dz_ab * gWz) / r2",
        "acc_x += lam * u_ab", "acc_y += lam * v_ab", "acc_z += lam * w_ab"]
    # a line with a reduction and a free @ is written per component, the reduction in each
    assert T.expand_components("acc_@ += dot(U@_ab, d@_ab) * gW@", D2).splitlines() == [
        "acc_x += (u_ab * dx_ab + v_ab * dy_ab) * gWx",
        "acc_y += (u_ab * dx_ab + v_ab * dy_ab) * gWy"]
    # a name that merely ends in "dot" is no reduction
    assert T.expand_components("x = vdot(a)", D2) == "x = vdot(a)"


# --- code per dimension ---------------------------------------------------------------------------
def test_code_per_dimension_and_its_dimensions():
    t = T.Term("m", ("prepass",), init={2: "s = 0.0", 3: "s = 1.0"}, pair="s += Wab")
    assert t.dims == (2, 3) and t.code("init", 2) == "s = 0.0" and t.code("init", 3) == "s = 1.0"
    assert t.code("pair", 3) == "s += Wab"
    two = T.Term("m", ("prepass",), pair={2: "s += Wab"})
    assert two.dims == (2,) and two.code("pair", 3) == ""
    assert T.Term("m", ("prepass",), pair="s += Wab").dims == (2, 3)
    assert T.Term("m", ("prepass",), pair="s += Wab", dims=(2,)).dims == (2,)
    hash(two)                               # still a frozen, hashable dataclass


_FORBIDDEN_2D = re.compile(r"@|\bdot\(|\bsum@\(")
#: a name of the x (first) component and its z (third) one: 3-D code naming the first names
#: the third too (else it would be 2-D code run in 3-D)
_X_Z = [(r"\bgWx\b", r"\bgWz\b"), (r"\bdx_ab\b", r"\bdz_ab\b"), (r"\bu_ab\b", r"\bw_ab\b"),
        (r"\buc_ab\b", r"\bwc_ab\b"), (r"\bacc_x\b", r"\bacc_z\b"), (r"\bgx\b", r"\bgz\b"),
        (r"\bF_nx\b", r"\bF_nz\b")]


def _codes(t, dim):
    return {part: expand(t.code(part, dim), dim) for part in T.CODE_PARTS}


@pytest.mark.parametrize("model", list(_pipeline_models()), ids=lambda m: f"{m.family}-{m.name}")
def test_every_model_expands_in_2d_and_3d_or_is_refused(model):
    """In 2-D every term expands to Python with no @, dot(, sum@( left; in 3-D it either
    expands (z wherever x) or is declared 2-D only."""
    for t in model.terms():
        assert 2 in t.dims, t.name
        for part, code in _codes(t, 2).items():
            assert not _FORBIDDEN_2D.search(code), (t.name, part, code)
            ast.parse(f"def f():\n" + "\n".join("    " + x for x in (code or "pass").splitlines()))
        if 3 not in t.dims:
            continue
        for part, code in _codes(t, 3).items():
            assert not _FORBIDDEN_2D.search(code), (t.name, part, code)
            for x, z in _X_Z:
                assert not re.search(x, code) or re.search(z, code), (t.name, part, x, code)


def test_a_model_without_a_3d_form_is_refused_by_name():
    sel = dataclasses.replace(selection(turbulence={"type": "mixingLength"}), dim=3)
    with pytest.raises(T.ContractError, match="turbulence .mixingLength. has no 3-D form"):
        sel.plan()
    dataclasses.replace(sel, dim=2).plan()


def test_the_loop_bodies_take_the_code_of_the_plans_dimension():
    """A term with code per dimension: the generated source holds the form of the case's
    dimension (read through ``Term.code`` by the loop bodies)."""
    from sphfoam.engine.bodies import LoopBodies
    from sphfoam.models.viscosity import VISCOUS_SEES, Viscosity

    class PerDimension(Viscosity):
        name = "perDimensionExample"

        def params(self, ctx):
            return {"visc_k2": 1.0, "visc_k3": 2.0}

        def terms(self):
            return [T.Term("viscosity", ("rates",), sees=VISCOUS_SEES, reads=("gradW",),
                           writes=("acc",), pair={2: "acc_@ += visc_k2 * mb * gW@",
                                                  3: "acc_@ -= visc_k3 * mb * gW@"})]

    for dim, want, other in ((2, "acc_y += visc_k2 * mb * gWy", "visc_k3"),
                             (3, "acc_z -= visc_k3 * mb * gWz", "visc_k2")):
        sel = dataclasses.replace(selection(), viscosity=PerDimension(), dim=dim)
        body = LoopBodies(sel.plan()).gather(sel.plan().stage("rates", "fluid"))
        assert want in body and other not in body, (dim, body)
