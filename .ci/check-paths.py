#!/usr/bin/env python3
"""Every repository path that the code and the docs cite must exist in a clone.

Scans tracked text files for repository paths (tokens that start with a top-level folder:
`kernel/`, `runner/`, `tools/`, `tests/`, `sweeps/`, `models/`, `data/`, `docs/`, `.ci/`) and for
relative Markdown links, and fails naming the file, line and path of each that does not exist.
Tokens with wildcards or placeholders (`*`, `{`, `NNN`, `<...>`) are patterns, not paths, and
are skipped; so are outputs under `runs/` and `target/`, which commands write.

    python3 .ci/check-paths.py        # exit 1 and one line per missing path
"""
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TOP = ("kernel", "runner", "tools", "tests", "sweeps", "models", "data", "docs", ".ci")
SCANNED = (".rs", ".md", ".toml", ".py", ".sh", ".yml", ".csv")
# A repository path: a top-level folder, then path characters; not preceded by a path
# character (so `shared/docs/x` or `runs/demo/docs/x` is not read as `docs/x`).
REPO_PATH = re.compile(r"(?<![\w./-])((?:%s)/[\w./+-]*[\w/])" % "|".join(re.escape(t) for t in TOP))
MD_LINK = re.compile(r"\]\(([^)\s#]+)(?:#[^)]*)?\)")
# Paths out of the repository (a sibling checkout's shared/ folder): absent in a clone.
OUTSIDE = re.compile(r"(?:\.\./)+shared/[\w./-]+")
# Bare names of the reference pages, which live in docs/.
BARE_REFERENCE = re.compile(r"(?<![\w/.-])(physics\.md|experiments\.md)")
PLACEHOLDER = re.compile(r"[*{}<>]|NNN|XXX")
# Path-like strings that are data, not citations: (file, path) -> why.
NOT_CITATIONS = {
    ("runner/tests/runner/measurements.rs", "models/v1.toml"): "a model name the test writes",
    ("runner/tests/runner/measurements.rs", "models/v2.toml"): "a model name the test writes",
}


def tracked_files():
    out = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True)
    this = Path(__file__).resolve().relative_to(ROOT).as_posix()
    return [ROOT / p for p in out.stdout.splitlines() if p.endswith(SCANNED) and p != this]


def exists(cited: str, source: Path) -> bool:
    """From the root, from the citing file's folder, or from its crate's folder (tests and
    build scripts name paths relative to CARGO_MANIFEST_DIR)."""
    bases = [ROOT, source.parent] + [p for p in source.parents if (p / "Cargo.toml").exists()]
    return any((base / cited).exists() for base in bases)


def check_file(path: Path):
    rel = path.relative_to(ROOT)
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        return
    for lineno, line in enumerate(text.splitlines(), 1):
        for m in REPO_PATH.finditer(line):
            cited = m.group(1).rstrip(".")
            if PLACEHOLDER.search(line[m.start():m.end() + 1]):
                continue
            if (rel.as_posix(), cited) in NOT_CITATIONS:
                continue
            if not exists(cited, path):
                yield f"{rel}:{lineno}: {cited} does not exist"
        for m in OUTSIDE.finditer(line):
            yield f"{rel}:{lineno}: {m.group(0)} is outside the repository"
        if path.suffix == ".md":
            for m in MD_LINK.finditer(line):
                target = m.group(1)
                if "://" in target or target.startswith("mailto:") or PLACEHOLDER.search(target):
                    continue
                resolved = (path.parent / target).resolve()
                if not resolved.exists():
                    yield f"{rel}:{lineno}: link {target} does not exist"
        for m in BARE_REFERENCE.finditer(line):
            if line[:m.start()].endswith("docs/"):
                continue
            yield f"{rel}:{lineno}: cite {m.group(1)} as docs/{m.group(1)}"


def main():
    problems = [p for f in tracked_files() for p in check_file(f)]
    for p in problems:
        print(p)
    if problems:
        print(f"{len(problems)} cited paths do not exist", file=sys.stderr)
        return 1
    print("every cited repository path exists")
    return 0


if __name__ == "__main__":
    sys.exit(main())
