"""The app's help pages are the user guide's pages of the same names (scripts/help_pages.py makes
them): the manual's site and the Help menu cannot say different things."""

import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def help_pages():
    spec = importlib.util.spec_from_file_location("scripts_help_pages", ROOT / "scripts" / "help_pages.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("page", ["model", "plots", "compare"])
def test_the_shipped_help_page_is_made_from_the_guide(help_pages, page):
    shipped = (ROOT / "resources" / "help_pages" / f"{page}.html").read_text(encoding="utf-8")
    assert shipped == help_pages.page_html(page), "run: .venv/bin/python scripts/help_pages.py"


def test_every_topic_the_app_names_is_an_anchor_of_its_page(help_pages):
    """The app opens pages at anchors ("model.html#contact"); the help window scrolls to <a name>."""
    sources = "\n".join(p.read_text(encoding="utf-8") for p in (ROOT / "app").glob("*.py"))
    topics = set(re.findall(r'"((?:model|plots|compare)\.html)#([\w-]+)"', sources))
    assert len(topics) >= 10
    for page, anchor in topics:
        html = help_pages.page_html(page[:-5])
        assert f'<a name="{anchor}"></a>' in html, (page, anchor)


def test_links_between_help_pages_become_the_apps_addresses(help_pages):
    html = help_pages.page_html("plots")
    assert 'href="compare.html#true-error"' in html and 'href="model.html#munthe-kaas"' in html
    assert ".md" not in " ".join(re.findall(r'href="([^"]*)"', html))


def test_a_help_page_linking_outside_the_help_pages_is_refused(help_pages, tmp_path, monkeypatch):
    (tmp_path / "model.md").write_text("# The model\n\nSee [the formats](../reference/formats.md).\n")
    monkeypatch.setattr(help_pages, "GUIDE", tmp_path)
    with pytest.raises(ValueError, match=r"model\.md: the link '\.\./reference/formats\.md' leads outside"):
        help_pages.page_html("model")
