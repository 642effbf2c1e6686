#!/usr/bin/env bash
# Every promise the code's doc comments and docs/design.md's tables make is named by a test. The
# unit is a documented declaration: a class, function, constant, enumerator or member with a ///
# or ///< comment in a header under include/ or src/ (outside the private sections of classes),
# and each identifier in backquotes in a row of a table of docs/design.md. A test names it when
# the name occurs in a file under test/core, test/messages, test/bag, test/ros or test/fuzz. The
# ones no test names yet are listed, with the reason they are covered otherwise, in
# test/checks/doc_promises_known.txt; the check fails for a documented name neither named nor
# listed (a new promise without its test), and for a listed one a test now names or that is no
# longer documented (the list only shrinks). Reads the files only.
source "$(dirname "${BASH_SOURCE[0]}")/../../scripts/common.sh"
cd "$REPO_DIR" || exit 1
/usr/bin/python3 - <<'PY'
import pathlib
import re
import sys

KNOWN = pathlib.Path("test/checks/doc_promises_known.txt")
TEST_DIRS = ("test/core", "test/messages", "test/bag", "test/ros", "test/fuzz")
KEYWORDS = {"operator", "explicit", "virtual", "static", "inline", "const", "constexpr",
            "return", "if", "for", "while", "switch", "sizeof", "decltype", "noexcept"}
DECLARATIONS = [
    re.compile(r"^\s*(?:struct|class|enum class|enum|union)\s+(\w+)"),
    re.compile(r"^\s*using\s+(\w+)\s*="),
    re.compile(r"(\w+)\s*\("),                                  # a function
    re.compile(r"(\w+)\s*(?:=[^=].*)?[;{,]\s*(?://.*)?$"),      # a variable or an enumerator
]


def declared_name(line):
    for pattern in DECLARATIONS:
        m = pattern.search(line)
        if m and m.group(1) not in KEYWORDS:
            return m.group(1)
    return None


def private_lines(lines):
    """For each line, whether it lies in a private section of a class (by brace depth)."""
    private, scopes = [], []  # per open brace: None, or the access of a class body
    for line in lines:
        code = re.sub(r"//.*", "", line)
        label = re.match(r"\s*(public|private|protected)\s*:", code)
        if label and scopes and scopes[-1] is not None:
            scopes[-1] = label.group(1)
        private.append("private" in scopes)
        head = code.split("{")[0]
        for ch in code:
            if ch == "{":
                is_class = re.search(r"\b(class|struct)\b[^;(]*$", head) and "enum" not in head
                scopes.append(("private" if re.search(r"\bclass\b", head) else "public")
                              if is_class else None)
            elif ch == "}" and scopes:
                scopes.pop()
    return private


def documented_in_headers():
    found = []
    headers = sorted(pathlib.Path("include").rglob("*.h")) + sorted(pathlib.Path("src").rglob("*.h"))
    for header in headers:
        lines = header.read_text().splitlines()
        private = private_lines(lines)
        i = 0
        while i < len(lines):
            text = lines[i].strip()
            if text.startswith("///") and not text.startswith("///<"):
                j = i
                while j < len(lines) and lines[j].strip().startswith("///"):
                    j += 1
                while j < len(lines) and lines[j].strip().startswith(("template", "[[")):
                    j += 1
                if j < len(lines) and not private[j]:
                    name = declared_name(lines[j])
                    if name:
                        found.append((f"{header}:{j + 1}", name))
                i = max(j, i + 1)
                continue
            trailing = re.search(r"^(.*?)///<", lines[i])
            if trailing and not private[i]:
                name = declared_name(trailing.group(1).rstrip())
                if name:
                    found.append((f"{header}:{i + 1}", name))
            i += 1
    return found


def named_in_design_tables():
    found = []
    for number, line in enumerate(open("docs/design.md", encoding="utf-8"), 1):
        if not line.startswith("|") or re.fullmatch(r"[|\-: ]+", line.strip()):
            continue
        for quoted in re.findall(r"`([^`]+)`", line):
            if "/" in quoted or "." in quoted:
                continue  # a path or a file: docs_paths.sh checks those
            for name in re.findall(r"(?<![\w])[A-Za-z]\w{2,}", quoted):
                found.append((f"docs/design.md:{number}", name))
    return found


words = set()
for folder in TEST_DIRS:
    for path in pathlib.Path(folder).rglob("*"):
        if path.is_file():
            words.update(re.findall(r"[A-Za-z_]\w*", path.read_text(errors="ignore")))

known = {}
for number, line in enumerate(KNOWN.read_text().splitlines(), 1):
    line = line.split("#")[0].strip()
    if line:
        where, _, name = line.rpartition(" ")
        known[(where, name)] = number

promises = documented_in_headers() + named_in_design_tables()
status = 0
listed = set()
for where, name in promises:
    source = where.rsplit(":", 1)[0]
    if name in words:
        if (source, name) in known:
            print(f"{KNOWN}:{known[(source, name)]}: {name} ({source}) is named by a test now: "
                  "take it off the list")
            status = 1
        continue
    listed.add((source, name))
    if (source, name) not in known:
        print(f"{where}: {name} is documented and no test names it: test what its comment "
              f"promises, or list it in {KNOWN} with the reason it is covered otherwise")
        status = 1
for (source, name), number in sorted(known.items(), key=lambda item: item[1]):
    if (source, name) not in listed and not any(
            s.rsplit(":", 1)[0] == source and n == name for s, n in promises):
        print(f"{KNOWN}:{number}: {name} is no longer documented in {source}: take it off the list")
        status = 1
untested = len({(w.rsplit(':', 1)[0], n) for w, n in promises if n not in words})
print(f"doc promises: {len(promises)} documented names, {untested} named by no test "
      f"(listed in {KNOWN})")
sys.exit(status)
PY
