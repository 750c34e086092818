"""The documentation site's nav (mkdocs.yml) lists every page in docs/. `make docs` builds
the site strictly; this test needs no MkDocs (PyYAML comes with the test extras, via Dask)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import yaml

ROOT = Path(__file__).resolve().parents[1]

#: Pages in docs/ that the site leaves out of its nav on purpose (none yet).
NOT_IN_NAV: set[str] = set()


def nav_pages(nav: Any) -> list[str]:
    """The .md files a MkDocs nav names, in order: entries are a file, a {title: file} or a
    {section: [entries]}."""
    if isinstance(nav, str):
        return [nav] if nav.endswith(".md") else []
    if isinstance(nav, list):
        return [page for entry in nav for page in nav_pages(entry)]
    return [page for value in nav.values() for page in nav_pages(value)]


def test_nav_pages_walks_sections_titles_and_links() -> None:
    nav = yaml.safe_load(
        "- Start:\n    - index.md\n    - Tour: tour.md\n- Home: https://example.org\n- api.md\n"
    )
    assert nav_pages(nav) == ["index.md", "tour.md", "api.md"]


def test_every_docs_page_is_in_the_nav_once() -> None:
    config = yaml.safe_load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"))
    docs = ROOT / config["docs_dir"]
    pages = nav_pages(config["nav"])
    on_disk = {p.relative_to(docs).as_posix() for p in docs.rglob("*.md")}
    assert len(pages) == len(set(pages)), "a page is in the nav twice"
    assert set(pages) <= on_disk, f"nav entries without a page: {set(pages) - on_disk}"
    assert on_disk - NOT_IN_NAV == set(pages), f"pages not in the nav: {on_disk - set(pages)}"


def test_the_api_reference_documents_every_public_name() -> None:
    """Each ``cp.<name>`` (but the version) has its ``::: module.name`` entry in
    reference.md, and every entry resolves to the public object."""
    import importlib

    import casadi_posture as cp

    entries = re.findall(r"^::: ([\w.]+)$", (ROOT / "docs/reference.md").read_text(), re.M)
    documented = {}
    for entry in entries:
        module, name = entry.rsplit(".", 1)
        documented[name] = getattr(importlib.import_module(module), name)
    public = [name for name in cp.__all__ if name != "__version__"]
    assert set(public) - set(documented) == set(), "public names left out of reference.md"
    for name in public:
        assert documented[name] is getattr(cp, name), name
