"""Generates the Python bindings' docstrings from the `///` comments of the C++ library headers.

Usage: docstrings.py [--root DIR] --out FILE HEADER...   (HEADERs absolute or relative to DIR)

Reads the headers line by line (no libclang): a `///` block documents the declaration after it,
a trailing `///< text` (continued by `///<` lines below) the member on its line. The key is the
namespace after `lasercell` (`core` for `lasercell` itself), the enclosing classes and the name,
joined by `_`; `detail`, `internal` and anonymous namespaces, function bodies and operators are
skipped; different texts of one key (overloads) are joined by a blank line. Writes FILE with
`#define LASERCELL_DOC_<key> R"lcdoc(text)lcdoc"` per key and `LC_DOC(key)`, and FILE.json
(key -> text, for tests), each only when its content changes. Exit 2: a header is unreadable.
"""

import argparse
import json
import os
import pathlib
import re
import sys

IDENT = r"[A-Za-z_]\w*"
HIDDEN_NAMESPACES = {"", "detail", "internal"}
KEYWORDS = set("""alignas auto bool char const constexpr decltype default delete double explicit
    extern final float for if inline int long mutable noexcept nullptr operator override private
    protected public return short signed sizeof static switch unsigned virtual void""".split())


def split_comment(line, in_block):
    """Returns (code, comment, in_block): `line` with its literals emptied and comments removed,
    the text of its `//` comment (or None), and whether a `/* */` comment is still open."""
    code, i, n = [], 0, len(line)
    while i < n:
        if in_block:
            end = line.find("*/", i)
            if end < 0:
                return "".join(code), None, True
            i, in_block = end + 2, False
            code.append(" ")
        elif line.startswith("//", i):
            return "".join(code), line[i:], False
        elif line.startswith("/*", i):
            i, in_block = i + 2, True
        elif line[i] in "\"'" and not (line[i] == "'" and i and line[i - 1].isalnum()):
            quote, i = line[i], i + 1  # a literal (a ' after a digit is a digit separator)
            while i < n and line[i] != quote:
                i += 2 if line[i] == "\\" else 1
            code.append(quote + quote)
            i += 1
        else:
            code.append(line[i])
            i += 1
    return "".join(code), None, in_block


def top_level(text, chars):
    """Indices of `chars` outside (), [], {} and <> in text (`=` only as an assignment)."""
    depth, found = 0, []
    for i, c in enumerate(text):
        if depth == 0 and c in chars:
            if c != "=" or (text[i + 1:i + 2] != "=" and text[i - 1:i] not in "=!<>"):
                found.append(i)
        if c in "([{<":
            depth += 1
        elif c in ")]}>" and not (c == ">" and text[i - 1:i] == "-"):
            depth -= 1
    return found


def strip_prefixes(stmt):
    """Removes attributes and leading `template <...>`, access specifiers and `friend`."""
    s = re.sub(r"\[\[.*?\]\]", " ", stmt).strip()
    while True:  # template arguments nest up to 3 levels deep
        match = re.match(r"(template\s*<(?:[^<>]|<(?:[^<>]|<[^<>]*>)*>)*>|(public|private|"
                         r"protected)\s*:(?!:)|friend\b)\s*", s)
        if not match:
            return s
        s = s[match.end():]


def declaration(stmt):
    """Returns (kind, names) of a declaration: kind is "namespace", "class", "enum", "function",
    "variable" or "other"; names what it declares (empty when nothing worth documenting)."""
    s = strip_prefixes(stmt)
    match = re.match(r"(inline\s+)?namespace\b\s*([\w:]*)", s)
    if match:
        return "namespace", [match.group(2)]
    match = re.match(r"(enum(\s+(class|struct))?|struct|class|union)\s+([\w\s]*?)\s*(:(?!:).*)?$",
                     s, re.S)
    if match:
        names = [w for w in re.findall(IDENT, match.group(4)) if w != "final"]
        return ("enum" if s.startswith("enum") else "class"), names[-1:]
    match = re.match(rf"using\s+({IDENT})\s*=", s)
    if match:
        return "variable", [match.group(1)]
    if re.search(r"\boperator\b|~\s*\w+\s*\(", s) or re.match(r"(using|static_assert)\b", s):
        return "other", []  # operators, destructors, using-declarations
    names, bounds = [], [-1] + top_level(s, ",") + [len(s)]
    for n, (start, end) in enumerate(zip(bounds, bounds[1:])):
        part = s[start + 1:end]
        equals = top_level(part, "=")
        prefix = part[:equals[0]] if equals else part
        paren = top_level(prefix, "(")
        if paren and n == 0:
            match = re.search(rf"({IDENT})\s*$", prefix[:paren[0]])
            return "function", [match.group(1)] if match and match[1] not in KEYWORDS else []
        prefix = re.sub(r"\[[^\]]*\]|:\s*\d+\s*$", " ", prefix)  # array sizes, bit-fields
        idents = re.findall(IDENT, prefix)
        names += idents[-1:] if idents and idents[-1] not in KEYWORDS else []
    return "variable", names


