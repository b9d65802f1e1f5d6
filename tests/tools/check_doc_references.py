#!/usr/bin/python3
"""Every reference to a section of a Markdown page resolves.

The tree points readers at sections by name, in prose and in comments:

    (docs/results.md, "Networks: MobileNetV2 and ERFNet")
    /// ... (docs/method.md, "Cells that pay").
    ([results.md](results.md), "When
    climbing is slower than level flight")
    (docs/journal/2026-11-oracle.md "The paper's configuration")
    `../ensemble-dubai/README.md`, section "Test-time mirror"

that is, a path ending in `.md` (relative to the repository root or to the referring file; in
backticks or a Markdown link's target too), then a comma, blanks, a line break with its comment
marker (`//`, `///`, `#`, `*`), the word "section" or an opening parenthesis, then a title in
double quotes, which may run over lines. A title resolves when the page has a section whose
name starts with it, blanks and comment markers collapsed: a heading (`#` to `######`, outside
fenced code; a prefix is enough, as headings carry suffixes such as "(beyond the paper)"), or a
bold lead-in, the bold words that open a paragraph or a list item (`**What any choice of z can
buy.**`), which the pages use as named sub-sections.

Also checked, in Markdown files: every relative link target exists (`[x](journal/README.md)`,
`![fig](figures/a.png)`), and every `page.md#anchor` names a heading of that page (GitHub's
anchors: lower case, punctuation dropped, blanks to '-').

Files: `git ls-files`, untracked files that git does not ignore included (without git: every
file but .git, build and out), less tests/mavlink/node_modules and files that are not UTF-8
text. Exit 1 listing file:line and what is missing; exit 0 with a count.

Usage: check_doc_references.py [REPOSITORY_ROOT]   (default: two folders above this file)
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

SKIPPED_PREFIXES = ("tests/mavlink/node_modules/",)

# A path ending in .md, an optional anchor, closing backtick and link parenthesis, then what may
# stand between it and the quoted title. The separator must not be empty: `"$dir/t.md"` in a
# shell script is a path in quotes, not a reference.
REFERENCE = re.compile(
    r'(?P<path>[A-Za-z0-9_.][A-Za-z0-9_./-]*\.md)(?:#[\w-]*)?`?\)?'
    r'(?P<sep>[ \t]*,?[ \t]*(?:\n[ \t]*(?:/{2,3}|#+|\*)?[ \t]*)?'
    r'(?:(?:section|paragraph)[ \t]+)?\(?)'
    r'"(?P<title>[^"\s][^"]{0,300}?)"'
)
COMMENT_MARKER = re.compile(r"\n[ \t]*(?:/{2,3}|#+|\*)?[ \t]*")
HEADING = re.compile(r"^(#{1,6})[ \t]+(.+?)[ \t]*#*[ \t]*$")
BOLD_LEAD = re.compile(r"^[ \t]*(?:(?:[-*+]|\d+\.)[ \t]+)?\*\*(.+?)\*\*")
FENCE = re.compile(r"^[ \t]*(```|~~~)")
LINK = re.compile(r"!?\[[^\]\n]*\]\(([^)\s]+)(?:[ \t]+\"[^\"]*\")?\)")


def tracked_files(root: Path) -> list[str]:
    try:
        command = ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"]
        out = subprocess.run(command, cwd=root, capture_output=True, check=True).stdout.decode()
        files = [f for f in out.split("\0") if f]
    except (OSError, subprocess.CalledProcessError):
        files = []
        for folder, dirs, names in os.walk(root):
            rel = Path(folder).relative_to(root)
            if rel == Path("."):
                dirs[:] = [d for d in dirs if d not in (".git", "build", "out")]
            files += [(rel / n).as_posix() for n in names]
    return sorted(f for f in files if not f.startswith(SKIPPED_PREFIXES))


def read_text(path: Path) -> str | None:
    try:
        data = path.read_bytes()
    except OSError:
        return None
    if b"\0" in data[:8192]:
        return None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return None


def normalise(text: str) -> str:
    """Blanks and comment markers at line starts collapsed to one space; Markdown's ` and **
    dropped."""
    text = COMMENT_MARKER.sub(" ", text)
    text = text.replace("`", "").replace("**", "")
    return " ".join(text.split())


def github_anchor(heading: str) -> str:
    text = heading.replace("`", "").lower()
    text = "".join(c for c in text if c.isalnum() or c in " -_")
    return text.replace(" ", "-")


class Page:
    """A Markdown page's section names: headings, then bold lead-ins."""

    def __init__(self, text: str):
        self.headings: list[str] = []
        self.leads: list[str] = []
        inside = False
        previous = ""
        for line in text.splitlines():
            if FENCE.match(line):
                inside = not inside
                previous = "```"
                continue
            if inside:
                continue
            heading = HEADING.match(line)
            if heading:
                self.headings.append(normalise(heading.group(2)))
            else:
                lead = BOLD_LEAD.match(line)
                opens = previous.strip() == "" or HEADING.match(previous) or \
                    re.match(r"^[ \t]*(?:[-*+]|\d+\.)[ \t]+", line)
                if lead and opens:
                    self.leads.append(normalise(lead.group(1)))
            previous = line
        self.anchors = {github_anchor(h) for h in self.headings}

    def has_section(self, title: str) -> bool:
        return any(name.startswith(title) for name in self.headings + self.leads)


