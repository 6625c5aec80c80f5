"""The README is a front door: at most 300 lines, its first lines the two
commands that work (``.ci/run`` runs exactly the second), what s7graph is not, and links
into ``docs/`` that resolve — files and the headings they point at; the links of the docs
pages and of bench/README.md resolve too."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
RUN = "pip install -e . && s7graph run examples/drill/drill.s7g --plant examples/drill/demo_plant.py --symbols examples/drill/symbols.txt --web"  # noqa: E501
TEST = "bash .ci/install && python -m pytest"
LINK = re.compile(r"\]\(([^)\s]+)\)")


def slug(heading: str) -> str:
    """GitHub's anchor of a Markdown heading."""
    text = heading.strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(page: Path) -> set[str]:
    text = page.read_text(encoding="utf-8")
    text = re.sub(r"```.*?```", "", text, flags=re.S)  # no headings inside code blocks
    return {slug(m[1]) for m in re.finditer(r"^#+ (.+)$", text, flags=re.M)}


def broken_links(page: Path) -> list[str]:
    """Relative links of ``page`` whose file, or heading, is not there."""
    text = re.sub(r"```.*?```", "", page.read_text(encoding="utf-8"), flags=re.S)
    broken = []
    for target in LINK.findall(text):
        if re.match(r"[a-z]+:", target):
            continue  # http(s), mailto: not ours to check
        file, _, anchor = target.partition("#")
        path = (page.parent / file).resolve() if file else page
        if not path.exists() or (anchor and path.suffix == ".md" and anchor not in anchors(path)):
            broken.append(target)
    return broken


def test_the_readme_is_at_most_300_lines() -> None:
    lines = README.read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 300, f"README.md has {len(lines)} lines"


def test_the_readme_begins_with_the_two_commands_and_ci_runs_the_second() -> None:
    text = README.read_text(encoding="utf-8")
    blocks = re.findall(r"```bash\n(.*?)\n```", text, flags=re.S)
    assert blocks[:2] == [RUN, TEST]
    assert text.index(TEST) < text.index("\n## ")  # both before the first section
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8").strip().splitlines()
    assert ci[-1] == TEST


def test_every_docs_link_of_the_readme_resolves() -> None:
    text = README.read_text(encoding="utf-8")
    docs = [t for t in LINK.findall(text) if t.startswith("docs/")]
    pages = {t.partition("#")[0] for t in docs if t.partition("#")[0].endswith(".md")}
    assert pages >= {
        f"docs/{name}.md"
        for name in ("cli", "chart-format", "semantics", "runtime", "online-change",
                     "import-export", "security", "performance", "architecture", "bus",
                     "durability", "state-file", "supervisor")
    }  # fmt: skip
    assert broken_links(README) == []
    assert "docs/status-view.png" in docs


PAGES = [*sorted((ROOT / "docs").glob("*.md")), ROOT / "bench" / "README.md"]


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_the_links_of_every_docs_page_resolve(page: Path) -> None:
    assert broken_links(page) == []


def test_the_readme_says_what_s7graph_is_not() -> None:
    text = README.read_text(encoding="utf-8")
    section = text.split("## What s7graph is not")[1].split("\n## ")[0]
    for words in ("not a fail-safe controller", "no safety function may depend on it",
                  "emergency stop", "guard interlocks", "outside the PLC", "safety relay",
                  "mixing plant"):  # fmt: skip
        assert words in section.replace("\n", " ").lower() or words in section, words
