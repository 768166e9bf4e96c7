"""The manual's site builds with MkDocs, warnings as errors: no page links to a missing page,
anchor or image (mkdocs.yml's validation settings make each of those a warning), and the Python
API page finds every object it names. The README's own links lead to files and anchors that exist."""

import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parent.parent


def build(config: Path, site: Path) -> subprocess.CompletedProcess:
    """``mkdocs build --strict``; never with ``-q``, which drops the warnings before --strict counts them."""
    return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(config),
                           "-d", str(site)], capture_output=True, text=True, cwd=ROOT, timeout=300)


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    folder = tmp_path_factory.mktemp("site")
    done = build(ROOT / "mkdocs.yml", folder)
    assert done.returncode == 0, done.stderr
    assert "WARNING" not in done.stderr and "ERROR" not in done.stderr, done.stderr
    return folder


def test_the_site_builds_without_warnings(site):
    assert (site / "index.html").is_file()
    api = (site / "reference" / "python" / "index.html").read_text(encoding="utf-8")
    assert 'id="rollball.simulation.simulate"' in api and "t_end" in api   # read from the docstrings


def test_every_page_is_in_the_navigation():
    config = yaml.load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"), Loader=yaml.BaseLoader)

    def pages(nav):
        for entry in nav:
            value = next(iter(entry.values())) if isinstance(entry, dict) else entry
            yield from (pages(value) if isinstance(value, list) else [value])

    listed = set(pages(config["nav"]))
    written = {str(p.relative_to(ROOT / "docs")) for p in (ROOT / "docs").rglob("*.md")}
    assert listed == written


@pytest.mark.parametrize("broken, message", [
    ("[the formats](missing.md)", "missing.md"),
    ("[the contact](guide.md#no-such-anchor)", "no-such-anchor"),
    ("![a picture](missing.png)", "missing.png"),
])
def test_a_broken_link_anchor_or_image_fails_the_build(tmp_path, broken, message):
    """The same validation settings, on two small pages: what the real build would meet."""
    config = yaml.load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"), Loader=yaml.BaseLoader)
    docs = tmp_path / "docs"
    docs.mkdir()
    (docs / "index.md").write_text(f"# Home\n\nSee {broken}.\n")
    (docs / "guide.md").write_text("# Guide\n\n## The contact {#contact}\n")
    small = {"site_name": "test", "docs_dir": str(docs), "strict": True, "validation": config["validation"],
             "markdown_extensions": ["attr_list"], "nav": [{"Home": "index.md"}, {"Guide": "guide.md"}]}
    (tmp_path / "mkdocs.yml").write_text(yaml.safe_dump(small))
    done = build(tmp_path / "mkdocs.yml", tmp_path / "site")
    assert done.returncode != 0 and message in done.stderr, done.stderr
    (docs / "index.md").write_text("# Home\n\nSee [the contact](guide.md#contact).\n")
    assert build(tmp_path / "mkdocs.yml", tmp_path / "site").returncode == 0


def test_the_readmes_links_lead_to_files_and_anchors_that_exist(site):
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    links = re.findall(r"\]\(([^)\s]+)\)", readme)
    assert len(links) >= 15
    for link in links:
        assert not link.startswith(("http:", "https:")), link   # none needs the network
        target, _, anchor = link.partition("#")
        assert (ROOT / target).exists(), link
        if anchor:
            page = site / Path(target).relative_to("docs").with_suffix("") / "index.html"
            assert f'id="{anchor}"' in page.read_text(encoding="utf-8"), link
