"""Generate the documentation pages that derive from code and data, so they cannot rot.

- `docs/references.bib`: merged from the per-subpackage `docs/refs/*.bib` files;
- `docs/references.md`: rendered from `docs/references.bib`;
- `docs/thesis-map.md`: every thesis equation and section that a public docstring cites,
  linked to the function, and the ones that no code implements yet, named as such.

Run `python docs/_gen.py` after changing docstrings or bib files; `tests/docs/test_docs.py` fails
when a committed page differs from what this script produces.
"""

import importlib
import inspect
import re
from pathlib import Path

DOCS = Path(__file__).resolve().parent
THESIS_EQUATIONS = [
    "1.1", "1.2", "1.3", "1.5", "1.6", "1.9", "1.10", "1.11", "1.12", "1.13", "1.14", "1.16",
    "1.17", "1.19", "1.22", "1.23", "1.24", "1.25", "2.1", "2.2", "2.3", "2.4", "2.5", "2.8",
    "2.10", "2.11", "2.12", "2.13", "2.14", "2.15", "2.16", "2.17", "2.18", "2.19", "2.20",
    "2.25", "2.26", "2.27", "2.28", "2.29", "2.30", "2.31", "2.32", "2.33", "2.34", "2.35",
    "3.4", "3.5", "3.6", "3.7", "3.8", "3.10", "3.12", "3.13", "3.14", "3.15", "3.16", "3.17",
    "3.18",
]  # fmt: skip
THESIS_SECTIONS = {
    "1.1": "Radiazione elettromagnetica",
    "1.2": "Dualità onda-particella",
    "1.3": "Introduzione all'assorbimento di radiazione",
    "1.4": "Radiometria",
    "1.5": "Radiazione di corpo nero",
    "2.1": "Fotometria",
    "2.2": "Colorimetria",
    "2.2.1": "xy chromaticity diagram",
    "2.2.2": "sRGB color space",
    "2.2.3": "Conversione da XYZ o RGB a SPD",
    "2.3": "Camera",
    "2.3.1": "Pinhole camera model",
    "2.3.2": "Filtrare image samples",
    "3.1": "Modellazione di superfici",
    "3.1.1": "Proprietà ottiche delle interfacce",
    "4": "Trasporto di energia elettromagnetica nel mezzo (title only)",
    "5": "Campionamento e ricostruzione con quasirandom number generation (title only)",
    "6": "Integrazione di Monte Carlo (title only)",
    "7": "Metodi di riduzione della varianza (title only)",
    "8": "Light transport: modello e surface reflection (title only)",
    "9": "Light transport: volume rendering e bidirectional methods (title only)",
    "A": "Fondamenti di probabilità e statistica (title only)",
    "B": "Algebra lineare applicata (title only)",
    "C": "Numeri pseudocasuali e algoritmi vari; C.1 metodo di Gauss-Newton",
    "D": "Codice Vulkan & HLSL (title only)",
    "E": "Implementazione dei concetti fisici (title only)",
}
SUBPACKAGES = [
    "radiometry", "photometry", "colorimetry", "upsampling", "montecarlo", "scattering",
    "camera", "render",
]  # fmt: skip
_EQ = re.compile(
    r"[Ee]q(?:s|uations?)?\.?\s*\(?(\d\.\d+)\)?(?:\s*(?:-|–|to|and)\s*\(?(\d\.\d+)\)?)?"
)
_SEC = re.compile(
    r"(?:[Ss]ection|[Ss]ec\.|§|ch\.|[Cc]hapter|[Aa]pp(?:endix|\.)?)\s*([1-9A-E](?:\.\d+){0,2})"
)
_KEY = re.compile(r"`([A-Z][A-Za-z\-]+\d{4}[a-z]?)`")


def public_objects():
    """Yield `(subpackage, name, object)` for every public name of every subpackage."""
    for sub in SUBPACKAGES:
        mod = importlib.import_module(f"radiometria.{sub}")
        for name in sorted(vars(mod)):
            if name.startswith("_"):
                continue
            obj = getattr(mod, name)
            if inspect.ismodule(obj):
                continue
            yield sub, name, obj


def _expand(a: str, b: str | None) -> list[str]:
    if b is None:
        return [a]
    ca, na = a.split(".")
    cb, nb = b.split(".")
    if ca != cb or int(nb) < int(na):
        return [a, b]
    return [f"{ca}.{i}" for i in range(int(na), int(nb) + 1)]


def cited_equations(doc: str) -> set[str]:
    """Thesis equation numbers cited in a docstring (only where the thesis is named)."""
    found: set[str] = set()
    for line in doc.splitlines():
        if "hesis" not in line and "Eq" not in line:
            continue
        for a, b in _EQ.findall(line):
            found.update(_expand(a, b or None))
    return found


