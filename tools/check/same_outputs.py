#!/usr/bin/env python3
"""Compare two trees of tilth outputs: the same numbers and text, apart from what a run
cannot repeat (wall-clock times, dates, the build's commit, absolute paths of the trees).

A refactor that must not change behaviour is checked by running the same commands with the
old and the new binary (for example the fast test tier, whose cases write their outputs
under target/tmp) and comparing the two trees:

    python3 tools/check/same_outputs.py OLD_DIR NEW_DIR [WHERE_OLD_WAS_MADE ...]

JSON is compared value by value with volatile keys dropped; CSV cell by cell with volatile
columns dropped; text files (md, toml, svg, html, txt, csv without a header we know) line by
line after the two roots are replaced by a placeholder. MCAP files are compared by size only
(their metadata holds the commit). Exit status 1 lists every difference.
"""
import csv
import io
import json
import os
import re
import sys

VOLATILE_KEYS = {
    "created", "git_commit", "tilth", "wall_seconds", "setup_seconds", "seconds", "percent",
    "particle_steps_per_second", "time_breakdown", "started", "finished", "date", "host",
    "elapsed_seconds", "runs_per_hour", "recorder", "mcap_bytes", "bytes",
    # The core a run was pinned to: whichever was free.
    "cores",
    # A hash of the plan with its absolute paths: differs between two checkouts.
    "fingerprint",
}
VOLATILE_COLUMNS = {"wall_seconds", "wall_s", "seconds", "mcap"}
TEXT = (".md", ".toml", ".svg", ".html", ".txt", ".csv", ".sh", ".out")
# Lines that hold a time or the build (e.g. "wall time 1.2 s", "tilth 0a1b2c3d").
VOLATILE_LINE = re.compile(r"wall time|seconds|\bs/run\b|tilth [0-9a-f]{12}|generated|Generated")


def scrub(value):
    if isinstance(value, dict):
        return {k: scrub(v) for k, v in value.items() if k not in VOLATILE_KEYS}
    if isinstance(value, list):
        return [scrub(v) for v in value]
    return value


def first_difference(a, b, path="$"):
    """Where two JSON values first differ, as a path."""
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if a.get(k) != b.get(k):
                return first_difference(a.get(k), b.get(k), f"{path}.{k}")
    elif isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for k, (x, y) in enumerate(zip(a, b)):
            if x != y:
                return first_difference(x, y, f"{path}[{k}]")
    return f"{path}: {str(a)[:80]} vs {str(b)[:80]}"


def norm_text(text, roots):
    # Either tree's root in either file: a tree copied from where it was made still names
    # the place it was made.
    for root in roots:
        text = text.replace(os.path.abspath(root), "<ROOT>")
    return BUILD_HASH.sub("-<build>", text)


def csv_rows(text):
    rows = list(csv.reader(io.StringIO(text)))
    if not rows:
        return rows
    keep = [i for i, name in enumerate(rows[0]) if name not in VOLATILE_COLUMNS]
    return [[r[i] for i in keep if i < len(r)] for r in rows]


def compare_file(a, b, roots):
    if a.endswith((".mcap", ".mcap.partial")):
        # The metadata holds the commit; a killed run's partial file ends where it was killed.
        return None
    if a.endswith(".json"):
        try:
            ja = json.loads(norm_text(open(a).read(), roots))
            jb = json.loads(norm_text(open(b).read(), roots))
        except ValueError:
            pass
        else:
            return None if scrub(ja) == scrub(jb) else "JSON values differ: " + first_difference(scrub(ja), scrub(jb))
    if a.endswith(TEXT):
        ta = norm_text(open(a, errors="replace").read(), roots)
        tb = norm_text(open(b, errors="replace").read(), roots)
        if a.endswith(".csv"):
            return None if csv_rows(ta) == csv_rows(tb) else "CSV cells differ"
        la = [l for l in ta.splitlines() if not VOLATILE_LINE.search(l)]
        lb = [l for l in tb.splitlines() if not VOLATILE_LINE.search(l)]
        if la == lb:
            return None
        for k, (x, y) in enumerate(zip(la, lb)):
            if x != y:
                return f"line {k + 1}: {x[:100]!r} vs {y[:100]!r}"
        return f"{len(la)} vs {len(lb)} lines"
    return None if open(a, "rb").read() == open(b, "rb").read() else "bytes differ"


# The run cache's directories are named by a hash of the build (`repose-<16 hex>`).
BUILD_HASH = re.compile(r"-[0-9a-f]{16}(?=/|$)")


def files(root):
    """{path with build hashes masked: [real relative paths]} (several cache entries of one
    test mask to the same path)."""
    out = {}
    for dirpath, _, names in os.walk(root):
        for n in names:
            rel = os.path.relpath(os.path.join(dirpath, n), root)
            out.setdefault(BUILD_HASH.sub("-<build>", rel), []).append(rel)
    return out


def match(old, new, olds, news, roots):
    """Pairs each of `olds` with an equal one of `news`; the reasons of those left over."""
    left = list(news)
    problems = []
    for a in olds:
        for b in left:
            if compare_file(os.path.join(old, a), os.path.join(new, b), roots) is None:
                left.remove(b)
                break
        else:
            b = left[0] if left else None
            why = compare_file(os.path.join(old, a), os.path.join(new, b), roots) if b else "no counterpart"
            problems.append(f"{a}: {why}")
    return problems


def main():
    if len(sys.argv) < 3:
        print(__doc__)
        return 2
    old, new = sys.argv[1], sys.argv[2]
    fa, fb = files(old), files(new)
    roots = [new, old] + sys.argv[3:]
    problems = [f"only in {old}: {p}" for p in sorted(fa.keys() - fb.keys())]
    problems += [f"only in {new}: {p}" for p in sorted(fb.keys() - fa.keys())]
    same = 0
    for p in sorted(fa.keys() & fb.keys()):
        unmatched = match(old, new, fa[p], fb[p], roots)
        problems += unmatched
        same += len(fa[p]) - len(unmatched)
    for p in problems:
        print(p)
    print(f"same-outputs: {same} files equal, {len(problems)} difference(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
