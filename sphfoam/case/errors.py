"""Errors a user can act on: file, key path, bad value, valid choices, did-you-mean."""

from __future__ import annotations

import difflib
from dataclasses import dataclass, field

from pydantic import ValidationError


@dataclass
class Problem:
    file: str
    key: str
    message: str

    def __str__(self) -> str:
        where = f"{self.file}: {self.key}" if self.key else self.file
        return f"{where}: {self.message}"


@dataclass
class CaseError(Exception):
    """One or more problems in a case; printed as one screen by the CLI."""

    problems: list[Problem] = field(default_factory=list)

    @classmethod
    def single(cls, file: str, key: str, message: str) -> "CaseError":
        return cls([Problem(file, key, message)])

    def __str__(self) -> str:
        return "\n".join(str(p) for p in self.problems)


def did_you_mean(word: str, choices) -> str:
    close = difflib.get_close_matches(str(word), [str(c) for c in choices], n=1, cutoff=0.5)
    return f"; did you mean {close[0]!r}?" if close else ""


def _fields_at(model_cls, loc) -> list[str]:
    """Valid keys of the (sub)model at ``loc`` (best effort, for unknown-key messages)."""
    cls = model_cls
    for part in loc:
        f = getattr(cls, "model_fields", {}).get(part)
        if f is None:
            break
        ann = f.annotation
        cls = ann if hasattr(ann, "model_fields") else None
        if cls is None:
            return []
    return list(getattr(cls, "model_fields", {}) or [])


def _short(value, limit: int = 80) -> str:
    """``repr(value)``, cut to ``limit`` characters (a value that swallowed the rest of a
    file, e.g. after a missing ';', must not fill the screen)."""
    r = repr(value)
    return r if len(r) <= limit else r[:limit - 5] + " ...)"


def from_validation(err: ValidationError, file: str, model_cls=None, prefix: str = "") -> CaseError:
    """Translate pydantic's errors into :class:`Problem` lines."""
    problems = []
    for e in err.errors():
        loc = [str(p) for p in e["loc"]]
        key = ".".join(([prefix] if prefix else []) + loc)
        kind = e["type"]
        bad = e.get("input")
        if kind == "extra_forbidden":
            valid = _fields_at(model_cls, e["loc"][:-1]) if model_cls else []
            msg = f"unknown key '{loc[-1]}'{did_you_mean(loc[-1], valid)}"
            if valid:
                msg += f" valid keys: {', '.join(valid)}"
        elif kind in ("literal_error", "enum"):
            expected = e.get("ctx", {}).get("expected", "")
            choices = [c.strip().strip("'") for c in expected.replace(" or ", ",").split(",")]
            choices = [c for c in choices if c]
            shown = f"'{bad}'" if isinstance(bad, str) and len(bad) <= 80 else _short(bad)
            msg = (f"{shown} is not valid{did_you_mean(bad, choices)} "
                   f"valid choices: {', '.join(choices)}")
        elif kind == "missing":
            msg = "required key is missing"
        else:
            msg = f"{e['msg']} (got {_short(bad)})" if bad is not None and \
                not isinstance(bad, dict) else e["msg"]
        problems.append(Problem(file, key, msg))
    return CaseError(problems)
