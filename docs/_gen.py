"""Generate the documentation pages that derive from code and data, so they cannot rot.

- `docs/references.bib`: merged from the per-subpackage `docs/refs/*.bib` files;
- `docs/references.md`: rendered from `docs/references.bib`;
- `docs/thesis_inventory.json`: every chapter, section, numbered equation, table, figure and
  definition of the thesis, read from the thesis text itself (`thesis_inventory`);
- `docs/thesis-map.md`: each item of that inventory with the public functions whose docstrings
  cite it as a *thesis* item, or the reason, from `docs/thesis_reasons.toml`, why none does.

Run `python docs/_gen.py` after changing docstrings, bib files or reasons; `tests/docs/test_docs.py`
fails when a committed page differs from what this script produces. The thesis text is looked up
in `$RADIOMETRIA_THESIS` (a file), `thesis/*.txt` in the repository, then `../shared/thesis/*.txt`;
without it, the committed inventory is used as it is.
"""

import difflib
import hashlib
import importlib
import inspect
import json
import os
import re
import tomllib
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
INVENTORY = DOCS / "thesis_inventory.json"
REASONS = DOCS / "thesis_reasons.toml"
SUBPACKAGES = [
    "radiometry", "photometry", "colorimetry", "upsampling", "montecarlo", "scattering",
    "camera", "media", "render",
]  # fmt: skip
KINDS = ("sections", "equations", "tables", "figures")  # the items the map accounts for


def public_objects():
    """Yield `(subpackage, name, object)` for every public name of every subpackage."""
    for sub in SUBPACKAGES:
        mod = importlib.import_module(f"radiometria.{sub}")
        for name in sorted(dir(mod)):  # dir: names a module loads lazily (PEP 562) too
            if name.startswith("_"):
                continue
            obj = getattr(mod, name)
            if inspect.ismodule(obj):
                continue
            yield sub, name, obj


def figure_functions():
    """Yield `("figures", name, function)` for every registered thesis figure."""
    from radiometria.figures import FIGURES

    for name in sorted(FIGURES):
        yield "figures", name, FIGURES[name]


def object_docs(obj) -> list[str]:
    """The docstring of `obj`, and for a class those of its own public methods and properties."""
    docs = [inspect.getdoc(obj) or ""]
    if inspect.isclass(obj):
        for name, member in vars(obj).items():
            if name.startswith("_") and name != "__call__":
                continue
            if isinstance(member, (staticmethod, classmethod)):
                member = member.__func__
            if inspect.isfunction(member) or isinstance(member, property):
                docs.append(inspect.getdoc(member) or "")
    return [d for d in docs if d]


# ------------------------------------------------------------------------ the thesis text
# The text is a PDF-to-text conversion: numbered section headings stand on their own line
# ("2.2.1xy chromaticity diagram" included); chapters are "Chapter N" / "Appendix X" with the
# title on the same or the next line, or only their title (chapters 3-5, 7-9), so their numbers
# come from the table of contents; equation labels are `\tag{N}` or "(N)" at the end of a line;
# captions are "Table N: ..." / "Figure N: ..." lines; definitions are "Def. N. — ..." lines.

_HOMOGLYPHS = str.maketrans("АВСЕΙΑΒΕ", "ABCEIABE")  # Cyrillic and Greek capitals of the OCR
_TOC_ENTRY = re.compile(r"^(\d{1,2}(?:\.\d{1,2})*|[A-E])(?:\s+|$)(.*)$")
_PAGE = re.compile(r"^\d+(?:\s+\d+)?$")
_CHAPTER = re.compile(r"^(?:Chapter\s+(\d{1,2})|Appendix\s+([A-E]))\b\s*(.*)$")
_PART = re.compile(r"^Part\s+[IV]+\b")
_SECTION = re.compile(r"^((?:\d{1,2}|[A-E])(?:\.\d{1,2}){1,3})\s*([^\W\d_].{0,100})$")
_EQ_LABEL = re.compile(r"\\tag\{(\d{1,2}\.\d{1,3})\}|\((\d{1,2}\.\d{1,3})\)\s*\$*\s*$")
_CAPTION = re.compile(r"^(Table|Tabella|Figure|Figura)\s+(\d{1,2}\.\d{1,2})\s*:\s*(.*)$")
_DEFINITION = re.compile(r"^Def\.\s*(\d{1,2}\.\d{1,2}\.\d{1,2})\.")


