"""mkdocs hook: the user guide pages are the Markdown files of docs/ themselves (the README and
the code link them there), added to the site beside docs/pages/. mkdocs refuses a site_dir
inside its docs_dir, so docs/ cannot be the docs_dir while the site goes to docs/site/."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from mkdocs.structure.files import File, Files

GUIDE = Path(__file__).resolve().parent


def on_files(files: Files, config: Any) -> Files:
    for page in sorted(GUIDE.glob("*.md")):
        files.append(File(page.name, src_dir=str(GUIDE), dest_dir=config["site_dir"],
                          use_directory_urls=config["use_directory_urls"]))
    return files