def line_of(text: str, offset: int) -> int:
    return text.count("\n", 0, offset) + 1


def main() -> int:
    root = Path(sys.argv[1]).resolve() if len(sys.argv) > 1 else \
        Path(__file__).resolve().parent.parent.parent
    files = tracked_files(root)
    existing = set(files)
    pages: dict[str, Page | None] = {}

    def page(rel: str) -> Page | None:
        if rel not in pages:
            text = read_text(root / rel)
            pages[rel] = Page(text) if text is not None else None
        return pages[rel]

    def resolve(referrer: str, target: str, from_root: bool = True) -> str | None:
        for base in (os.path.dirname(referrer), "") if from_root else (os.path.dirname(referrer),):
            candidate = os.path.normpath(os.path.join(base, target)).replace(os.sep, "/")
            if candidate in existing or (root / candidate).is_dir():
                return candidate
        return None

    problems: list[str] = []
    checked = 0
    for rel in files:
        text = read_text(root / rel)
        if text is None:
            continue
        for m in REFERENCE.finditer(text):
            if not m.group("sep"):
                continue
            path, title = m.group("path"), normalise(m.group("title"))
            where = f"{rel}:{line_of(text, m.start('path'))}"
            target = resolve(rel, path)
            if target is None:
                if path.startswith("docs/") or "/docs/" in path:
                    problems.append(f'{where}: {path} does not exist (reference to "{title}")')
                continue
            checked += 1
            target_page = page(target)
            if target_page is None or not target_page.has_section(title):
                problems.append(f'{where}: {path} has no section "{title}"')
        if not rel.endswith(".md"):
            continue
        # Relative links of a Markdown page, outside fenced code.
        inside = False
        for number, line in enumerate(text.splitlines(), 1):
            if FENCE.match(line):
                inside = not inside
                continue
            if inside:
                continue
            for link in LINK.finditer(line):
                url = link.group(1)
                if re.match(r"^[a-z][a-z0-9+.-]*:", url) or url.startswith("#"):
                    continue
                file_part, _, anchor = url.partition("#")
                target = resolve(rel, file_part, from_root=False)
                checked += 1
                if target is None:
                    problems.append(f"{rel}:{number}: link target {file_part} does not exist")
                elif anchor and target.endswith(".md"):
                    target_page = page(target)
                    if target_page is None or anchor not in target_page.anchors:
                        problems.append(f"{rel}:{number}: {file_part} has no heading #{anchor}")
    for problem in problems:
        print(problem)
    if problems:
        print(f"check_doc_references: {len(problems)} of {checked} references do not resolve")
        return 1
    print(f"check_doc_references: {checked} references resolve")
    return 0


if __name__ == "__main__":
    sys.exit(main())
