"""The app's help pages, made from the user guide: ``docs/guide/NAME.md`` becomes
``resources/help_pages/NAME.html`` for NAME in model, plots and compare, so the manual's site and the
app's Help menu say the same thing. After editing one of those pages run

    .venv/bin/python scripts/help_pages.py

and commit the HTML with it; ``tests/test_help_pages.py`` fails while they differ. The app needs
nothing of this at run time (Qt shows the HTML); ``markdown`` comes with the docs tools.

A help page may link to the other help pages (``compare.md#true-error``) and to web addresses only:
the app's Help window has no other pages to show.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import markdown

ROOT = Path(__file__).resolve().parent.parent
GUIDE = ROOT / "docs" / "guide"
OUT = ROOT / "resources" / "help_pages"
PAGES = ("model", "plots", "compare")
# Qt's rich text has its own defaults; the equation tables' style is the site's (docs/css/equations.css)
BASE_STYLE = """body { font-size: 11pt; line-height: 130%; }
h1 { font-size: 17pt; } h2 { font-size: 14pt; margin-top: 18px; }
td { padding: 3px 10px 3px 0; vertical-align: top; }
"""
STYLE = ROOT / "docs" / "css" / "equations.css"
LINK = re.compile(r'href="([^"]*)"')


def _link(page: str, target: str) -> str:
    """The help window's address of a link on ``page``; a link it cannot follow is refused."""
    if target.startswith(("http://", "https://", "#")):
        return target
    name, _, anchor = target.partition("#")
    stem = name[:-3] if name.endswith(".md") else None
    if stem not in PAGES:
        raise ValueError(f"docs/guide/{page}.md: the link {target!r} leads outside the help pages "
                         f"({', '.join(p + '.md' for p in PAGES)}) and web addresses")
    return f"{stem}.html" + (f"#{anchor}" if anchor else "")


def page_html(page: str) -> str:
    """The help page ``page`` (``"model"``, ``"plots"`` or ``"compare"``) as the app shows it."""
    source = (GUIDE / f"{page}.md").read_text(encoding="utf-8")
    body = markdown.markdown(source, extensions=["attr_list", "tables"], output_format="html")
    body = LINK.sub(lambda m: f'href="{_link(page, m.group(1))}"', body)
    # Qt's browser scrolls to <a name=...>; the site's pages give headings an id
    body = re.sub(r'<(h[1-6]) id="([^"]+)">', r'<\1 id="\2"><a name="\2"></a>', body)
    style = BASE_STYLE + STYLE.read_text(encoding="utf-8")
    return f"<html><head><style>\n{style}</style></head><body>\n{body}\n</body></html>\n"


def main() -> int:
    for page in PAGES:
        (OUT / f"{page}.html").write_text(page_html(page), encoding="utf-8")
        print(f"help_pages: wrote resources/help_pages/{page}.html", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
