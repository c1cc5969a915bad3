"""The generated reference documentation is up to date with the code."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from sphfoam import docs, registry
from sphfoam.case import schemas

DOCS = Path(__file__).resolve().parents[1] / "docs"
TUTORIALS = Path(__file__).resolve().parents[1] / "tutorials"


@pytest.mark.parametrize("name", ["models.md", "dictionaries.md"])
def test_generated_docs_are_current(name):
    path = DOCS / name
    assert path.is_file(), f"docs/{name} is missing: run python -m sphfoam.docs"
    assert path.read_text() == docs.generated()[name], \
        f"docs/{name} is stale: run python -m sphfoam.docs"


def test_generated_docs_start_with_the_header():
    for name, text in docs.generated().items():
        assert text.splitlines()[0] == docs.HEADER, name


def test_every_model_is_in_models_md():
    text = (DOCS / "models.md").read_text()
    for family, models in registry.families().items():
        assert f"## {family}\n" in text, family
        for name in models:
            assert f"`{name}`" in text, f"{family} {name!r} missing from docs/models.md"


def test_every_dictionary_key_is_in_dictionaries_md():
    text = (DOCS / "dictionaries.md").read_text()
    for key in schemas.ControlDict.model_fields:
        assert f"| `{key}` |" in text, f"controlDict {key!r} missing from docs/dictionaries.md"
    for family in schemas.SPH_FAMILIES:
        assert f"| `{family}` |" in text, family


def test_fallback_descriptions_name_existing_fields():
    """Every hand-written fallback description refers to a field that still exists."""
    models = {}
    for obj in vars(schemas).values():
        if isinstance(obj, type) and hasattr(obj, "model_fields"):
            models[obj.__qualname__] = obj
    for fam in registry.families().values():
        for cls in fam.values():
            for klass in cls.Coeffs.__mro__:
                if hasattr(klass, "model_fields"):
                    models[klass.__qualname__] = klass
    for owner, keys in docs.FALLBACK_DESCRIPTIONS.items():
        assert owner in models, f"FALLBACK_DESCRIPTIONS: no schema {owner!r}"
        for key in keys:
            assert key in models[owner].model_fields, f"FALLBACK_DESCRIPTIONS: {owner}.{key}"


def test_user_guide_dictionary_excerpts_match_the_tutorials():
    """Dictionary excerpts quoted in the user guide are verbatim parts of a tutorial file."""
    guide = (DOCS / "user-guide.md").read_text()
    # text files only: a study run inside a tutorial leaves pictures and binary fields there
    sources = [f.read_text(errors="replace")
               for f in [*TUTORIALS.glob("*/*/*"), *TUTORIALS.glob("*/*")]
               if f.is_file() and f.suffix not in (".py", ".png", ".json")]
    blocks = re.findall(r"^```[^\n]*\n(.*?)^```", guide, flags=re.S | re.M)
    excerpts = [b for b in blocks if re.search(r"^\w+\s+[^:\n]*;", b, flags=re.M)
                and not b.lstrip().startswith("$")]
    assert len(excerpts) >= 3
    for b in excerpts:
        assert any(b.strip() in s for s in sources), f"not in any tutorial:\n{b}"
