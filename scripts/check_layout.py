#!/usr/bin/env python3
"""Checks the source layout's conventions (docs/design.md "Layout conventions"):

1. a source file includes its own header first (src/<m>/x.cpp ->
   rvlio/<m>/x.h or src/<m>/x.h; apps/x.cpp -> x.h), when that header exists;
2. in a source file, each named namespace is opened once at a given depth
   (one block, not closed and reopened; anonymous helper blocks may sit next
   to their users);
3. the test tree mirrors the sources: every top folder of test/ is a module
   of src/, `cli` (apps/), `support` or `data`.

Prints each violation as FILE: reason and exits 1 if there is one.

    python3 scripts/check_layout.py [REPO]
"""
import pathlib
import re
import sys

OPEN = re.compile(r"^\s*namespace\s+([\w:]+)\s*\{\s*(//.*)?$")
OPEN_ANON = re.compile(r"^\s*namespace\s*\{\s*(//.*)?$")
CLOSE = re.compile(r"^\s*\}\s*//\s*namespace")
INCLUDE = re.compile(r'^#include\s+[<"]([^>"]+)[>"]')
TEST_TOP_EXTRA = {"cli", "support", "data"}


def own_header(repo, source):
    rel = source.relative_to(repo)
    stem = source.stem
    if rel.parts[0] == "src":
        module = rel.parts[1]
        if (repo / "include" / "rvlio" / module / f"{stem}.h").exists():
            return {f"rvlio/{module}/{stem}.h"}
        if (source.parent / f"{stem}.h").exists():  # a private header beside it
            return {f"{stem}.h", f"rvlio/{module}/{stem}.h"}
    if rel.parts[0] == "apps" and (source.parent / f"{stem}.h").exists():
        return {f"{stem}.h"}
    return None


def check_own_header_first(repo, source):
    header = own_header(repo, source)
    if header is None:
        return []
    for line in source.read_text(errors="replace").splitlines():
        m = INCLUDE.match(line)
        if m:
            if m.group(1) not in header:
                return [f"{source.relative_to(repo)}: includes {m.group(1)} before its own header"]
            return []
    return []


def check_namespaces(repo, source):
    stack, seen, problems = [], set(), []
    for number, line in enumerate(source.read_text(errors="replace").splitlines(), 1):
        m = OPEN.match(line)
        if m or OPEN_ANON.match(line):
            name = m.group(1) if m else ""
            key = (tuple(stack), name)
            if name and key in seen:
                problems.append(f"{source.relative_to(repo)}:{number}: namespace {name} reopened")
            seen.add(key)
            stack.append(name)
        elif CLOSE.match(line) and stack:
            stack.pop()
    return problems


def check_test_tree(repo):
    modules = {p.name for p in (repo / "src").iterdir() if p.is_dir()}
    return [f"test/{p.name}: not a module of src/ (the test tree mirrors the sources)"
            for p in sorted((repo / "test").iterdir())
            if p.is_dir() and p.name not in modules | TEST_TOP_EXTRA
            and any(f.is_file() for f in p.rglob("*"))]  # git keeps no empty folder


def main():
    repo = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
    problems = []
    sources = sorted(list((repo / "src").rglob("*.cpp")) + list((repo / "apps").glob("*.cpp")))
    for source in sources:
        problems += check_own_header_first(repo, source)
    for source in sources:
        problems += check_namespaces(repo, source)
    problems += check_test_tree(repo)
    for p in problems:
        print(p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
