"""MkDocs hooks of the docs site (mkdocs.yml): the pages stay plain Markdown that reads the
same on a repository browser, and the site gets them with their links made to work there.

- ``index.md`` is the README (README.md), and ``examples.md`` and ``changelog.md`` are
  examples/README.md and CHANGELOG.md, generated into the site from those files.
- A link whose target is a file of the repository outside docs/ is rewritten: to README.md,
  examples/README.md or CHANGELOG.md it goes to their page; to any other file (a module, the
  LICENSE) it becomes its text, with the file's path where the text does not name it, or a
  link into ``repo_url`` where mkdocs.yml sets one. A
  link from one of the generated pages into docs/ is made relative to that page.
- A link whose target does not exist is left as written, so that ``mkdocs build --strict``
  reports it.
"""

from __future__ import annotations

import posixpath
import re
from pathlib import Path

from mkdocs.structure.files import File

ROOT = Path(__file__).resolve().parent
#: Site pages generated from files outside docs/: site path -> repository path.
GENERATED = {
    "index.md": "README.md",
    "examples.md": "examples/README.md",
    "changelog.md": "CHANGELOG.md",
}
PAGE_OF = {repo: site for site, repo in GENERATED.items()}
LINK = re.compile(r"(!?)\[((?:[^\[\]]|\[[^\[\]]*\])*)\]\(([^()\s]+)\)")
FENCE = re.compile(r"^(```|~~~)")


def on_files(files, config):
    """Add the pages generated from README.md, examples/README.md and CHANGELOG.md."""
    for site, repo in GENERATED.items():
        old = files.get_file_from_path(site)
        if old is not None:  # docs/index.md, if someone adds one, gives way to the README
            files.remove(old)
        text = (ROOT / repo).read_text(encoding="utf-8")
        files.append(File.generated(config, site, content=text))
    return files


def on_page_markdown(markdown, page, config, files):
    """Every link of the page with its target made to work in the site."""
    site = page.file.src_uri
    repo = GENERATED.get(site, f"docs/{site}")
    out, fenced = [], False
    for line in markdown.splitlines(keepends=True):
        if FENCE.match(line.lstrip()):
            fenced = not fenced
        out.append(line if fenced else LINK.sub(lambda m: _link(m, site, repo, config), line))
    return "".join(out)


def _link(m: re.Match, site: str, repo: str, config) -> str:
    bang, text, target = m.groups()
    if re.match(r"^[a-z][a-z0-9+.-]*:|^#|^/", target):  # a URL, an anchor, an absolute path
        return m.group(0)
    path, _, anchor = target.partition("#")
    to = posixpath.normpath(posixpath.join(posixpath.dirname(repo), path))
    if not (ROOT / to).exists() or to.startswith(".."):
        return m.group(0)  # not found: mkdocs says so
    if to in PAGE_OF:
        new = PAGE_OF[to]
    elif to.startswith("docs/"):
        new = to.removeprefix("docs/")
    elif config.get("repo_url"):
        kind = "tree" if (ROOT / to).is_dir() else "blob"
        return f"{bang}[{text}]({config['repo_url'].rstrip('/')}/{kind}/HEAD/{to})"
    elif text.strip("`") in (to, posixpath.basename(to)):
        return text
    else:
        return f"{text} (`{to}`)"
    rel = posixpath.relpath(new, posixpath.dirname(site) or ".")
    return f"{bang}[{text}]({rel}{'#' + anchor if anchor else ''})"