def thesis_path() -> Path | None:
    """The thesis text file, or None where this checkout cannot see it."""
    found = [Path(os.environ["RADIOMETRIA_THESIS"])] if os.environ.get("RADIOMETRIA_THESIS") else []
    for folder in (ROOT / "thesis", ROOT.parent / "shared" / "thesis"):
        if folder.is_dir():
            found += sorted(folder.glob("*.txt"))
    return next((p for p in found if p.is_file()), None)


def number_key(number: str) -> list[int]:
    """Sort key of an item number: chapters 1-9 before appendices A-E, then numerically."""
    return [int(p) if p.isdigit() else 100 + ord(p) for p in number.split(".")]


def _table_of_contents(lines: list[str]) -> tuple[dict[str, str], int]:
    """`{number: title as printed}` of the contents pages, and the line where the body starts."""
    start = lines.index("Contents")
    toc: dict[str, str] = {}
    for i in range(start + 1, len(lines)):
        raw = lines[i].translate(_HOMOGLYPHS)
        if raw.strip() == "Part I":
            return toc, i
        fields = [f.strip() for f in re.sub(r"\\mathbf\{(\w)\}", r"\1", raw).split("\t")]
        fields = [f for f in fields if f]
        if fields and _PAGE.match(fields[-1]):
            fields.pop()
        m = _TOC_ENTRY.match(" ".join(fields[:1]))
        if not m:
            continue
        title = "".join([m.group(2), *fields[1:]]) if m.group(2) else "".join(fields[1:])
        # "C  Numeri Pseudocasuali e Algoritmi Vari C.1 Metodo di Gauss-Newton": two entries
        for j, part in enumerate(re.split(r"\s+(?=[A-E]\.\d+\s)", title)):
            number, _, rest = part.partition(" ") if j else (m.group(1), "", part)
            toc[number] = rest.strip()
    raise ValueError("thesis text: no 'Part I' line closes the table of contents")


def _headings(lines: list[str], start: int, toc: dict[str, str]) -> list[dict]:
    """Chapter, appendix and section headings of the body, in reading order."""
    chapters = {n: t for n, t in toc.items() if "." not in n}
    found: list[dict] = []
    for i in range(start, len(lines)):
        line = lines[i].strip()
        if line == "Bibliography":
            break
        m = _CHAPTER.match(line)
        if m:
            number = m.group(1) or m.group(2)
            entry = {"number": number, "title": m.group(3), "line": i + 1}
            if not m.group(3):  # the title stands on the next non-empty line
                j = next(j for j in range(i + 1, len(lines)) if lines[j].strip())
                entry.update(title=lines[j].strip(), title_line=j)
            found.append(entry)
            continue
        m = _SECTION.match(line)
        if m and "$" not in line and m.group(1).split(".")[0] in chapters:
            found.append({"number": m.group(1), "title": m.group(2).strip(), "line": i + 1})
    # Chapters printed as a title alone: the body line most like the contents' title.
    titled = {h["line"] - 1 for h in found} | {h.get("title_line") for h in found}
    for number, toc_title in chapters.items():
        if any(h["number"] == number for h in found):
            continue
        best, best_ratio = None, 0.75
        for i in range(start, len(lines)):
            line = lines[i].strip()
            if line == "Bibliography":
                break
            if i in titled or not line or len(line) > 100 or "$" in line:
                continue
            ratio = difflib.SequenceMatcher(None, line.lower(), toc_title.lower()).ratio()
            if ratio > best_ratio:
                best, best_ratio = i, ratio
        if best is not None:
            found.append({"number": number, "title": lines[best].strip(), "line": best + 1})
    found.sort(key=lambda h: h["line"])
    return found