def scope(kind, names):
    """The scope a `{` opens after a declaration: a namespace, class or enum, or one to skip (a
    function body, an initializer, a namespace whose contents are not public)."""
    parts = names[0].split("::") if kind == "namespace" else []
    if kind == "namespace" and not HIDDEN_NAMESPACES.intersection(parts):
        return "namespace", parts
    return (kind, names) if kind in ("class", "enum") and names else ("skip", [])


def doc_text(lines):
    """Joins comment lines: a line break is a space, an empty line a paragraph break."""
    paragraphs = re.split(r"\n{2,}", "\n".join(line.strip() for line in lines).strip("\n"))
    return "\n\n".join(p.replace("\n", " ") for p in paragraphs if p)


def comment_body(comment):
    """The text after `///` or `///<` and one following space."""
    return re.sub(r"^\s*///<? ?", "", comment)


class Parser:
    """Reads one header line by line, keeping the scope stack and the statement being read."""

    def __init__(self, path, docs, warnings):
        self.path, self.docs, self.warnings = path, docs, warnings
        self.scopes = []  # (kind, names): kind is namespace, class, enum or skip
        self.stmt, self.parens = "", 0
        self.pending, self.pending_depth = None, 0  # a `///` block waiting for its declaration
        self.trailing = ([], [])  # keys and lines of the last `///<` text, until a line without
        self.directive = False  # the previous line continues a preprocessor directive

    def key(self, name):
        """The key of `name` in the current scope, or None when it is not documented here."""
        namespaces, classes = [], []
        for kind, names in self.scopes:
            if kind == "skip":
                return None
            (namespaces if kind == "namespace" else classes).extend(names)
        if namespaces[:1] != ["lasercell"] or not name:
            return None
        return "_".join((namespaces[1:] or ["core"]) + classes + [name])

    def record(self, keys, lines):
        text = doc_text(lines)
        for key in keys:
            if text and text not in self.docs.setdefault(key, []):
                self.docs[key].append(text)

    def complete(self, lineno):
        """Ends the statement at a boundary; returns (kind, names, keys) or None when empty."""
        stmt, self.stmt, self.parens = self.stmt.strip(), "", 0
        if not stmt:
            return None
        kind, names = declaration(stmt)
        keys = [k for k in map(self.key, names) if k] if kind != "namespace" else []
        if self.pending is not None and len(self.scopes) == self.pending_depth:
            if not keys and kind not in ("namespace", "other") and self.key("x"):
                self.warnings.append(f"{self.path}:{lineno}: no name for documented `{stmt}`")
            self.record(keys, self.pending)
            self.pending = None
        return kind, names, keys

    def close_scope(self):
        self.scopes = self.scopes[:-1]
        if self.pending is not None and self.pending_depth > len(self.scopes):
            self.pending = None

    def code(self, code, lineno):
        """Reads the code of one line; returns the declarations it ends at its starting depth."""
        depth, done_here = len(self.scopes), []
        for c in code:
            in_enum = self.scopes and self.scopes[-1][0] == "enum"
            if self.parens == 0 and (c in "{};" or (c == "," and in_enum)):
                done = self.complete(lineno)
                if done and len(self.scopes) == depth:
                    done_here.append(done)
                if c == "{":
                    self.scopes.append(scope(*(done or ("other", []))[:2]))
                elif c == "}":
                    self.close_scope()
                continue
            if c == "{":  # inside parentheses: a default argument or a lambda
                self.scopes.append(("skip", []))
            elif c == "}":
                self.close_scope()
            self.parens += (c in "([") - (c in ")]")
            self.stmt += c
        return done_here

    def line(self, text, lineno, in_block):
        """Reads one line; returns whether a `/* */` comment is still open after it."""
        stripped = text.strip()
        if not in_block and stripped.startswith("///<"):
            self.trailing[1].append(comment_body(stripped))
            return False
        self.record(*self.trailing)
        self.trailing = ([], [])
        if not in_block and stripped.startswith("///") and not stripped.startswith("////"):
            if self.pending is None:
                self.pending, self.pending_depth = [], len(self.scopes)
            self.pending.append(comment_body(stripped))
            return False
        if self.directive or (not in_block and stripped.startswith("#")):
            self.pending = None  # a macro's documentation, or a conditional we do not follow
            self.directive = stripped.endswith("\\")
            return False
        code, comment, in_block = split_comment(text, in_block)
        done_here = self.code(code, lineno)
        if comment and comment.startswith("///<"):
            done = done_here[0] if done_here else None
            if not done and self.stmt.strip():  # a last enumerator without a comma
                kind, names = declaration(self.stmt)
                done = (kind, names, [k for k in map(self.key, names) if k])
            if done and done[2]:
                self.trailing = (done[2], [comment_body(comment)])
            elif self.key("x"):
                self.warnings.append(f"{self.path}:{lineno}: no member for `{comment.strip()}`")
        return in_block


