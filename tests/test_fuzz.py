"""A seeded fuzz test of the `sphfoam check` path (issue 15).

Every dictionary of every tutorial (system/, constant/, system/metricsDict and the study
dictionaries) is mutated a few hundred times in all: a value replaced by inf, nan, 1e400, a
negative or zero number, a huge one, a wrong type (a word, a list, a sub-dictionary, a
switch), rich markup, a path that escapes the case; a key deleted or misspelt; and, on the
text, a brace or a semicolon removed, a latin-1 byte inserted, the file cut short. Each
mutated case goes through :func:`sphfoam.check.check_case` in-process. The outcome must
be a valid case or a clean CaseError whose every problem names its file (and its key, unless
the file as a whole is unreadable); never another exception.
"""

from __future__ import annotations

import random
import shutil
import time
from pathlib import Path

import pytest

from sphfoam.case import foamdict
from sphfoam.check import check_case, study_dicts
from sphfoam.case.errors import CaseError

TUTORIALS = Path(__file__).resolve().parents[1] / "tutorials"
MUTATIONS = 600
SEED = 20261201

INF400 = "__sphfoam_fuzz_1e400__"
VALUES = ["inf", "-inf", "nan", INF400, -1, 0, -1e300, 1e300, 1e-300, 3,
          foamdict.QuotedString("[/bold]"), "oddWord", [1, 2, 3], {"type": "oddWord"}, True,
          foamdict.QuotedString("../../escaped"), foamdict.QuotedString("/abs/path"),
          foamdict.QuotedString(""), [], {}]
#: problems about a file as a whole (it cannot be read) need not name a key
WHOLE_FILE = ("syntax error", "not a text dictionary", "file not found", "required")


def _dictionaries(case: Path) -> list[Path]:
    files = [f for d in ("system", "constant") for f in sorted((case / d).iterdir())
             if f.is_file()]
    return files + study_dicts(case)


def _leaves(d, path=()):
    """Key paths of a parsed dictionary (sub-dictionaries too: they can be replaced whole)."""
    for k, v in d.items():
        if k == "FoamFile":
            continue
        yield (*path, k)
        if isinstance(v, dict):
            yield from _leaves(v, (*path, k))


def _mutate_structure(text: str, rng: random.Random) -> str | None:
    try:
        d = foamdict.parse(text)
    except foamdict.FoamDictError:
        return None
    leaves = list(_leaves(d))
    if not leaves:
        return None
    key = rng.choice(leaves)
    node = d
    for k in key[:-1]:
        node = node[k]
    op = rng.random()
    if op < 0.15:
        del node[key[-1]]
    elif op < 0.25:
        node[key[-1] + rng.choice(["s", "X", "_"])] = node.pop(key[-1])
    else:
        node[key[-1]] = rng.choice(VALUES)
    header = d.pop("FoamFile", None)
    try:
        out = foamdict.dumps(d, header=header if isinstance(header, dict) else None)
    except (ValueError, TypeError):
        return None
    return out.replace(INF400, "1e400")


def _mutate_text(text: str, rng: random.Random) -> bytes:
    b = text.encode()
    op = rng.randrange(5)
    if op == 0 and (b.count(b"{") or b.count(b"}")):
        idx = [i for i, c in enumerate(b) if c in b"{}"]
        i = rng.choice(idx)
        return b[:i] + b[i + 1:]
    if op == 1 and b.count(b";"):
        idx = [i for i, c in enumerate(b) if c == ord(";")]
        i = rng.choice(idx)
        return b[:i] + b[i + 1:]
    if op == 2:
        i = rng.randrange(len(b) + 1)
        return b[:i] + b"\xe9" + b[i:]
    if op == 3:
        return b[:rng.randrange(len(b) + 1)]
    lines = b.splitlines(keepends=True)
    i = rng.randrange(len(lines))
    return b"".join(lines[:i] + [lines[i]] + lines[i:])


def _clean(err: CaseError) -> list[str]:
    """What is wrong with an error's report (empty: one clean screen)."""
    bad = []
    if not err.problems:
        bad.append("a CaseError without problems")
    for p in err.problems:
        if not p.file:
            bad.append(f"problem without a file: {p}")
        elif not p.key and not any(w in p.message for w in WHOLE_FILE):
            bad.append(f"problem without a key: {p}")
    return bad


def test_fuzz_check_only_clean_errors(tmp_path):
    rng = random.Random(SEED)
    cases = {}
    for tut in sorted(p for p in TUTORIALS.iterdir() if (p / "system").is_dir()):
        dst = tmp_path / tut.name
        shutil.copytree(tut, dst, ignore=shutil.ignore_patterns("[1-9]*", "0*", "log.*",
                                                                "postProcessing", "study*"))
        check_case(dst)                         # every tutorial is valid as shipped
        cases[dst] = _dictionaries(dst)
    targets = [(c, f) for c, files in cases.items() for f in files]
    counts = {"valid": 0, "caseError": 0}
    failures = []
    t0 = time.perf_counter()
    for i in range(MUTATIONS):
        case, f = targets[i % len(targets)] if i < len(targets) else rng.choice(targets)
        original = f.read_bytes()
        text = original.decode()
        if rng.random() < 0.7:
            mutated = _mutate_structure(text, rng)
            data = mutated.encode() if mutated is not None else _mutate_text(text, rng)
        else:
            data = _mutate_text(text, rng)
        f.write_bytes(data)
        try:
            # the runs of a study are cloned and validated when the study dictionary is the
            # mutated file (a mutated case dictionary is validated as the base case)
            check_case(case, study_runs=f.parent == case)
            counts["valid"] += 1
        except CaseError as e:
            counts["caseError"] += 1
            failures += [f"{f.relative_to(tmp_path)} #{i}: {b}" for b in _clean(e)]
        except Exception as e:                  # noqa: BLE001 -- the point of the test
            failures.append(f"{f.relative_to(tmp_path)} #{i}: {type(e).__name__}: {e}"[:400])
        finally:
            f.write_bytes(original)
    elapsed = time.perf_counter() - t0
    print(f"fuzz: {MUTATIONS} mutations of {len(targets)} dictionaries in {elapsed:.1f} s: "
          f"{counts['caseError']} clean case errors, {counts['valid']} valid cases, "
          f"{len(failures)} failures")
    assert not failures, "\n".join(failures[:30])
    assert counts["caseError"] > MUTATIONS // 2     # the mutations do hit something


@pytest.mark.parametrize("value", ["inf", "-inf", "nan", "1e400"])
@pytest.mark.parametrize("key", ["writeInterval", "endTime", "deltaT", "startTime",
                                 "maxDeltaT", "maxCo"])
def test_non_finite_control_numbers_refused(tmp_path, key, value):
    case = tmp_path / "c"
    shutil.copytree(TUTORIALS / "hydrostaticTank", case)
    f = case / "system" / "controlDict"
    text = f.read_text()
    import re

    if re.search(rf"^{key}\s", text, re.M):
        text = re.sub(rf"^{key}\s+[^;]*;", f"{key} {value};", text, flags=re.M)
    else:
        text += f"\n{key} {value};\n"
    f.write_text(text)
    with pytest.raises(CaseError) as e:
        check_case(case)
    assert any(p.file == "system/controlDict" and p.key == key for p in e.value.problems), \
        str(e.value)