def parse_thesis(text: str, name: str = "thesis.txt") -> dict:
    """The inventory of the thesis: sections, equations, tables, figures and definitions.

    Equation numbers run 1, 2, ... within a chapter; a number whose label the text lost (the
    conversion dropped it, or printed the previous one twice) is listed with `"line": null`.
    """
    lines = text.splitlines()
    toc, start = _table_of_contents(lines)
    heads = _headings(lines, start, toc)
    end = next(i for i in range(start, len(lines)) if lines[i].strip() == "Bibliography")
    head_lines = {h["line"] - 1 for h in heads}
    # a chapter's title printed on the line below "Chapter N" is no text of its own
    title_lines = {h["title_line"] for h in heads if "title_line" in h}

    def prose(i: int) -> bool:
        s = lines[i].strip()
        return bool(s) and i not in head_lines | title_lines and not _PART.match(s)

    sections = []
    for k, h in enumerate(heads):
        depth = h["number"].count(".")
        stop = next((g["line"] - 1 for g in heads[k + 1 :] if g["number"].count(".") <= depth), end)
        sections.append(
            {
                "number": h["number"],
                "title": h["title"],
                "line": h["line"],
                "title_only": not any(prose(i) for i in range(h["line"], stop)),
            }
        )
    for number, title in toc.items():  # listed in the contents, missing from the body
        if not any(s["number"] == number for s in sections):
            sections.append({"number": number, "title": title, "line": None, "title_only": True})
    sections.sort(key=lambda s: number_key(s["number"]))

    def section_at(i: int) -> str:
        return max((h for h in heads if h["line"] <= i + 1), key=lambda h: h["line"])["number"]

    labels: dict[str, dict] = {}
    tables, figures, definitions = [], [], []
    for i in range(start, end):
        line = lines[i].strip()
        for m in _EQ_LABEL.finditer(line):
            number = m.group(1) or m.group(2)
            labels.setdefault(number, {"number": number, "line": i + 1, "section": section_at(i)})
        m = _CAPTION.match(line)
        if m:
            item = {
                "number": m.group(2),
                "caption": m.group(3).strip(),
                "line": i + 1,
                "section": section_at(i),
            }
            (tables if m.group(1).startswith("Tab") else figures).append(item)
        m = _DEFINITION.match(line)
        if m:
            definitions.append({"number": m.group(1), "line": i + 1, "section": section_at(i)})
    equations = []
    for chapter in sorted({n.split(".")[0] for n in labels}, key=number_key):
        last = max(int(n.split(".")[1]) for n in labels if n.split(".")[0] == chapter)
        for j in range(1, last + 1):
            number = f"{chapter}.{j}"
            if number in labels:
                equations.append(labels[number])
                continue
            before = next(
                labels[f"{chapter}.{k}"] for k in range(j - 1, 0, -1) if f"{chapter}.{k}" in labels
            )
            after = next(
                labels[f"{chapter}.{k}"]
                for k in range(j + 1, last + 1)
                if f"{chapter}.{k}" in labels
            )
            between = sorted({before["section"], after["section"]}, key=number_key)
            equations.append({"number": number, "line": None, "section": "-".join(between)})
    return {
        "source": {"file": name, "sha256": hashlib.sha256(text.encode()).hexdigest()},
        "sections": sections,
        "equations": equations,
        "tables": sorted(tables, key=lambda t: number_key(t["number"])),
        "figures": sorted(figures, key=lambda t: number_key(t["number"])),
        "definitions": definitions,
    }


def thesis_inventory() -> dict:
    """The inventory parsed from the thesis text, or the committed one where the text is absent."""
    path = thesis_path()
    if path is None:
        return json.loads(INVENTORY.read_text())
    return parse_thesis(path.read_text(encoding="utf-8"), path.name)


def inventory_json(inventory: dict) -> str:
    return json.dumps(inventory, ensure_ascii=False, indent=1) + "\n"


# --------------------------------------------------------------- thesis citations in docstrings
# Two things cite the thesis: the `!!! note "Thesis"` block, where "Eq. 2.12-2.14", "section
# 2.3.1", "Table 3.2", "Ch. 8" or "Appendix C.1" all mean thesis items, and, anywhere else, a
# phrase that names the thesis ("thesis eq. 2.27", "(thesis ch. 5, app. A)", "thesis 2.1"),
# read up to its clause's end. Numbers of other works never count: "`Pharr2023` §4.6.6" in a
# `??? cite "References"` block names no thesis, and a keyword right after a backticked key
# ("following `Pharr2023` section 9.6") is skipped even inside a Thesis block.

