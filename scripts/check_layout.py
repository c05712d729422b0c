#!/usr/bin/env python3
"""Layout check for the workspace's Rust sources (Python 3 standard library only).

Scans `crates/*/src/**/*.rs` and reports, one line per violation as `path:line: message`:

  (a) files longer than --max-file-lines (default 600) lines, test modules included;
  (b) functions longer than --max-fn-lines (default 120) lines, counted from the line of the
      `fn` keyword to the line of the body's closing brace;
  (c) import cycles between the top-level modules of each crate target: an edge `X -> Y` for
      every path `crate::Y` (also inside `use crate::{..}` groups) or `super::..` that resolves
      to `Y`, written in a file of module `X`; each strongly connected component of more than
      one module is reported, with one place for each of its edges.

Comments, string and character literals are blanked before anything is parsed, so braces and
`fn` inside them do not count. Exits 1 if there is any violation, 0 otherwise.

Usage: scripts/check_layout.py [--root DIR] [--max-file-lines N] [--max-fn-lines N] [CRATE ...]
where CRATE names directories under crates/ to check (default: all of them).
"""

import argparse
import re
import sys
from pathlib import Path

IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def blank(text):
    """`text` with comments and the contents of string/char literals replaced by spaces
    (newlines kept, so offsets and line numbers stay valid). Quotes stay, as `""`."""
    out = list(text)
    n = len(text)
    i = 0

    def wipe(a, b):
        for k in range(a, b):
            if out[k] != "\n":
                out[k] = " "

    while i < n:
        c = text[i]
        prev = text[i - 1] if i > 0 else ""
        if c == "/" and text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            wipe(i, j)
            i = j
        elif c == "/" and text.startswith("/*", i):
            # Block comments nest in Rust.
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            wipe(i, j)
            i = j
        elif c in "rbc" and not (prev.isalnum() or prev == "_"):
            # Raw strings r"..", r#".."#, br"..", cr"..", and prefixed b"..", c"..", b'..'.
            m = re.compile(r'(?:b|c)?r(#*)"').match(text, i)
            if m:
                close = '"' + m.group(1)
                j = text.find(close, m.end())
                j = n if j < 0 else j + len(close)
                wipe(m.end(), j - len(close))
                i = j
            elif c in "bc" and i + 1 < n and text[i + 1] in "\"'":
                i += 1  # the literal itself is handled on the next iteration
            else:
                i += 1
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            wipe(i + 1, min(j, n))
            i = j + 1
        elif c == "'":
            # A char literal ('x', '\n', '\u{..}', '\'') or a lifetime / label ('a, 'static).
            if i + 1 < n and text[i + 1] == "\\":
                # The escaped character may itself be a quote: `'\''`.
                j = i + 3
                while j < n and text[j] != "'":
                    j += 1
                wipe(i + 1, min(j, n))
                i = j + 1
            elif i + 2 < n and text[i + 2] == "'":
                wipe(i + 1, i + 2)
                i += 3
            else:
                i += 1
        else:
            i += 1
    return "".join(out)


def line_of(starts, offset):
    """1-based line number of `offset`, given the offsets where lines start."""
    lo, hi = 0, len(starts)
    while lo + 1 < hi:
        mid = (lo + hi) // 2
        if starts[mid] <= offset:
            lo = mid
        else:
            hi = mid
    return lo + 1


def functions(code):
    """`(name, start offset, end offset)` of every `fn` item with a body in blanked `code`."""
    found = []
    for m in re.finditer(r"\bfn\s+(?:r#)?([A-Za-z_][A-Za-z0-9_]*)", code):
        # The body starts at the first `{` outside parentheses and brackets (`[u8; 4]` holds a
        # `;`); a `;` there first means a declaration without a body.
        depth, j = 0, m.end()
        while j < len(code):
            ch = code[j]
            if ch in "([":
                depth += 1
            elif ch in ")]":
                depth -= 1
            elif depth == 0 and ch in "{;":
                break
            j += 1
        if j >= len(code) or code[j] == ";":
            continue
        braces, k = 0, j
        while k < len(code):
            if code[k] == "{":
                braces += 1
            elif code[k] == "}":
                braces -= 1
                if braces == 0:
                    break
            k += 1
        found.append((m.group(1), m.start(), k))
    return found


def module_path(src, path):
    """The module path of file `path` under `src` (`[]` for a crate root)."""
    parts = list(path.relative_to(src).with_suffix("").parts)
    if parts and parts[-1] == "mod":
        parts.pop()
    if len(parts) == 1 and parts[0] in ("lib", "main"):
        return []
    if parts and parts[0] == "bin":
        return []
    return parts


def root_modules(code):
    """Names of the file modules (`mod x;`) a crate root declares."""
    return set(re.findall(r"\bmod\s+([A-Za-z_][A-Za-z0-9_]*)\s*;", code))


