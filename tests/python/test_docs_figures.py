"""The documentation's figures: every image that README.md or docs/*.md shows exists,
every file in docs/figures/ is shown by some document (an unreferenced figure is a
stale picture nobody reads, and nobody regenerates), and scripts/figures, which
regenerates them, knows every one of them.

Independent reference: the file system and the Markdown texts themselves (image links
`![alt](path)` and HTML `<img src="path">`, resolved from the document's own
directory, as a Markdown renderer resolves them)."""
import re

from conftest import ROOT

FIGURES = ROOT / "docs" / "figures"
IMAGE = re.compile(r"!\[[^\]]*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)|<img\s[^>]*src=[\"']([^\"']+)[\"']", re.I)


def documents():
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def shown_images():
    """(document, link as written, resolved path) of every image the documents show."""
    found = []
    for doc in documents():
        for m in IMAGE.finditer(doc.read_text(encoding="utf-8")):
            link = m.group(1) or m.group(2)
            if re.match(r"[a-z]+://", link):
                continue      # an image on the web: not ours to check
            found.append((doc, link, (doc.parent / link.split("#")[0]).resolve()))
    return found


def test_every_shown_image_exists():
    missing = [f"{doc.relative_to(ROOT)}: {link}" for doc, link, path in shown_images() if not path.is_file()]
    assert not missing, "images shown but missing: " + "; ".join(missing)


def test_every_figure_is_shown():
    shown = {path for _, _, path in shown_images()}
    figures = sorted(p for p in FIGURES.iterdir() if p.is_file())
    assert figures, FIGURES
    unshown = [p.name for p in figures if p.resolve() not in shown]
    assert not unshown, "in docs/figures but shown by no document: " + ", ".join(unshown)


def test_scripts_figures_makes_every_figure():
    """scripts/figures's two lists (cheap, slow) name exactly the files of docs/figures."""
    text = (ROOT / "scripts" / "figures").read_text()
    names = set()
    for var in ("cheap", "slow"):
        m = re.search(rf"^{var}=\(([^)]*)\)", text, re.M)
        assert m, f"scripts/figures has no {var}=( ... ) list"
        names |= set(m.group(1).split())
    on_disk = {p.stem for p in FIGURES.glob("*.png")}
    assert names == on_disk, {"made but not in docs/figures": sorted(names - on_disk),
                              "in docs/figures but not made": sorted(on_disk - names)}
