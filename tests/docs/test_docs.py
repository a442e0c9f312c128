"""Documentation integrity: citations resolve, public names are documented, pages are current."""

import importlib.util
import inspect
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"


@pytest.fixture(scope="module")
def gen():
    spec = importlib.util.spec_from_file_location("_docs_gen", DOCS / "_gen.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["_docs_gen"] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def public(gen):
    return list(gen.public_objects())


def test_references_resolve(gen, public):
    keys = set(gen.parse_bib((DOCS / "references.bib").read_text()))
    missing = {}
    for sub, name, obj in public:
        for key in gen.cite_keys(inspect.getdoc(obj) or ""):
            if key not in keys:
                missing.setdefault(key, []).append(f"{sub}.{name}")
    assert not missing, f"cite keys missing from docs/references.bib: {missing}"


def test_public_functions_documented(gen, public):
    """Every public function and class has a docstring that cites a source and states units."""
    undocumented, uncited, unitless = [], [], []
    for sub, name, obj in public:
        if not (inspect.isfunction(obj) or inspect.isclass(obj)):
            continue
        doc = inspect.getdoc(obj) or ""
        if len(doc) < 20:
            undocumented.append(f"{sub}.{name}")
            continue
        if inspect.isclass(obj) and issubclass(obj, Exception):
            continue  # an error type documents when it is raised, not a formula
        if not (gen.cite_keys(doc) or "hesis" in doc):
            uncited.append(f"{sub}.{name}")
        params = [p for p in inspect.signature(obj).parameters if p not in ("self", "key")]
        if inspect.isfunction(obj) and params and "[" not in doc:
            unitless.append(f"{sub}.{name}")
    assert not undocumented, f"public names without a docstring: {undocumented}"
    assert not uncited, f"docstrings citing neither the thesis nor a bib key: {uncited}"
    assert not unitless, f"docstrings with arguments but no [unit]: {unitless}"


def test_generated_pages_are_current(gen):
    bib = gen.merged_bib()
    assert (DOCS / "references.bib").read_text() == bib, "run `python docs/_gen.py`"
    assert (DOCS / "references.md").read_text() == gen.references_markdown(bib)
    assert (DOCS / "thesis-map.md").read_text() == gen.thesis_map_markdown()


def test_thesis_map_links_core_equations(gen):
    text = (DOCS / "thesis-map.md").read_text()
    for eq, fn in [("1.24", "radiometry.planck"), ("2.27", "upsampling."), ("3.18", "scattering.")]:
        row = next(line for line in text.splitlines() if line.startswith(f"| ({eq})"))
        assert fn in row, f"eq. {eq} is not linked to {fn}: {row}"