def extract(headers):
    """Returns ({key: text}, warnings) for the [(path, text)] of the headers, in order."""
    docs, warnings = {}, []
    for path, text in headers:
        parser, in_block = Parser(path, docs, warnings), False
        for lineno, line in enumerate(text.splitlines(), 1):
            in_block = parser.line(line, lineno, in_block)
        parser.record(*parser.trailing)
    return {key: "\n\n".join(texts) for key, texts in sorted(docs.items())}, warnings


def render(docs):
    """The generated header: one `#define LASERCELL_DOC_<key> R"lcdoc(text)lcdoc"` per key."""
    lines = ["#pragma once",
             "// Generated by python/docstrings.py from the `///` comments of the library headers;",
             "// do not edit. A binding writes LC_DOC(key), e.g. LC_DOC(localize_LocalizeParts).",
             "", "#define LC_DOC(key) LASERCELL_DOC_##key", ""]
    for key, text in docs.items():
        if ')lcdoc"' in text:  # exit status 1
            raise SystemExit(f'docstrings.py: the text of {key} contains )lcdoc", which ends it')
        pieces = [f'R"lcdoc({p})lcdoc"' for p in text.split("\n\n")]  # one line per macro
        lines.append(f"#define LASERCELL_DOC_{key} " + ' "\\n\\n" '.join(pieces))
    return "\n".join(lines) + "\n"


def write_if_changed(path, content):
    """Replaces path by content atomically (temporary file and rename) unless already equal."""
    if os.path.isfile(path) and pathlib.Path(path).read_text("utf-8", "replace") == content:
        return
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    temp = f"{path}.{os.getpid()}.tmp"  # beside it: same file system, so the rename is atomic
    try:
        with open(temp, "w", encoding="utf-8") as f:
            f.write(content)
        os.replace(temp, path)
    finally:
        if os.path.exists(temp):
            os.unlink(temp)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", required=True, help="the header to write (and OUT.json)")
    parser.add_argument("--root", default=".", help="the directory HEADERs are relative to")
    parser.add_argument("headers", nargs="+", metavar="HEADER")
    args = parser.parse_args(argv)
    headers = []
    for header in args.headers:
        path = os.path.join(args.root, header)
        try:
            text = pathlib.Path(path).read_text("utf-8")
        except (OSError, UnicodeDecodeError) as error:
            print(f"docstrings.py: cannot read header {header}: {error}", file=sys.stderr)
            return 2
        headers.append((os.path.relpath(path, args.root), text))
    docs, warnings = extract(sorted(headers))
    for warning in warnings:
        print(f"docstrings.py: warning: {warning}", file=sys.stderr)
    write_if_changed(args.out, render(docs))
    write_if_changed(args.out + ".json", json.dumps(docs, indent=1, ensure_ascii=False) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
