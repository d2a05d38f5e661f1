#!/usr/bin/env python3
"""Checks that every document the sources and docs cite is in the repository.

Scans the tracked sources, scripts, data and docs for citations of Markdown documents (a file name ending in
.md, optionally with a section `§n` or `§n.m`) and fails when a cited document is not under docs/ (or the repository root),
or when a cited section has no heading `## n.` / `### n.m` in it. Generated results (docs/results/) are
checked like the rest. Prints one line per broken citation, `path:line: citation: what is wrong`, and exits 1
when there is any.
"""
import pathlib
import re
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
SUFFIXES = {".cpp", ".hpp", ".h", ".md", ".toml", ".sh", ".py", ".txt", ".cmake", ".json"}
CITATION = re.compile(r"(?<![\w/.-])((?:docs/|docs/results/)?[A-Za-z][\w-]*\.md)(?: §(\d+(?:\.\d+)*))?")
# Names that are not citations: the repository's README, and reports the commands write into their run folders
# (`sflsh sweep` → sweep.md, `sflsh validate` → table2.md, scripts' OUT.md arguments).
IGNORED_NAMES = {"README.md", "sweep.md", "table2.md", "OUT.md"}


def tracked_files():
    try:
        out = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout
        names = out.split()
    except (OSError, subprocess.CalledProcessError):
        names = [str(p.relative_to(ROOT)) for p in ROOT.rglob("*") if p.is_file() and "build" not in p.parts]
    return [ROOT / n for n in names if pathlib.Path(n).suffix in SUFFIXES]


def find_document(name):
    base = pathlib.Path(name).name
    for candidate in (ROOT / name, ROOT / "docs" / base, ROOT / "docs" / "results" / base, ROOT / base):
        if candidate.is_file():
            return candidate
    return None


def sections(document):
    numbers = set()
    for line in document.read_text(encoding="utf-8").splitlines():
        m = re.match(r"#{1,4}\s+(?:§\s*)?(\d+(?:\.\d+)*)[.\s]", line)
        if m:
            numbers.add(m.group(1))
    return numbers


def main():
    problems = []
    cache = {}
    for path in tracked_files():
        try:
            text = path.read_text(encoding="utf-8")
        except (UnicodeDecodeError, OSError):
            continue
        for number, line in enumerate(text.splitlines(), start=1):
            for m in CITATION.finditer(line):
                name, section = m.group(1), m.group(2)
                if pathlib.Path(name).name in IGNORED_NAMES and not section:
                    continue
                where = f"{path.relative_to(ROOT)}:{number}: {m.group(0)}"
                document = find_document(name)
                if document is None:
                    problems.append(f"{where}: no such document in the repository (expected docs/{pathlib.Path(name).name})")
                    continue
                if section:
                    if document not in cache:
                        cache[document] = sections(document)
                    if section not in cache[document]:
                        problems.append(f"{where}: {document.relative_to(ROOT)} has no section {section}")
    for p in problems:
        print(p)
    print(f"check_citations: {len(problems)} broken citation(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
