#!/usr/bin/env python3
"""Checks that the Swift tests run every call JawTrackKit makes into the library.

Reads the library's entry points from the uniffi-generated bindings (functions, methods and
constructors, with their first argument label) and from the C header (`jt_*`), finds each line
of JawTrackKit's sources that calls one, and fails if `swift test` never executed such a line,
per the coverage report of `llvm-cov show` (text). Run by `ios/swift-on-linux.sh test`:

    check-library-calls.py BINDINGS.swift HEADER.h COVERAGE.txt
"""

import re
import sys
from pathlib import Path


def entry_points(bindings: str, header: str) -> dict:
    """Call patterns (e.g. `updateSettings(settings:`, `Tracker(settings:`, `jt_track_luma(`)."""
    patterns = {}
    owner = None
    for line in bindings.splitlines():
        m = re.match(r"open class (\w+)", line)
        if m:
            owner = m.group(1)
        m = re.match(r"(?:open|public)(?: static)? func `?(\w+)`?\((\w+)?", line)
        if m and not m.group(1).startswith(("FfiConverter", "uniffi")):
            name, label = m.group(1), m.group(2)
            patterns[f"{name}({label}:" if label else f"{name}()"] = name
        m = re.match(r"public convenience init\((\w+)", line)
        if m and owner:
            patterns[f"{owner}({m.group(1)}:"] = f"{owner}.init"
    for name in set(re.findall(r"\b(jt_\w+)\(", header)):
        patterns[f"{name}("] = name
    return patterns


def coverage(text: str) -> dict:
    """(file name, line) -> execution count, for lines llvm-cov counts."""
    counts, current = {}, None
    for line in text.splitlines():
        if line.endswith(".swift:") and not line.startswith(" "):
            current = Path(line[:-1]).name
            continue
        m = re.match(r"\s*(\d+)\|\s*([0-9.]+[kMG]?)\|(.*)$", line)
        if current and m:
            value = m.group(2)
            scale = {"k": 1e3, "M": 1e6, "G": 1e9}.get(value[-1], 1)
            counts[(current, int(m.group(1)))] = (float(value.rstrip("kMG")) * scale, m.group(3))
    return counts


def main() -> int:
    bindings, header, report = (Path(p).read_text() for p in sys.argv[1:4])
    patterns = entry_points(bindings, header)
    counts = coverage(report)
    called, missed = set(), []
    for (file, line), (count, source) in sorted(counts.items()):
        code = source.split("//")[0]
        for pattern, name in patterns.items():
            # A call whose arguments start on the next line ends its line with `name(`.
            if pattern in code or code.rstrip().endswith(pattern.split("(")[0] + "("):
                if count > 0:
                    called.add(name)
                else:
                    missed.append(f"{file}:{line}: {name} never ran under swift test: {source.strip()}")
    if not counts:
        print("check-library-calls: the coverage report has no JawTrackKit line", file=sys.stderr)
        return 1
    for m in missed:
        print(m, file=sys.stderr)
    print(f"library calls in JawTrackKit run by the Swift tests: {len(called)} entry points "
          f"({', '.join(sorted(called))}); {len(missed)} call sites never ran")
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