def references(code, modpath):
    """`(top-level module, offset)` of each path in blanked `code` (a file of module `modpath`)
    that resolves to a top-level module of the crate: `crate::x`, `crate::{x, ..}`, `super::..`."""
    refs = []
    for m in re.finditer(r"(?<![A-Za-z0-9_:$])crate\s*::\s*(\{)?", code):
        if m.group(1):
            # A group: the names at its first nesting level.
            depth, j, start = 1, m.end(), m.end()
            names = []
            while j < len(code) and depth:
                ch = code[j]
                if ch == "{":
                    if depth == 1:
                        names.append((code[start:j], start))
                    depth += 1
                elif ch == "}":
                    depth -= 1
                    if depth == 0:
                        names.append((code[start:j], start))
                elif ch == "," and depth == 1:
                    names.append((code[start:j], start))
                    start = j + 1
                j += 1
            for seg, off in names:
                first = IDENT.search(seg)
                if first and first.group(0) != "self":
                    refs.append((first.group(0), off + first.start()))
        else:
            first = IDENT.match(code, m.end())
            if first:
                refs.append((first.group(0), m.start()))
    for m in re.finditer(r"(?<![A-Za-z0-9_:])((?:super\s*::\s*)+)([A-Za-z_][A-Za-z0-9_]*)?", code):
        ups = m.group(1).count("super")
        base = modpath[: len(modpath) - ups] if ups <= len(modpath) else None
        if base is None:
            continue
        if base:
            refs.append((base[0], m.start()))
        elif m.group(2):
            refs.append((m.group(2), m.start()))
    return refs


def strongly_connected(graph):
    """Tarjan's strongly connected components of `graph` (node -> set of nodes)."""
    index, low, on, stack, out = {}, {}, set(), [], []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
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
            out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def check_crate(crate, root, max_file, max_fn):
    """The violations in one crate directory, as `(path, line, message)`."""
    src = crate / "src"
    found = []
    files = sorted(src.rglob("*.rs"))
    blanked = {}
    for path in files:
        text = path.read_text(encoding="utf-8")
        rel = path.relative_to(root)
        lines = text.count("\n") + (0 if text.endswith("\n") or not text else 1)
        if lines > max_file:
            found.append((rel, 1, f"file has {lines} lines (limit {max_file})"))
        code = blank(text)
        blanked[path] = code
        starts = [0] + [k + 1 for k, ch in enumerate(text) if ch == "\n"]
        for name, a, b in functions(code):
            la, lb = line_of(starts, a), line_of(starts, b)
            if lb - la + 1 > max_fn:
                found.append((rel, la, f"fn {name} has {lb - la + 1} lines (limit {max_fn})"))
    # Import cycles, per target: the library and the binary have their own module trees.
    for target in ("lib.rs", "main.rs"):
        root_file = src / target
        if not root_file.exists():
            continue
        tops = root_modules(blanked[root_file])
        graph, where = {t: set() for t in tops}, {}
        for path in files:
            modpath = module_path(src, path)
            if not modpath or modpath[0] not in tops:
                continue
            here = modpath[0]
            text_starts = None
            for other, off in references(blanked[path], modpath):
                if other == here or other not in tops:
                    continue
                graph[here].add(other)
                if (here, other) not in where:
                    if text_starts is None:
                        text = path.read_text(encoding="utf-8")
                        text_starts = [0] + [k + 1 for k, ch in enumerate(text) if ch == "\n"]
                    where[(here, other)] = (path.relative_to(root), line_of(text_starts, off))
        for comp in strongly_connected(graph):
            if len(comp) < 2:
                continue
            members = set(comp)
            edges = sorted((a, b) for a in comp for b in graph[a] if b in members)
            first = where[edges[0]]
            found.append((first[0], first[1], f"import cycle in {crate.name} ({target}): {', '.join(comp)}"))
            for a, b in edges:
                p, ln = where[(a, b)]
                found.append((p, ln, f"  {a} -> {b}"))
    return found


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--root", type=Path, default=Path(__file__).resolve().parent.parent)
    ap.add_argument("--max-file-lines", type=int, default=600)
    ap.add_argument("--max-fn-lines", type=int, default=120)
    ap.add_argument("crates", nargs="*", help="crate directories under crates/ (default: all)")
    args = ap.parse_args()
    root = args.root.resolve()
    names = args.crates or sorted(p.name for p in (root / "crates").iterdir() if (p / "src").is_dir())
    total = 0
    for name in names:
        crate = root / "crates" / name
        if not (crate / "src").is_dir():
            print(f"{crate}: no src directory", file=sys.stderr)
            return 2
        for path, line, msg in check_crate(crate, root, args.max_file_lines, args.max_fn_lines):
            print(f"{path}:{line}: {msg}")
            if not msg.startswith("  "):
                total += 1
    print(f"{total} layout violation(s)" if total else "layout ok", file=sys.stderr)
    return 1 if total else 0


if __name__ == "__main__":
    sys.exit(main())
