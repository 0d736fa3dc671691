#!/usr/bin/env python3
"""Syntax check of the app's Swift without a Swift compiler.

Parses every hand-written `.swift` file under `ios/` (or the files and folders given) with
tree-sitter's Swift grammar and fails on any ERROR or MISSING node, naming file:line:col and
the node. It proves the files parse, not that they type-check: the app is compiled only by Xcode.

    pip install tree-sitter==0.26.1 tree-sitter-swift==0.7.4
    python3 ios/check-swift.py [PATH ...]

The uniffi-generated bindings (`jawtrack.swift`) and build folders are skipped.
Known false positive of the grammar: an `#if` block wrapping only an attribute; don't write one.
"""

import sys
from pathlib import Path

try:
    import tree_sitter_swift
    from tree_sitter import Language, Parser
except ImportError:
    sys.exit("check-swift: pip install tree-sitter==0.26.1 tree-sitter-swift==0.7.4")

SKIPPED_FILES = {"jawtrack.swift"}
SKIPPED_DIRS = {".build", "build", "DerivedData", ".swiftpm", "JawTrackFFI.xcframework", "JawTrack.xcodeproj"}


def swift_files(roots):
    """The .swift files under `roots`, minus generated bindings and build folders."""
    for root in roots:
        if root.is_file():
            yield root
            continue
        for path in sorted(root.rglob("*.swift")):
            if path.name in SKIPPED_FILES:
                continue
            if any(part in SKIPPED_DIRS for part in path.relative_to(root).parts):
                continue
            yield path


def problems(tree):
    """Every ERROR or MISSING node, descending only into subtrees that hold one."""
    found = []
    stack = [tree.root_node]
    while stack:
        node = stack.pop()
        if node.is_error or node.is_missing:
            found.append(node)
            continue
        stack.extend(child for child in reversed(node.children) if child.has_error or child.is_missing)
    return found


def describe(node, source):
    """How a bad node reads in the report: its kind and the start of its text."""
    kind = f"MISSING {node.type}" if node.is_missing else "ERROR"
    text = source[node.start_byte : min(node.end_byte, node.start_byte + 60)].decode("utf-8", "replace")
    text = " ".join(text.split())
    return f"{kind}: {text!r}" if text else kind


def main(argv):
    here = Path(__file__).resolve().parent
    roots = [Path(a) for a in argv] if argv else [here]
    for root in roots:
        if not root.exists():
            print(f"check-swift: {root} does not exist", file=sys.stderr)
            return 2
    parser = Parser(Language(tree_sitter_swift.language()))
    files = lines = 0
    failures = []
    for path in swift_files(roots):
        source = path.read_bytes()
        files += 1
        lines += source.count(b"\n") + (0 if source.endswith(b"\n") or not source else 1)
        tree = parser.parse(source)
        for node in problems(tree):
            row, col = node.start_point
            failures.append(f"{path}:{row + 1}:{col + 1}: {describe(node, source)}")
    for failure in failures:
        print(failure)
    if files == 0:
        print("check-swift: no Swift files found", file=sys.stderr)
        return 1
    status = "FAILED" if failures else "ok"
    print(f"check-swift: {files} files, {lines} lines, {len(failures)} problems: {status}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