_DOTTED = r"\d{1,2}\.\d{1,3}"
_SECTION_NUMBER = r"(?:\d{1,2}|[A-E])(?:\.\d{1,2}){0,3}"
_CITE_KINDS = {  # keyword -> (inventory list, keyword pattern, number pattern)
    "equation": ("equations", r"\b(?:eqs?\b\.?|equations?\b)", _DOTTED),
    "section": ("sections", r"(?:\b(?:sections?\b|secs?\b\.?)|§)", _SECTION_NUMBER),
    "chapter": ("sections", r"\b(?:chapters?\b|ch\b\.?)", r"\d{1,2}|[A-E]"),
    "appendix": ("sections", r"\b(?:appendix\b|appendices\b|app\b\.?)", r"[A-E](?:\.\d{1,2}){0,2}"),
    "table": ("tables", r"\b(?:tables?\b|tab\b\.)", _DOTTED),
    "figure": ("figures", r"\b(?:figures?\b|figs?\b\.?)", _DOTTED),
    "definition": ("definitions", r"\b(?:definitions?\b|defs?\b\.?)", r"\d{1,2}\.\d{1,2}\.\d{1,2}"),
    "footnote": (None, r"\bfootnotes?\b", r"\d{1,2}"),
}  # fmt: skip
_KEYWORD = re.compile(
    "|".join(f"(?P<{k}>{kw})" for k, (_, kw, _) in _CITE_KINDS.items()), re.IGNORECASE
)
_NUMBER = {
    k: re.compile(rf"\s*(?:\(\s*({num})\s*\)|({num}))(?![\w.]*\d)(?![A-Za-z])")
    for k, (_, _, num) in _CITE_KINDS.items()
}
_RANGE = re.compile(r"\s*(?:-|–|—|to)\s*")
_LIST = re.compile(r"\s*(?:\((?:[^()]|\([^()]*\))*\)\s*)?(?:,\s*(?:and\s+)?|and\s+|&\s*)")
_ADMONITION = re.compile(r'^(\s*)(?:!!!|\?\?\?\+?)\s*(\w+)(?:\s+"([^"]*)")?\s*$')
_THESIS_WORD = re.compile(r"\bthesis\b(?:'s)?", re.IGNORECASE)
_ABBREVIATIONS = {
    "eq",
    "eqs",
    "sec",
    "secs",
    "ch",
    "app",
    "fig",
    "figs",
    "tab",
    "def",
    "e.g",
    "i.e",
}


def _expand(a: str, b: str) -> list[str]:
    """Members of the range `a`-`b`: "2.12", "2.14" -> 2.12, 2.13, 2.14; "6", "7" -> 6, 7."""
    pa, pb = a.split("."), b.split(".")
    if pa[:-1] == pb[:-1] and pa[-1].isdigit() and pb[-1].isdigit():
        if int(pa[-1]) <= int(pb[-1]):
            return [".".join([*pa[:-1], str(i)]) for i in range(int(pa[-1]), int(pb[-1]) + 1)]
    if len(pa) == len(pb) == 1 and pa[0].isalpha() and pb[0].isalpha() and pa[0] <= pb[0]:
        return [chr(c) for c in range(ord(pa[0]), ord(pb[0]) + 1)]
    return [a, b]


def _chain(text: str, kind: str, pos: int) -> list[str]:
    """The numbers of one citation after its keyword: "2.12-2.14, 2.35", "(3.7)-(3.8), (3.13)"."""
    number = _NUMBER[kind]
    found: list[str] = []
    m = number.match(text, pos)
    while m:
        first = m.group(1) or m.group(2)
        pos = m.end()
        r = _RANGE.match(text, pos)
        m2 = number.match(text, r.end()) if r else None
        if m2:
            found += _expand(first, m2.group(1) or m2.group(2))
            pos = m2.end()
        else:
            found.append(first)
        sep = _LIST.match(text, pos)
        m = number.match(text, sep.end()) if sep else None
    return found


def _cite(text: str, citations: dict[str, set[str]]) -> None:
    """Add every thesis item that `text` (a Thesis block or a thesis phrase) cites."""
    for m in _KEYWORD.finditer(text):
        if text[: m.start()].rstrip().endswith("`"):
            continue  # "`Pharr2023` section 9.6": another work's numbering
        kind = m.lastgroup
        target = _CITE_KINDS[kind][0]
        if target is None:
            continue
        for number in _chain(text, kind, m.end()):
            citations.setdefault(target, set()).add(number)


