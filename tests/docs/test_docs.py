"""Documentation integrity: citations resolve, public names are documented, pages are current."""

import importlib.util
import inspect
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
ALL_KINDS = ("sections", "equations", "tables", "figures", "definitions")


@pytest.fixture(scope="module")
def gen():
    spec = importlib.util.spec_from_file_location("_docs_gen", DOCS / "_gen.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["_docs_gen"] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def inventory(gen):
    return gen.thesis_inventory()


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


def test_thesis_inventory_is_current(gen):
    """The committed inventory is what the parser reads from the thesis text today."""
    path = gen.thesis_path()
    if path is None:
        pytest.skip("the thesis text is not in this checkout; the committed inventory stands")
    fresh = gen.parse_thesis(path.read_text(encoding="utf-8"), path.name)
    assert gen.INVENTORY.read_text(encoding="utf-8") == gen.inventory_json(fresh), (
        "run `python docs/_gen.py`"
    )


def test_thesis_inventory_holds_the_thesis(inventory):
    """Spot checks of the parse against the text: every label, caption and heading kind."""
    numbers = {k: [i["number"] for i in inventory[k]] for k in ALL_KINDS}
    assert numbers["equations"] == [
        *(f"1.{i}" for i in range(1, 26)),
        *(f"2.{i}" for i in range(1, 36)),
        *(f"3.{i}" for i in range(1, 19)),
    ]
    lost = {e["number"] for e in inventory["equations"] if e["line"] is None}
    assert lost == {"2.21", "2.23", "2.24", "3.11"}  # labels the text conversion dropped
    assert numbers["tables"] == ["1.1", "1.2", "2.1", "2.2", "3.1", "3.2"]
    assert numbers["figures"] == ["2.1", "2.2", "2.3", "2.4", "2.5", "2.6", "3.1", "3.2"]
    sections = {s["number"]: s for s in inventory["sections"]}
    for number in [*"123456789", *"ABCDE", "1.4.2", "2.1.1", "2.2.1", "2.3.2", "3.1.1", "C.1"]:
        assert number in sections, number
    assert {n for n, s in sections.items() if s["title_only"]} == {*"456789", *"ABCDE", "C.1"}
    assert sections["3"]["title"] == "Modelli di Fonti Luminose e Superfici"
    assert sections["C.1"]["title"] == "Metodo di Gauss-Newton"
    assert not any(n in sections for n in ("4.6.6", "3.8.3"))  # pbrt's numbering


NOTE = '!!! note "Thesis"\n    '


@pytest.mark.parametrize(
    ("doc", "expected"),
    [
        (
            NOTE + "Eq. 2.12-2.14, section 2.2.",
            {"equations": {"2.12", "2.13", "2.14"}, "sections": {"2.2"}},
        ),
        (
            NOTE + "Thesis eq. (1.14)-(1.15), eq. (1.21), section 1.4.1 and 1.4.2.",
            {"equations": {"1.14", "1.15", "1.21"}, "sections": {"1.4.1", "1.4.2"}},
        ),
        (
            NOTE + 'Section 3.1 ("Specular"), 3.1.1, eq. (3.7)-(3.8), (3.13)-(3.14).',
            {"equations": {"3.7", "3.8", "3.13", "3.14"}, "sections": {"3.1", "3.1.1"}},
        ),
        (
            NOTE + "Section 2.2.1 (locus), eq. 1.24, 2.12-2.13; table 2.1, fig. 2.2.",
            {
                "equations": {"1.24", "2.12", "2.13"},
                "sections": {"2.2.1"},
                "tables": {"2.1"},
                "figures": {"2.2"},
            },
        ),
        (
            NOTE + "Ch. 8 (ray casting); chapters 6-7; Appendix C.1; app. A and C.",
            {"sections": {"8", "6", "7", "C.1", "A", "C"}},
        ),
        (
            NOTE + "Section 1.4 (def. 1.4.5), footnote 5; as `Pharr2023` section 9.6.",
            {"sections": {"1.4"}, "definitions": {"1.4.5"}},
        ),
        ('Summary.\n\n??? cite "References"\n    `Pharr2023` §4.6.6, §3.8.3; `Owen1995`.', {}),
        (
            '??? cite "References"\n    `Sobol1967`; `Pharr2023` §8.7.\n    Thesis ch. 5.',
            {"sections": {"5"}},
        ),
        ("Closely (thesis 2.1). See section 9.6 of `Pharr2023` and eq. 5.", {"sections": {"2.1"}}),
        (
            "The estimate (thesis, after eq. 2.34). With weights, eq. 7 of `Veach1995`.",
            {"equations": {"2.34"}},
        ),
    ],
)
def test_thesis_citations_are_read_from_thesis_phrases_only(gen, doc, expected):
    assert gen.thesis_citations(doc) == expected


def test_thesis_citations_exist(gen, inventory):
    """Every thesis number that a docstring cites is a number the thesis has."""
    have = {k: {i["number"] for i in inventory[k]} for k in ALL_KINDS}
    wrong = {}
    for sub, name, obj in [*gen.public_objects(), *gen.figure_functions()]:
        for doc in gen.object_docs(obj):
            for kind, numbers in gen.thesis_citations(doc).items():
                for number in sorted(numbers - have[kind]):
                    wrong.setdefault(f"{sub}.{name}", []).append(f"{kind[:-1]} {number}")
    assert not wrong, f"docstrings citing thesis items the thesis does not have: {wrong}"


def test_every_thesis_item_is_implemented_or_explained(gen, inventory):
    """Each section, equation, table and figure has an implementing function or a reason."""
    missing = gen.missing_items(inventory)
    assert not missing, (
        f"thesis items with no implementing function (a docstring citing it in its Thesis "
        f"note) and no reason in docs/thesis_reasons.toml: {missing}"
    )


def test_thesis_reasons_are_current(gen, inventory):
    """Each reason names a thesis item, and no item both has an implementation and a reason."""
    have = {k: {i["number"] for i in inventory[k]} for k in gen.KINDS}
    users, reasons = gen.thesis_users(), gen.thesis_reasons()
    assert set(reasons) <= set(gen.KINDS), f"unknown tables in thesis_reasons.toml: {set(reasons)}"
    unknown = {k: sorted(set(r) - have[k]) for k, r in reasons.items() if set(r) - have[k]}
    assert not unknown, f"reasons for items the thesis does not have: {unknown}"
    stale = {k: sorted(set(r) & set(users.get(k, {}))) for k, r in reasons.items()}
    stale = {k: v for k, v in stale.items() if v}
    assert not stale, f"implemented now, delete their reasons from thesis_reasons.toml: {stale}"


def test_thesis_map_links_core_equations(gen):
    text = (DOCS / "thesis-map.md").read_text()
    for eq, fn in [("1.24", "radiometry.planck"), ("2.27", "upsampling."), ("3.18", "scattering.")]:
        row = next(line for line in text.splitlines() if line.startswith(f"| ({eq})"))
        assert fn in row, f"eq. {eq} is not linked to {fn}: {row}"