def cited_sections(doc: str) -> set[str]:
    found: set[str] = set()
    for line in doc.splitlines():
        if "hesis" in line:
            found.update(_SEC.findall(line))
    return found


def cite_keys(doc: str) -> set[str]:
    """BibTeX keys cited in a docstring: backticked `AuthorYear` tokens."""
    return set(_KEY.findall(doc))


def _anchor(sub: str, name: str) -> str:
    return f"api/{sub}.md#radiometria.{sub}.{name}"


def thesis_map_markdown() -> str:
    eqs: dict[str, list[tuple[str, str]]] = {}
    secs: dict[str, list[tuple[str, str]]] = {}
    for sub, name, obj in public_objects():
        doc = inspect.getdoc(obj) or ""
        for eq in cited_equations(doc):
            eqs.setdefault(eq, []).append((sub, name))
        for sec in cited_sections(doc):
            secs.setdefault(sec, []).append((sub, name))
    key = lambda s: [int(p) if p.isdigit() else ord(p) for p in re.split(r"\.", s)]  # noqa: E731
    lines = [
        "# Thesis map",
        "",
        "Where each numbered equation and section of the thesis *Metodi di Monte Carlo Applicati",
        "Alla Computer Grafica* lives in the code. Generated from the docstrings by",
        "`docs/_gen.py`; a test keeps it current.",
        "",
        "## Equations",
        "",
        "| equation | implemented by |",
        "|---|---|",
    ]
    for eq in sorted(set(THESIS_EQUATIONS) | set(eqs), key=key):
        users = sorted(set(eqs.get(eq, [])))
        cell = (
            ", ".join(f"[`{s}.{n}`]({_anchor(s, n)})" for s, n in users)
            if users
            else "not implemented (background or derivation only)"
        )
        lines.append(f"| ({eq}) | {cell} |")
    lines += ["", "## Sections", "", "| section | title | implemented by |", "|---|---|---|"]
    for sec in sorted(set(THESIS_SECTIONS) | set(secs), key=key):
        users = sorted(set(secs.get(sec, [])))
        cell = (
            ", ".join(f"[`{s}.{n}`]({_anchor(s, n)})" for s, n in users[:8])
            + (f" and {len(users) - 8} more" if len(users) > 8 else "")
            if users
            else "not implemented yet"
        )
        lines.append(f"| {sec} | {THESIS_SECTIONS.get(sec, '')} | {cell} |")
    return "\n".join(lines) + "\n"


_ENTRY = re.compile(r"@(\w+)\s*\{\s*([^,\s]+)\s*,(.*?)\n\}", re.S)
_FIELD = re.compile(r"(\w+)\s*=\s*[{\"](.*?)[}\"]\s*,?\s*$", re.M)


def parse_bib(text: str) -> dict[str, dict[str, str]]:
    """A small BibTeX reader: one `field = {value}` per line, entries closed by a `}` line."""
    entries = {}
    for kind, key, body in _ENTRY.findall(text):
        fields = {k.lower(): re.sub(r"[{}]", "", v).strip() for k, v in _FIELD.findall(body)}
        fields["_type"] = kind.lower()
        entries[key] = fields
    return entries


def merged_bib() -> str:
    """All `docs/refs/*.bib` entries, deduplicated by key (first wins), sorted by key."""
    chunks: dict[str, str] = {}
    for path in sorted((DOCS / "refs").glob("*.bib")):
        for m in re.finditer(r"@\w+\s*\{\s*([^,\s]+)\s*,.*?\n\}", path.read_text(), re.S):
            chunks.setdefault(m.group(1), m.group(0).strip())
    return "\n\n".join(chunks[k] for k in sorted(chunks, key=str.lower)) + "\n"


def references_markdown(bib_text: str) -> str:
    lines = ["# References", "", "Rendered from `docs/references.bib` by `docs/_gen.py`.", ""]
    for key, f in sorted(parse_bib(bib_text).items(), key=lambda kv: kv[0].lower()):
        venue = (
            f.get("journal")
            or f.get("booktitle")
            or f.get("publisher")
            or f.get("howpublished", "")
        )
        parts = [f.get("author", ""), f"*{f.get('title', '')}*", venue, f.get("year", "")]
        text = ". ".join(p for p in parts if p)
        if "doi" in f:
            text += f". doi:{f['doi']}"
        elif "url" in f:
            text += f". <{f['url']}>"
        lines.append(f'- <a id="{key}"></a>**{key}**: {text}.')
    return "\n".join(lines) + "\n"


def main() -> None:
    bib = merged_bib()
    (DOCS / "references.bib").write_text(bib)
    (DOCS / "references.md").write_text(references_markdown(bib))
    (DOCS / "thesis-map.md").write_text(thesis_map_markdown())


if __name__ == "__main__":
    main()
