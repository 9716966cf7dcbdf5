#!/usr/bin/env python3
"""Issue 48's size limits: no function over 150 lines and no file over 700 lines in src/, apps/
and python/ (C++ and Python). A function is counted from the first line of its signature to its
closing brace (C++) or its last line (Python, ast). The ones still over are listed below with
their size (none today): the check fails when one of them grows, when a new one goes over, and
when one listed is within the limits (so that the list only shrinks).

Usage: check_sizes.py SOURCE_DIR [--list]   (--list: every function and file over, and exit 0)
"""

import ast
import os
import re
import sys

MAX_FUNCTION_LINES = 150
MAX_FILE_LINES = 700
ROOTS = ("src", "apps", "python")

# Still over the limits, with their size when this list was last shortened (issue 48: none).
KNOWN_FILES = {
}
KNOWN_FUNCTIONS = {
}


def strip_cpp(text):
    """The text with comments, string and character literals blanked (newlines kept), so that
    braces are the code's own."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "R" and text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or
                                                                      text[i - 1] == "_")):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            end = text.find(")" + m.group(1) + '"', i) if m else -1
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == '"' or (c == "'" and not (i > 0 and text[i - 1].isalnum())):
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            out.append(" " * (min(j, n - 1) + 1 - i))
            i = j + 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def cpp_functions(text):
    """(name, first line, line count) of each function body in a C++ file: a brace whose head
    (the code since the last ';', '{' or '}') ends in a parameter list, outside any function;
    namespaces, classes and other scopes are looked into."""
    code = strip_cpp(text)
    stack = []  # per open brace: "scope" or "function" or "block"
    head_start = 0
    found = []
    line_of = [0] * (len(code) + 1)
    line = 1
    for k, ch in enumerate(code):
        line_of[k] = line
        if ch == "\n":
            line += 1
    for k, ch in enumerate(code):
        if ch == "{":
            head = code[head_start:k]
            in_function = "function" in stack
            kind = "block"
            if not in_function:
                words = head.strip()
                if re.match(r"^(template\s*<.*>\s*)?(namespace|class|struct|union|enum|extern)\b",
                            words, re.S) or words == "":
                    kind = "scope"
                elif re.search(r"\)\s*(const|noexcept|override|final|mutable|->[^;{}]*|\s)*$",
                               words) or re.search(r"\)\s*:\s*[\s\S]*$", words):
                    kind = "function"
                    first = head_start + len(head) - len(head.lstrip())
                    name = re.findall(r"([~\w:]+)\s*\(", words)
                    found.append([name[0] if name else "?", line_of[first], None, len(stack)])
                else:
                    kind = "scope" if not re.search(r"[=(]", words) else "block"
            stack.append(kind)
            head_start = k + 1
        elif ch == "}":
            kind = stack.pop() if stack else "scope"
            if kind == "function":
                for f in reversed(found):
                    if f[2] is None and f[3] == len(stack):
                        f[2] = line_of[k] - f[1] + 1
                        break
            head_start = k + 1
        elif ch == ";":
            head_start = k + 1
    return [(name, first, count) for name, first, count, _ in found if count is not None]


def python_functions(text):
    tree = ast.parse(text)
    return [(node.name, node.lineno, node.end_lineno - node.lineno + 1)
            for node in ast.walk(tree)
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))]


def measure(source_dir):
    files, functions = {}, {}
    for root in ROOTS:
        for directory, _, names in os.walk(os.path.join(source_dir, root)):
            for name in sorted(names):
                if not name.endswith((".cpp", ".hpp", ".h", ".py")):
                    continue
                path = os.path.join(directory, name)
                relative = os.path.relpath(path, source_dir)
                text = open(path, encoding="utf-8", errors="replace").read()
                files[relative] = text.count("\n") + (0 if text.endswith("\n") else 1)
                found = python_functions(text) if name.endswith(".py") else cpp_functions(text)
                for function, first, count in found:
                    functions[f"{relative}:{function}:{first}"] = count
    return files, functions


def main():
    if len(sys.argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    files, functions = measure(sys.argv[1])
    long_files = {f: n for f, n in files.items() if n > MAX_FILE_LINES}
    long_functions = {}
    for key, n in functions.items():
        if n > MAX_FUNCTION_LINES:
            path, name, _ = key.rsplit(":", 2)
            long_functions[f"{path}:{name}"] = max(n, long_functions.get(f"{path}:{name}", 0))
    if "--list" in sys.argv:
        for f, n in sorted(long_files.items(), key=lambda x: -x[1]):
            print(f"file {f}: {n} lines")
        for f, n in sorted(long_functions.items(), key=lambda x: -x[1]):
            print(f"function {f}: {n} lines")
        return 0
    problems = []
    for f, n in long_files.items():
        if f not in KNOWN_FILES:
            problems.append(f"{f}: {n} lines, over {MAX_FILE_LINES}: split it by idea")
        elif n > KNOWN_FILES[f]:
            problems.append(f"{f}: {n} lines, grown from {KNOWN_FILES[f]} (limit {MAX_FILE_LINES})")
    for f, n in long_functions.items():
        if f not in KNOWN_FUNCTIONS:
            problems.append(f"{f}: {n} lines, over {MAX_FUNCTION_LINES}: split it by idea")
        elif n > KNOWN_FUNCTIONS[f]:
            problems.append(f"{f}: {n} lines, grown from {KNOWN_FUNCTIONS[f]} "
                            f"(limit {MAX_FUNCTION_LINES})")
    for f in KNOWN_FILES:
        if f not in long_files:
            problems.append(f"{f} is within {MAX_FILE_LINES} lines now: take it off KNOWN_FILES")
    for f in KNOWN_FUNCTIONS:
        if f not in long_functions:
            problems.append(f"{f} is within {MAX_FUNCTION_LINES} lines now: take it off "
                            "KNOWN_FUNCTIONS")
    for p in problems:
        print(f"check_sizes: {p}", file=sys.stderr)
    print(f"{len(files)} files, {len(functions)} functions; {len(long_files)} files and "
          f"{len(long_functions)} functions over the limits"
          + ("" if problems else (", all listed" if long_files or long_functions else "")))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
