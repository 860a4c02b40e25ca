#!/usr/bin/env python3
"""Points source comments at docs/design.md instead of the founding DESIGN.md.

The founding design document (DESIGN.md, sections 1-9) was never in the
repository; docs/design.md replaces it with its own numbering. This script
rewrites every "DESIGN.md section N" / "DESIGN.md sections N and M" /
"DESIGN.md sections N-M" (also when a comment line break falls between
"DESIGN.md" and "section") into "docs/design.md section N'" with the mapping
below. It is idempotent: run it again after merging branches that added new
references. Lines that become longer than 100 columns are listed (wrap them
by hand).

    python3 scripts/dev/design_refs.py          # rewrite in place
    python3 scripts/dev/design_refs.py --check  # exit 1 if a reference is left
"""
import pathlib
import re
import sys

# Founding DESIGN.md section -> docs/design.md section.
SECTION_MAP = {
    1: 1,   # Layout and module boundaries   -> Modules and their dependencies
    2: 2,   # Conventions                    -> Conventions
    3: 4,   # The shared measurement model   -> The shared measurement model
    4: 5,   # RV modules                     -> The RV pass
    5: 6,   # Estimators                     -> The backends
    6: 7,   # The command-line contract      -> The command-line contract
    7: 8,   # Evaluation                     -> Evaluation
    8: 9,   # Style, by example              -> Style
    9: 10,  # Build notes for Debian 12      -> Build notes
}

ROOT = pathlib.Path(__file__).resolve().parents[2]
SUFFIXES = {".h", ".hpp", ".cpp", ".cc", ".py", ".sh", ".yaml", ".yml", ".cmake", ".txt", ".md"}
SKIP_DIRS = {".git", "docs"}  # docs/ holds design.md itself
SKIP_FILES = {pathlib.Path(__file__).resolve()}

# "DESIGN.md" (not preceded by "docs/"), optional comment line break, then
# "section N" or "sections N and M" / "sections N-M".
REF = re.compile(
    r"(?<!docs/)DESIGN\.md(?P<gap>(?:\s*\n\s*(?://|#)\s*|\s+))"
    r"(?P<word>sections?)\s+(?P<a>\d+)(?:(?P<sep>\s+and\s+|-)(?P<b>\d+))?")
LEFT = re.compile(r"(?<!docs/)(?<!/)DESIGN\.md")


def new_ref(m):
    a = SECTION_MAP[int(m.group("a"))]
    text = f"docs/design.md{m.group('gap')}{m.group('word')} {a}"
    if m.group("b"):
        text += f"{m.group('sep')}{SECTION_MAP[int(m.group('b'))]}"
    return text


def files():
    for path in ROOT.rglob("*"):
        rel = path.relative_to(ROOT)
        if not path.is_file() or path.resolve() in SKIP_FILES:
            continue
        if rel.parts[0] in SKIP_DIRS or rel.parts[0].startswith("build"):
            continue
        if path.suffix in SUFFIXES or path.name == "CMakeLists.txt":
            yield path


def main():
    check = "--check" in sys.argv[1:]
    changed, left, long_lines = [], [], []
    for path in files():
        try:
            text = path.read_text()
        except UnicodeDecodeError:
            continue
        new = REF.sub(new_ref, text)
        rel = path.relative_to(ROOT)
        for i, line in enumerate(new.splitlines(), 1):
            if LEFT.search(line):
                left.append(f"{rel}:{i}: {line.strip()}")
            if new != text and "docs/design.md" in line and len(line) > 100:
                long_lines.append(f"{rel}:{i}: {len(line)} columns")
        if new != text:
            changed.append(str(rel))
            if not check:
                path.write_text(new)
    verb = "would change" if check else "changed"
    print(f"design_refs: {verb} {len(changed)} files")
    for line in long_lines:
        print(f"design_refs: longer than 100 columns: {line}")
    for line in left:
        print(f"design_refs: reference without a section: {line}")
    if check and (changed or left):
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