def _clause_end(text: str, pos: int) -> int:
    """Where the phrase that starts at `pos` ends: `;`, an unopened `)`, a sentence end."""
    depth = 0
    for i in range(pos, len(text)):
        c = text[i]
        if c == "(":
            depth += 1
        elif c == ")":
            depth -= 1
            if depth < 0:
                return i
        elif c == ";" or text.startswith("\n\n", i):
            return i
        elif c == "." and re.match(r"\s+[A-Z`]|\s*$", text[i + 1 :]):
            word = re.search(r"[\w.]*$", text[:i]).group(0).lower()
            if word not in _ABBREVIATIONS:
                return i
    return len(text)


def _blocks(doc: str) -> tuple[list[str], list[str]]:
    """A docstring split into its Thesis blocks and the rest (prose and other blocks)."""
    thesis, prose, lines = [], [], doc.splitlines()
    i = 0
    while i < len(lines):
        m = _ADMONITION.match(lines[i])
        if not m:
            prose.append(lines[i])
            i += 1
            continue
        indent, title = len(m.group(1)), (m.group(3) or "").lower()
        j = i + 1
        while j < len(lines) and (
            not lines[j].strip() or len(lines[j]) - len(lines[j].lstrip()) > indent
        ):
            j += 1
        body = "\n".join(line.strip() for line in lines[i + 1 : j])
        (thesis if title == "thesis" else prose).append(body)
        i = j
    return thesis, ["\n".join(prose)]


def thesis_citations(doc: str) -> dict[str, set[str]]:
    """The thesis items a docstring cites: `{"equations": {"2.12", ...}, "sections": ...}`."""
    citations: dict[str, set[str]] = {}
    thesis, prose = _blocks(doc)
    for block in thesis:
        _cite(block, citations)
    for text in prose:
        for m in _THESIS_WORD.finditer(text):
            bare = re.match(r"\s+(\d{1,2}(?:\.\d{1,2}){1,3})\b", text[m.end() :])
            if bare:  # "thesis 2.1": a section
                citations.setdefault("sections", set()).add(bare.group(1))
            _cite(text[m.end() : _clause_end(text, m.end())], citations)
    return citations


def cite_keys(doc: str) -> set[str]:
    """BibTeX keys cited in a docstring: backticked `AuthorYear` tokens."""
    return set(_KEY.findall(doc))


_KEY = re.compile(r"`([A-Z][A-Za-z\-]+\d{4}[a-z]?)`")


def thesis_users() -> dict[str, dict[str, list[tuple[str, str]]]]:
    """`{kind: {number: [(subpackage, name), ...]}}` over public objects and figure functions."""
    users: dict[str, dict[str, set[tuple[str, str]]]] = {}
    for sub, name, obj in [*public_objects(), *figure_functions()]:
        for doc in object_docs(obj):
            for kind, numbers in thesis_citations(doc).items():
                for number in numbers:
                    users.setdefault(kind, {}).setdefault(number, set()).add((sub, name))
    order = lambda u: (u[0] == "figures", u)  # noqa: E731 -- API functions before figures
    return {k: {n: sorted(v, key=order) for n, v in d.items()} for k, d in users.items()}


def thesis_reasons() -> dict[str, dict[str, str]]:
    """The hand-written reasons why an item has no implementing function."""
    return tomllib.loads(REASONS.read_text(encoding="utf-8"))


# -------------------------------------------------------------------------------- the map page
_HEADINGS = {"sections": "section", "equations": "equation", "tables": "table", "figures": "figure"}


def _link(sub: str, name: str) -> str:
    if sub == "figures":  # no API page: the command that draws it
        return f"`radiometria figures --only {name}`"
    return f"[`{sub}.{name}`](api/{sub}.md#radiometria.{sub}.{name})"


def _label(kind: str, number: str) -> str:
    return f"({number})" if kind == "equations" else number


def _cell(users: list[tuple[str, str]], reason: str | None, limit: int = 8) -> str:
    if users:
        more = f" and {len(users) - limit} more" if len(users) > limit else ""
        return ", ".join(_link(s, n) for s, n in users[:limit]) + more
    if reason:
        return f"*{_escape(reason)}*"
    return "**no implementing function and no stated reason**"


def _children(sections: list[dict], number: str) -> list[str]:
    """The subsections one level below `number`."""
    depth = number.count(".") + 1
    return [
        s["number"]
        for s in sections
        if s["number"].startswith(number + ".") and s["number"].count(".") == depth
    ]


