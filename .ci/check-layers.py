#!/usr/bin/env python3
"""Structure checks for the Rust crates (issue 73's rules), failing CI on a violation.

1. Layers: inside each crate, a top-level module may use (`crate::m`) only modules of its own
   or a lower layer, as LAYERS lists them; no cycle between top-level modules of any crate.
   Crates are layered by Cargo itself (it refuses cycles); `runner/` nests its layers as
   modules of the `tilth` crate, so that order is checked here.
2. A thin CLI: the modules under THIN_CLI parse and print; they read and write no files
   (`std::fs`, `File`, `OpenOptions`), which is the library's work.
3. Sizes: no non-test `.rs` file over 600 lines (outside `#[cfg(test)]` modules) and no
   function over 120 lines outside tests. Test code (tests/ directories, `tests.rs` files,
   `#[cfg(test)]` modules) is exempt.

The scan is lexical: comments, strings and char literals are blanked, then `crate::` paths
(including `use crate::{a, b}` groups) and brace-matched `fn` bodies are read.
Run: python3 .ci/check-layers.py   (exit 1 on any violation, listing each).
"""
import os
import re
import sys

MAX_FILE_LINES = 600
MAX_FN_LINES = 120
THIN_CLI = "runner/src/cli"
FILE_IO = re.compile(r"\bstd::fs\b|\bfs::|\bFile::|\bOpenOptions\b")

# Lowest layer first. A module may depend on its own layer and any layer below it.
LAYERS = {
    "runner/src": [
        {"memory", "progress", "provenance", "text"},
        {"config"},
        {"lab"},
        {"record", "sweep"},
        {"study"},
        {"cli"},
    ],
}
CRATES = ["kernel/src", "tools/src", "runner/src", "tests/src"]


def blank(src):
    """The source with comments, strings and char literals replaced by spaces (lines kept)."""
    out, i, n = [], 0, len(src)
    keep_lines = lambda s: re.sub(r"[^\n]", " ", s)
    while i < n:
        if src.startswith("//", i):
            j = src.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
            continue
        if src.startswith("/*", i):
            depth, j = 0, i
            while j < n:
                if src.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif src.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                    if depth == 0:
                        break
                else:
                    j += 1
            out.append(keep_lines(src[i:j]))
            i = j
            continue
        raw = re.match(r'b?r(#*)"', src[i : i + 12])
        if raw and (i == 0 or not (src[i - 1].isalnum() or src[i - 1] == "_")):
            end = '"' + raw.group(1)
            j = src.find(end, i + len(raw.group(0))) + len(end)
            out.append(keep_lines(src[i:j]))
            i = j
            continue
        if src[i] == '"':
            j = i + 1
            while src[j] != '"':
                j += 2 if src[j] == "\\" else 1
            out.append(keep_lines(src[i : j + 1]))
            i = j + 1
            continue
        if src[i] == "'":
            ch = re.match(r"'(\\u\{[0-9a-fA-F]+\}|\\.|[^\\'])'", src[i : i + 12])
            if ch:
                out.append(" " * len(ch.group(0)))
                i += len(ch.group(0))
                continue
        out.append(src[i])
        i += 1
    return "".join(out)


def block_end(text, open_brace):
    """Index of the brace closing the one at `open_brace`."""
    depth = 0
    for j in range(open_brace, len(text)):
        if text[j] == "{":
            depth += 1
        elif text[j] == "}":
            depth -= 1
            if depth == 0:
                return j
    return len(text) - 1


def line_of(text, index):
    return text.count("\n", 0, index) + 1


def test_spans(text):
    spans = []
    for m in re.finditer(r"#\[cfg\(test\)\]\s*(pub(\([^)]*\))?\s+)?mod\s+\w+\s*\{", text):
        end = block_end(text, m.end() - 1)
        spans.append((line_of(text, m.start()), line_of(text, end)))
    return spans


def is_test_file(path):
    parts = path.split(os.sep)
    return "tests" in parts or "benches" in parts or parts[-1] == "tests.rs"


