"""The reference in docs/ documents every option the command line accepts: each long option of
every subcommand's --help is named on the page for the command line (docs/cli.md), the one on
the algorithms (docs/algorithms.md, where smooth, polygonize and render are described) or the
PCL page (docs/pcl.md, the preprocessing switches). The README links every page."""
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = ("cli.md", "algorithms.md", "pcl.md")


@pytest.mark.parametrize("command", ["triangulate", "smooth", "polygonize", "render", "inspect", "sample"])
def test_every_option_is_documented(cli, command):
    docs = "\n".join((ROOT / "docs" / page).read_text() for page in PAGES)
    options = set(re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]+)", cli(command, "--help").stdout)) - {"--help"}
    assert options, f"{command} --help lists no options"
    missing = sorted(o for o in options if not re.search(re.escape(o) + r"(?![a-z0-9-])", docs))
    assert not missing, f"particlemesh {command}: options in --help but not in docs/{{{','.join(PAGES)}}}: {missing}"


def test_the_readme_links_every_page():
    readme = (ROOT / "README.md").read_text()
    for page in sorted((ROOT / "docs").glob("*.md")):
        assert f"](docs/{page.name})" in readme, f"README.md does not link docs/{page.name}"
    assert len(readme.splitlines()) <= 250