def _why_not(inventory: dict, kind: str, number: str, reasons: dict) -> str | None:
    """The stated reason for an item with no implementing function, or None."""
    reason = reasons.get(kind, {}).get(number)
    if reason is None and kind == "sections" and (parts := _children(inventory[kind], number)):
        reason = (
            f"through its sections {parts[0]}-{parts[-1]}"
            if len(parts) > 1
            else (f"through its section {parts[0]}")
        )
    return reason


def _escape(text: str) -> str:
    """Text for a table cell: pipes escaped; `$...$` stays maths (arithmatex renders it)."""
    return text.replace("|", "\\|").replace("<", "&lt;").strip()


def _short(text: str, n: int = 90) -> str:
    """A caption cut near `n` characters at a space outside inline maths."""
    if len(text) <= n:
        return _escape(text)
    cut = text[:n].rsplit(" ", 1)[0]
    if cut.count("$") % 2:
        cut = cut[: cut.rindex("$")].rstrip()
    return _escape(cut) + " …"


def thesis_map_markdown(inventory: dict | None = None) -> str:
    inventory = thesis_inventory() if inventory is None else inventory
    users = thesis_users()
    reasons = thesis_reasons()
    counts = {k: len(inventory[k]) for k in KINDS}
    lost = [e["number"] for e in inventory["equations"] if e["line"] is None]
    c = counts
    lines = [
        "# Thesis map",
        "",
        "Every numbered item of the thesis *Metodi di Monte Carlo Applicati Alla Computer",
        "Grafica*, and the public functions whose docstrings cite it.",
        "",
        f"The items are read from the thesis text itself (`{inventory['source']['file']}`)",
        f"into `docs/thesis_inventory.json`: {c['sections']} chapters and sections,",
        f"{c['equations']} equations, {c['tables']} tables and {c['figures']} figures.",
        'The citations are read from the `!!! note "Thesis"` block of each docstring and',
        'from phrases that name the thesis ("thesis eq. 2.27"); the numbers of other works',
        '("`Pharr2023` §4.6.6") never count. Where no function implements an item, the',
        "reason comes from `docs/thesis_reasons.toml`. Generated by `docs/_gen.py`; a test",
        "keeps this page current and fails on an item with neither an implementing function",
        "nor a reason.",
        "",
    ]
    if lost:
        lines += [
            f"Equations {', '.join(lost)} have no label in the text (the conversion to text lost",
            "them); their numbers follow from the numbering of their neighbours.",
            "",
        ]
    for kind in KINDS:
        lines += [f"## {kind.capitalize()}", ""]
        if kind == "sections":
            lines += ["| section | title | implemented by |", "|---|---|---|"]
        elif kind == "equations":
            lines += ["| equation | section | implemented by |", "|---|---|---|"]
        else:
            lines += [f"| {_HEADINGS[kind]} | caption | implemented by |", "|---|---|---|"]
        for item in inventory[kind]:
            number = item["number"]
            cell = _cell(
                users.get(kind, {}).get(number, []), _why_not(inventory, kind, number, reasons)
            )
            if kind == "sections":
                title = _escape(item["title"]) + (" (title only)" if item["title_only"] else "")
                middle = f"**{title}**" if "." not in number else title
            elif kind == "equations":
                middle = item["section"]
                if item["line"] is None:
                    middle += " (label lost in the text)"
            else:
                middle = _short(item["caption"])
            lines.append(f"| {_label(kind, number)} | {middle} | {cell} |")
        lines.append("")
    return "\n".join(lines)


def missing_items(inventory: dict) -> dict[str, list[str]]:
    """Items with neither an implementing function nor a stated reason, by kind."""
    users, reasons = thesis_users(), thesis_reasons()
    missing: dict[str, list[str]] = {}
    for kind in KINDS:
        for item in inventory[kind]:
            number = item["number"]
            if number in users.get(kind, {}) or _why_not(inventory, kind, number, reasons):
                continue
            missing.setdefault(kind, []).append(number)
    return missing


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
    inventory = thesis_inventory()
    INVENTORY.write_text(inventory_json(inventory), encoding="utf-8")
    (DOCS / "thesis-map.md").write_text(thesis_map_markdown(inventory), encoding="utf-8")
    for kind, numbers in missing_items(inventory).items():
        print(f"{kind} with no implementing function and no reason: {', '.join(numbers)}")


if __name__ == "__main__":
    main()