def first_components(tree):
    """`a::b` -> [a]; `{a::b, c}` -> [a, c]."""
    tree = tree.strip()
    if not tree.startswith("{"):
        return [tree.split("::")[0].strip()]
    items, depth, cur = [], 0, ""
    for ch in tree[1:-1]:
        depth += ch == "{"
        depth -= ch == "}"
        if ch == "," and depth == 0:
            items.append(cur)
            cur = ""
        else:
            cur += ch
    items.append(cur)
    return [x.strip().split("::")[0].strip() for x in items if x.strip()]


def rust_files(root):
    for dirpath, _, names in os.walk(root):
        for name in sorted(names):
            if name.endswith(".rs"):
                yield os.path.join(dirpath, name)


def crate_edges(root):
    """{(from, to): [files]} between top-level modules of the crate at `root`."""
    edges = {}
    for path in rust_files(root):
        top = os.path.relpath(path, root).split(os.sep)[0].removesuffix(".rs")
        if top in ("lib", "main"):
            continue
        text = blank(open(path, encoding="utf-8").read())
        for m in re.finditer(r"\bcrate::(\{[^;]*?\}|[A-Za-z_]\w*)", text):
            for dep in first_components(m.group(1)):
                if dep and dep != top and dep not in ("self", "super", "*"):
                    edges.setdefault((top, dep), []).append(os.path.relpath(path))
    return edges


def cycles(edges):
    """Strongly connected components with more than one module (Tarjan)."""
    graph = {}
    for a, b in edges:
        graph.setdefault(a, set()).add(b)
        graph.setdefault(b, set())
    index, low, stack, on, found, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def layer_problems(root, edges):
    layers = LAYERS.get(root)
    if not layers:
        return []
    rank = {m: i for i, group in enumerate(layers) for m in group}
    problems = []
    for (a, b), files in sorted(edges.items()):
        if a not in rank or b not in rank:
            missing = a if a not in rank else b
            problems.append(f"{root}: module `{missing}` is in no layer of .ci/check-layers.py")
        elif rank[b] > rank[a]:
            problems.append(
                f"{root}: `{a}` (layer {rank[a]}) uses higher layer `{b}` (layer {rank[b]}) "
                f"in {', '.join(sorted(set(files)))}"
            )
    return problems


def size_problems(root):
    problems = []
    for path in rust_files(root):
        rel = os.path.relpath(path)
        if is_test_file(rel):
            continue
        src = open(path, encoding="utf-8").read()
        text = blank(src)
        spans = test_spans(text)
        in_tests = lambda line: any(a <= line <= b for a, b in spans)
        code_lines = src.count("\n") - sum(b - a + 1 for a, b in spans)
        if code_lines > MAX_FILE_LINES:
            problems.append(f"{rel}: {code_lines} lines outside tests (limit {MAX_FILE_LINES})")
        for m in re.finditer(r"\bfn\s+(\w+)[^;{]*\{", text):
            start = line_of(text, m.start())
            if in_tests(start):
                continue
            length = line_of(text, block_end(text, m.end() - 1)) - start + 1
            if length > MAX_FN_LINES:
                problems.append(
                    f"{rel}:{start}: fn {m.group(1)} is {length} lines (limit {MAX_FN_LINES})"
                )
    return problems


def cli_problems():
    problems = []
    for path in rust_files(THIN_CLI):
        rel = os.path.relpath(path)
        text = blank(open(path, encoding="utf-8").read())
        for m in FILE_IO.finditer(text):
            problems.append(
                f"{rel}:{line_of(text, m.start())}: file I/O in the CLI "
                f"(`{m.group(0)}`): move it into the library function the command calls"
            )
    return problems


def main():
    os.chdir(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    problems = []
    for root in CRATES:
        if not os.path.isdir(root):
            continue
        edges = crate_edges(root)
        for comp in cycles(edges):
            detail = "; ".join(
                f"{a} -> {b} ({', '.join(sorted(set(edges[(a, b)]))[:3])})"
                for a in comp
                for b in comp
                if (a, b) in edges
            )
            problems.append(f"{root}: import cycle between {', '.join(comp)}: {detail}")
        problems += layer_problems(root, edges)
        problems += size_problems(root)
    problems += cli_problems()
    for p in problems:
        print(p)
    print(f"check-layers: {len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
